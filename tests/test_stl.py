import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bushenv import stl

signals = st.lists(st.floats(-10, 10), min_size=1, max_size=30).map(np.array)


def _brute_window(r, a, b, reduce, pad):
    T = r.size
    out = np.empty(T)
    for t in range(T):
        hi = T - 1 if b is None else t + b
        vals = [r[k] if k < T else pad for k in range(t + a, hi + 1)]
        if b is None and t + a > T - 1:
            vals = [pad]
        elif b is None and a > 0:
            vals = vals + [pad]
        out[t] = min(vals) if reduce == "min" else max(vals)
    return out


@settings(max_examples=60, deadline=None)
@given(r=signals, a=st.integers(0, 5), w=st.integers(0, 6))
def test_bounded_always_and_eventually_match_their_definition(r, a, w):
    b = a + w
    assert np.array_equal(stl.always(r, a, b)[:, 0], _brute_window(r, a, b, "min", np.inf))
    assert np.array_equal(stl.eventually(r, a, b)[:, 0], _brute_window(r, a, b, "max", -np.inf))


@settings(max_examples=40, deadline=None)
@given(r=signals)
def test_unbounded_always_is_the_suffix_minimum(r):
    got = stl.always(r)[:, 0]
    want = np.array([r[t:].min() for t in range(r.size)])
    assert np.array_equal(got, want)


@settings(max_examples=40, deadline=None)
@given(p=signals, data=st.data(), a=st.integers(0, 3), w=st.integers(0, 4))
def test_until_matches_its_definition(p, data, a, w):
    q = np.array(data.draw(st.lists(st.floats(-10, 10), min_size=p.size, max_size=p.size)))
    b = a + w
    got = stl.until(p, q, a, b)[:, 0]
    T = p.size
    for t in range(T):
        best = -np.inf
        for k in range(t + a, t + b + 1):
            qk = q[k] if k < T else -np.inf
            pmin = min(p[j] if j < T else -np.inf for j in range(t, k + 1))
            best = max(best, min(qk, pmin))
        assert got[t] == best


def test_boolean_and_implication_compose_with_real_robustness():
    inside = np.array([False, True, True, False])
    r = np.array([-5.0, 2.0, -1.0, -7.0])
    got = stl.at_start(stl.always(stl.implies(stl.boolean(inside), r)))
    assert got[0] == -1.0  # only the samples inside count


def test_batched_columns_are_independent():
    rng = np.random.default_rng(0)
    r = rng.normal(size=(50, 4))
    batched = stl.always(stl.eventually(r, 0, 7, pad=np.inf))
    for b in range(4):
        alone = stl.always(stl.eventually(r[:, b], 0, 7, pad=np.inf))[:, 0]
        assert np.array_equal(batched[:, b], alone)


def test_bad_windows_are_refused():
    with pytest.raises(stl.STLError, match="window"):
        stl.always(np.zeros(5), 3, 1)
    with pytest.raises(stl.STLError, match="shape"):
        stl.until(np.zeros(5), np.zeros(6))
