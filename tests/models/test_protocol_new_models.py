"""The model protocol (base.py) for nn, hybrid and boucwen: reset, batching, files."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bushenv.models import ModelError, get_model, load_model
from bushenv.models.boucwen import BoucWenBushing
from bushenv.models.hybrid import HybridBushing
from bushenv.models.narx import NarxBushing


def make_nn(hidden=(9,)):
    return NarxBushing.initialised((-0.002, 0.002), (-900.0, 1100.0), hidden=hidden, seed=3)


def make_hybrid():
    return HybridBushing.initialised(
        (-0.002, 0.002), (-200.0, 200.0), seed=4, k_n_per_m=3.0e5, c_ns_per_m=900.0
    )


FACTORIES = {
    "nn": make_nn,
    "nn_10_9": lambda: make_nn((10, 9)),
    "hybrid": make_hybrid,
    "boucwen": BoucWenBushing.preset,
}


def drive(T, B, seed):
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.normal(size=(T, B)), axis=0) * 2e-4
    x -= x.mean(axis=0)
    return x, np.gradient(x, 1 / 204.8, axis=0)


@pytest.mark.parametrize("kind", sorted(FACTORIES))
def test_reset_makes_reruns_identical(kind):
    m = FACTORIES[kind]()
    x, v = drive(300, 1, 0)
    first = m.simulate(x[:, 0], v[:, 0])
    again = m.simulate(x[:, 0], v[:, 0])
    m.reset()
    stepped = np.array([m.step(x[t, 0], v[t, 0]) for t in range(300)])
    assert np.array_equal(first, again)
    assert np.array_equal(first, stepped)
    assert np.all(np.isfinite(first)) and np.max(np.abs(first)) > 0


@pytest.mark.parametrize("kind", sorted(FACTORIES))
def test_batched_equals_looped_bit_for_bit(kind):
    m = FACTORIES[kind]()
    x, v = drive(200, 4, 1)
    batched = m.simulate(x, v)
    m.reset(4)
    looped = np.array([m.step(x[t], v[t]) for t in range(200)])
    singles = np.stack([m.simulate(x[:, b], v[:, b]) for b in range(4)], axis=1)
    assert np.array_equal(batched, looped)
    assert np.array_equal(batched, singles)


@settings(max_examples=20, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    batch=st.integers(1, 5),
    kind=st.sampled_from(sorted(FACTORIES)),
)
def test_any_batch_equals_its_columns_run_alone(seed, batch, kind):
    m = FACTORIES[kind]()
    x, v = drive(40, batch, seed)
    batched = m.simulate(x, v)
    for b in range(batch):
        assert np.array_equal(batched[:, b], m.simulate(x[:, b], v[:, b]))


@pytest.mark.parametrize("kind", sorted(FACTORIES))
def test_save_load_round_trip_gives_same_forces(kind, tmp_path):
    m = FACTORIES[kind]()
    x, v = drive(150, 2, 2)
    path = m.save(tmp_path / f"{kind}.npz")
    m2 = load_model(path)
    assert type(m2) is type(m)
    assert np.array_equal(m.simulate(x, v), m2.simulate(x, v))
    assert get_model(str(path)).name == m.name


@pytest.mark.parametrize("kind", ["nn", "hybrid"])
def test_load_refuses_inconsistent_network_shapes_naming_the_file(kind, tmp_path):
    path = FACTORIES[kind]().save(tmp_path / "net.npz")
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays.pop("__meta__")))
    arrays["w1"] = arrays["w1"][:, :-1]  # one input short
    meta["shapes"]["w1"] = list(arrays["w1"].shape)
    np.savez(tmp_path / "short.npz", __meta__=np.array(json.dumps(meta)), **arrays)
    with pytest.raises(ModelError, match=r"short\.npz.*'w1'.*shape"):
        load_model(tmp_path / "short.npz")


@pytest.mark.parametrize("kind", ["nn", "boucwen"])
def test_load_refuses_shape_disagreeing_with_header(kind, tmp_path):
    path = FACTORIES[kind]().save(tmp_path / "m.npz")
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    key = "b1" if kind == "nn" else "k0"
    arrays[key] = np.zeros(3)
    np.savez(tmp_path / "bad.npz", **arrays)
    with pytest.raises(ModelError, match=rf"bad\.npz: parameter '{key}' has shape \[3\]"):
        load_model(tmp_path / "bad.npz")


def test_boucwen_refuses_zero_c1_and_zero_c0_plus_c2():
    p = BoucWenBushing.preset().params
    with pytest.raises(ModelError, match="c1 = 0"):
        BoucWenBushing(**{**p, "c1": 0.0})
    with pytest.raises(ModelError, match=r"c0 \+ c2 = 0"):
        BoucWenBushing(**{**p, "c0": 1.0, "c2": -1.0})
