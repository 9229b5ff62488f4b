import pytest

from bushenv.execution import BackendError, LocalBackend, get_backend


def _square_with_seed(item):
    import numpy as np

    seed, n = item
    return float(np.random.default_rng(seed).normal(size=n).sum())


def test_local_backend_map_keeps_item_order_in_process_and_in_pool():
    items = [(s, 100) for s in range(6)]
    with LocalBackend(workers=1) as one:
        serial = one.map(_square_with_seed, items)
    with LocalBackend(workers=2) as two:
        pooled = two.map(_square_with_seed, items)
    assert serial == pooled
    assert len(set(serial)) == 6


def test_imap_unordered_yields_every_index_once():
    with LocalBackend(workers=2) as two:
        got = dict(two.imap_unordered(_square_with_seed, [(s, 10) for s in range(5)]))
    assert sorted(got) == [0, 1, 2, 3, 4]


def test_bad_backend_arguments_are_clear_errors():
    with pytest.raises(BackendError, match="workers must be >= 1"):
        LocalBackend(workers=0)
    with pytest.raises(BackendError, match="unknown backend 'spark'"):
        get_backend("spark")
