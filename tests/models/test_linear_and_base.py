import json

import numpy as np
import pytest

from bushenv.models import ModelError, get_model, load_model
from bushenv.models.linear import LinearBushing


def test_linear_preset_is_table1_in_si():
    m = get_model("linear", axis="radial")
    assert m.k_n_per_m == pytest.approx(1518.73e3)
    assert m.c_ns_per_m == pytest.approx(15.0e3)
    assert m.step(0.001, 0.01) == pytest.approx(1518.73 + 150.0)


def test_linear_batched_equals_looped_bit_for_bit():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(50, 3)) * 1e-3
    v = rng.normal(size=(50, 3)) * 1e-2
    m = LinearBushing.preset("axial")
    batched = m.simulate(x, v)
    m.reset(3)
    looped = np.array([m.step(x[t], v[t]) for t in range(50)])
    assert np.array_equal(batched, looped)


def test_save_load_round_trip(tmp_path):
    m = LinearBushing(k_n_per_m=1.0e5, c_ns_per_m=2.0e3, dt=1 / 512)
    path = m.save(tmp_path / "lin.npz")
    m2 = load_model(path)
    assert (m2.k_n_per_m, m2.c_ns_per_m, m2.dt) == (1.0e5, 2.0e3, 1 / 512)


def test_load_refuses_wrong_dt_version_and_junk(tmp_path):
    m = LinearBushing(k_n_per_m=1.0e5, c_ns_per_m=2.0e3)
    path = m.save(tmp_path / "lin.npz")
    with pytest.raises(ModelError, match=r"lin\.npz.*Hz"):
        load_model(path, dt=1 / 1024)
    junk = tmp_path / "junk.npz"
    junk.write_text("not a zip")
    with pytest.raises(ModelError, match="junk.npz: not a bushenv model file"):
        load_model(junk)
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays.pop("__meta__")))
    meta["version"] = 99
    np.savez(tmp_path / "v99.npz", __meta__=np.array(json.dumps(meta)), **arrays)
    with pytest.raises(ModelError, match="v99.npz: model file format version 99"):
        load_model(tmp_path / "v99.npz")


def test_unknown_model_name_is_a_clear_error():
    with pytest.raises(ModelError, match="unknown model 'nope'"):
        get_model("nope")
