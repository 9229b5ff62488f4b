"""The planar reference: one-axis lineage, the coupled elastic law, vector friction, effects."""

import numpy as np
import pytest

from bushenv.models import load_model
from bushenv.models.planar_base import PlanarModelError
from bushenv.reference.planar import PlanarRubber
from bushenv.reference.planar_elastic import elastic_force, tangent_stiffness
from bushenv.reference.rubber import RubberBushing

DT = 1 / 204.8


def _sines(T=600, amps=(2e-3, 2e-3, 0.05), freqs=(1.7, 2.3, 1.1)):
    t = np.arange(T) * DT
    return np.stack(
        [a * np.sin(2 * np.pi * f * t) for a, f in zip(amps, freqs, strict=True)], axis=1
    )


def _elastic(m, q):
    out = np.empty(3)
    elastic_force(*q, m.elastic_params(), out)
    return out


def test_one_axis_without_coupling_is_the_one_axis_reference():
    ref1 = RubberBushing.preset(
        "axial", measurement=False, effects=("relaxation", "friction"), friction_law="iwan"
    )
    planar = PlanarRubber.preset(effects=("relaxation", "friction"), measurement=False)
    q = _sines()
    q[:, 1:] = 0.0
    f = planar.simulate(q)
    np.testing.assert_allclose(f[:, 0], ref1.simulate(q[:, 0]), rtol=1e-9, atol=1e-6)
    np.testing.assert_array_equal(f[:, 1:], 0.0)


def test_tangent_stiffness_is_the_derivative_of_the_force():
    m = PlanarRubber.preset(measurement=False)
    rng = np.random.default_rng(1)
    for _ in range(20):
        q = rng.uniform(-1, 1, 3) * np.array([8e-3, 8e-3, 0.12])
        h = np.array([1e-8, 1e-8, 1e-7])
        fd = np.stack(
            [
                (_elastic(m, q + h[j] * np.eye(3)[j]) - _elastic(m, q - h[j] * np.eye(3)[j]))
                / (2 * h[j])
                for j in range(3)
            ],
            axis=1,
        )
        k = tangent_stiffness(q, m.elastic_params())
        np.testing.assert_allclose(k, fd, rtol=1e-5, atol=1e-3 * np.abs(k).max())
        np.testing.assert_array_equal(k, k.T)


def test_elastic_energy_is_convex_over_the_stroke_and_rotation_range():
    p = PlanarRubber.preset().elastic_params()
    for ua in np.linspace(-12.5e-3, 12.5e-3, 7):
        for ur in np.linspace(-12.5e-3, 12.5e-3, 11):
            for th in np.linspace(-0.15, 0.15, 11):
                assert np.linalg.eigvalsh(tangent_stiffness(np.array([ua, ur, th]), p)).min() > 0


def test_radial_force_falls_then_rises_under_rotation_at_held_preload():
    m = PlanarRubber.preset(effects=("coupling",), measurement=False)
    fr = np.array([_elastic(m, (0.0, 2e-3, th))[1] for th in np.linspace(0, 0.15, 31)])
    i = int(np.argmin(fr))
    assert 0 < i < 30 and fr[i] < 0.95 * fr[0] and fr[-1] > 1.2 * fr[0]


def test_coupling_switch_decouples_the_rotation_from_the_radial_force():
    q = _sines()
    q_still = q.copy()
    q_still[:, 2] = 0.0
    # friction left out: its vector yield surface couples the axes on its own (tested below)
    on = PlanarRubber.preset(effects=("coupling", "hardening", "relaxation"), measurement=False)
    off = on.without_effects("coupling")
    assert "coupling" not in off.effects
    d_on = np.abs(on.simulate(q)[:, 1] - on.simulate(q_still)[:, 1]).max()
    d_off = np.abs(off.simulate(q)[:, 1] - off.simulate(q_still)[:, 1]).max()
    assert d_off == 0.0 and d_on > 50.0


def test_vector_friction_couples_the_axes_and_axis_friction_does_not():
    base = dict(effects=("friction",), measurement=False)
    q = _sines(amps=(2e-3, 0.1e-3, 0.0))
    lone = q.copy()
    lone[:, 0] = 0.0
    for yield_, coupled in (("vector", True), ("axis", False)):
        m = PlanarRubber.preset(friction_yield=yield_, **base)
        diff = np.abs(m.simulate(q)[:, 1] - m.simulate(lone)[:, 1]).max()
        assert bool(diff > 1.0) is coupled, (yield_, diff)


def test_held_radial_step_relaxes_and_rotation_relaxes_through_the_coupling():
    m = PlanarRubber.preset(effects=("coupling", "relaxation"), measurement=False)
    T = 2048
    q = np.zeros((T, 3))
    q[5:, 1] = 3e-3
    q[5:, 2] = 0.06
    f = m.simulate(q, np.zeros_like(q))
    assert f[10, 1] > f[-1, 1] * 1.2 and f[10, 2] > f[-1, 2] * 1.2


def test_step_loop_equals_simulate_with_noise_and_batches():
    m = PlanarRubber.preset(seed=3)
    q = np.stack([_sines(200), 0.5 * _sines(200)], axis=1)
    v = np.gradient(q, DT, axis=0)
    f = m.simulate(q, v)
    m.reset(2)
    np.testing.assert_array_equal(np.stack([m.step(q[t], v[t]) for t in range(200)]), f)
    np.testing.assert_array_equal(m.simulate(q, v), f)  # seeded: same noise again


def test_save_load_keeps_effects_and_force(tmp_path):
    m = PlanarRubber.preset(effects=("coupling", "friction"), friction_yield="axis")
    back = load_model(m.save(tmp_path / "ref.npz"))
    assert back.effects == m.effects and back.friction_yield == "axis"
    q = _sines(100)
    np.testing.assert_array_equal(back.simulate(q), m.simulate(q))


def test_bad_arguments_name_the_value():
    with pytest.raises(PlanarModelError, match="unknown effect"):
        PlanarRubber.preset(effects=("thermal",))
    with pytest.raises(PlanarModelError, match="unknown effect"):
        PlanarRubber.preset().without_effects("thermal")
    with pytest.raises(PlanarModelError, match="friction_yield"):
        PlanarRubber.preset(friction_yield="box")
    with pytest.raises(PlanarModelError, match="stiffness"):
        PlanarRubber(stiffness=(1.0, -1.0, 1.0), damping=(0, 0, 0))


def test_stiffness_table_script_gives_nine_rows_with_the_coupling_sign_change():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).parents[2] / "scripts" / "planar_stiffness.py"
    spec = importlib.util.spec_from_file_location("planar_stiffness", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    rows = mod.table(PlanarRubber.preset().elastic_params()).splitlines()[2:]
    assert len(rows) == 9
    k_rt = [float(r.split("|")[7]) for r in rows]
    assert k_rt[4] < 0 < k_rt[5]  # 2 mm preload: falling at 0.05 rad, rising at 0.10 rad
