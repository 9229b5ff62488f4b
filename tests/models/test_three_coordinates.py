"""The planar protocol: shapes, step = simulate, files, registry errors (on the linear model)."""

import numpy as np
import pytest

from bushenv.errors import BadInput
from bushenv.models import MODELS, load_model
from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_linear import PlanarLinear, fit_linear

K = np.array([[380e3, 1e3, 0.0], [2e3, 1500e3, 5e3], [0.0, 40.0, 1500.0]])
C = np.diag([4.4e3, 15e3, 15.0])


def _q(T=50, B=None, seed=0):
    rng = np.random.default_rng(seed)
    shape = (T, 3) if B is None else (T, B, 3)
    return rng.standard_normal(shape) * np.array([1e-3, 1e-3, 0.02])


def test_linear_simulate_matches_k_q_plus_c_v_and_shapes():
    m = PlanarLinear(K, C)
    q = _q(40)
    v = np.gradient(q, m.dt, axis=0)
    f = m.simulate(q)
    assert f.shape == (40, 3)
    np.testing.assert_allclose(f, q @ K.T + v @ C.T, rtol=1e-12)
    fb = m.simulate(_q(40, B=4))
    assert fb.shape == (40, 4, 3)


def test_step_loop_equals_batched_simulate_bit_for_bit():
    m = PlanarLinear(K, C)
    q = _q(30, B=3)
    v = np.gradient(q, m.dt, axis=0)
    f = m.simulate(q, v)
    m.reset(3)
    looped = np.stack([m.step(q[t], v[t]) for t in range(30)])
    np.testing.assert_array_equal(looped, f)


def test_step_rejects_wrong_shapes_naming_the_order():
    m = PlanarLinear(K, C)
    with pytest.raises(PlanarModelError, match="axial, radial, rotation"):
        m.step(np.zeros(2), np.zeros(2))
    with pytest.raises(PlanarModelError, match=r"\(T, 3\)"):
        m.simulate(np.zeros((10, 2)))


def test_save_load_roundtrip_and_copy(tmp_path):
    m = PlanarLinear(K, C)
    back = load_model(m.save(tmp_path / "lin.npz"))
    assert isinstance(back, PlanarLinear)
    np.testing.assert_array_equal(back.k_matrix, K)
    q = _q(20)
    np.testing.assert_array_equal(back.simulate(q), m.simulate(q))
    np.testing.assert_array_equal(m.copy().simulate(q), m.simulate(q))


def test_one_file_format_loads_either_and_refuses_the_other_count_naming_what_takes_it(tmp_path):
    from bushenv.models import ModelError, get_model
    from bushenv.models.linear import LinearBushing

    one = LinearBushing.preset("axial").save(tmp_path / "one.npz")
    three = PlanarLinear(K, C).save(tmp_path / "three.npz")
    assert load_model(one).n_coords == 1 and load_model(three).n_coords == 3
    with pytest.raises(ModelError, match="one.npz is a one-axis model; the rig3 needs a three"):
        load_model(one, coords=3, wanted_by="the rig3")
    with pytest.raises(ModelError, match=r"three.npz is a three-axis model.*attack --env rig3"):
        get_model(str(three), wanted_by="bushenv export")


def test_a_three_axis_file_of_the_former_format_still_loads(tmp_path):
    import json

    m = PlanarLinear(K, C)
    path = m.save(tmp_path / "new.npz")
    with np.load(path) as z:
        files = {k: z[k] for k in z.files}
    meta = json.loads(str(files.pop("__meta__")))
    meta.pop("coords")
    meta["format"] = "bushenv-planar-model"
    np.savez(tmp_path / "old.npz", __meta__=np.array(json.dumps(meta)), **files)
    back = load_model(tmp_path / "old.npz")
    assert isinstance(back, PlanarLinear)
    np.testing.assert_array_equal(back.simulate(_q(20)), m.simulate(_q(20)))


def test_bad_files_name_the_file(tmp_path):
    txt = tmp_path / "x.npz"
    txt.write_text("hello")
    with pytest.raises(BadInput, match="x.npz"):
        load_model(txt)
    with pytest.raises(BadInput, match="no such"):
        load_model(tmp_path / "missing.npz")


def test_unknown_name_lists_known_names():
    from bushenv.models import ModelError

    with pytest.raises(ModelError, match="known names: .*linear"):
        MODELS["lstm"].model_class(3)
    assert "linear" in MODELS


def test_fit_linear_recovers_full_matrices():
    m = PlanarLinear(K, C)
    q = _q(400, seed=3)
    v = np.gradient(q, m.dt, axis=0)
    fit = fit_linear(q, v, m.simulate(q, v))
    np.testing.assert_allclose(fit.k_matrix, K, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(fit.c_matrix, C, rtol=1e-6, atol=1e-6)


def test_one_axis_models_unchanged():
    from bushenv.models.registry import MODELS

    assert {"linear", "nn", "hybrid"} <= set(MODELS.names())
