"""The vector Bouc-Wen bushing: its law, its bound, its coupling, and its identification."""

import numpy as np
import pytest

from bushenv.identify.vector_boucwen import VectorBoucWenOptions, fit_vector_boucwen
from bushenv.models.base import PAPER_DT
from bushenv.models.boucwen.planar import PlanarBoucWen
from bushenv.models.planar_base import PlanarModelError
from bushenv.motions import random_independent

D = np.array([0.3e-3, 0.4e-3, 0.01])


def unit(shape=(0.5, 0.5, 2.0)) -> PlanarBoucWen:
    return PlanarBoucWen(np.zeros((3, 3)), np.zeros((3, 3)), np.ones(3), D, shape)


def test_one_coordinate_follows_the_classical_scalar_law():
    # z' = u' - beta |u'| |z|^(eta-1) z - gamma u' |z|^eta, integrated by fine explicit Euler
    beta, gamma, eta = 0.8, 0.2, 1.5
    t = np.arange(200) * PAPER_DT
    x = 1.2e-3 * np.sin(2 * np.pi * 4.0 * t)
    q = np.zeros((200, 3))
    q[:, 1] = x
    z = unit((beta, gamma, eta)).hysteretic_state(q)
    u = np.interp(np.linspace(0, 199, 199 * 1000 + 1), np.arange(200), x / D[1])
    zs, want = 0.0, [0.0]
    for du in np.diff(u):
        zs += du - beta * abs(du) * abs(zs) ** (eta - 1) * zs - gamma * du * abs(zs) ** eta
        want.append(zs)
    want = np.array(want)[::1000]
    assert np.max(np.abs(z[:, 1] - want)) < 2e-3
    assert np.all(z[:, [0, 2]] == 0)


def test_hysteretic_state_stays_in_the_unit_ball():
    q = random_independent(1.5, 10.0, PAPER_DT, 3)
    for shape in ((0.5, 0.5, 1.0), (3.0, -2.0, 2.0), (1.0, 0.0, 6.0)):
        z = unit(shape).hysteretic_state(q)
        assert np.linalg.norm(z, axis=1).max() <= 1.0 + 1e-6, shape


def test_axial_yield_takes_radial_hysteretic_force():
    # saturate radially, hold, then slide axially: on the shared yield surface z turns
    # toward the axial direction and the radial hysteretic force falls (no axis-by-axis model can)
    T = 200
    q = np.zeros((T, 3))
    q[:, 1] = np.minimum(np.arange(T), 50) / 50 * 10 * D[1]
    q[100:, 0] = np.arange(T - 100) / 100 * 10 * D[0]
    z = unit().hysteretic_state(q)
    assert z[99, 1] > 0.99 and abs(z[99, 0]) < 1e-12
    assert z[-1, 1] < 0.2 and z[-1, 0] > 0.95


@pytest.mark.parametrize(
    "shape", [(0.4, 0.6, 2.0), (1.0, 0.1, 2.0), (0.6, 0.4, 0.5), (0.6, 0.4, 9.0)]
)
def test_shapes_outside_the_bounded_law_are_refused(shape):
    with pytest.raises(PlanarModelError, match="boucwen"):
        unit(shape)


def _truth() -> PlanarBoucWen:
    k = np.array([[3.0e5, 2.0e4, 0.0], [2.0e4, 1.2e6, 1.0e3], [0.0, 1.0e3, 4.0e3]])
    c = np.diag([4.0e3, 1.4e4, 50.0])
    return PlanarBoucWen(k, c, [100.0, 500.0, 40.0], [0.4e-3, 0.5e-3, 0.012], (1.5, -0.5, 2.5))


def test_identification_recovers_a_vector_boucwen_and_is_deterministic():
    q = random_independent(1.0, 6.0, PAPER_DT, 0)
    truth = _truth()
    f = truth.simulate(q)
    opts = VectorBoucWenOptions(evaluations=60, time_limit_s=0.0)
    model, info = fit_vector_boucwen([(q, f)], PAPER_DT, opts)
    again, _ = fit_vector_boucwen([(q, f)], PAPER_DT, opts)
    assert np.array_equal(model.k_matrix, again.k_matrix)
    assert np.array_equal(model.d_yield, again.d_yield)
    q_new = random_independent(1.3, 8.0, PAPER_DT, 9)
    f_new, pred = truth.simulate(q_new), model.simulate(q_new)
    err = np.sqrt(np.mean((pred - f_new) ** 2, axis=0) / np.mean(f_new**2, axis=0))
    assert np.all(err < 0.01), err
    assert np.allclose(model.d_yield, truth.d_yield, rtol=0.1)
    assert not info["time_limited"] and np.all(model.h_force >= 0)


def test_the_clock_stops_the_search_and_says_so():
    q = random_independent(1.0, 8.0, PAPER_DT, 1)
    f = _truth().simulate(q)
    for selection in ("all", "extrapolation"):
        opts = VectorBoucWenOptions(300, time_limit_s=1e-6, relaxation_selection=selection)
        model, info = fit_vector_boucwen([(q, f)], PAPER_DT, opts)
        # each search evaluates its first shape whatever the clock: a second search runs
        # only when the selection dropped a branch
        again = len(model.relax_tau) < len(opts.taus())
        assert info["time_limited"] and info["evaluations"] == 1 + again, info
        assert np.all(np.isfinite(model.simulate(q)))


def test_hybrid_bw_is_its_backbone_plus_its_network():
    from bushenv.models.planar_hybrid_bw import PlanarBoucWenHybrid
    from bushenv.models.planar_narx import PlanarNarx

    model = PlanarBoucWenHybrid.untrained(seed=3)
    net = PlanarNarx(**{k: model.params[k] for k in PlanarNarx.param_names})
    q = random_independent(1.0, 3.0, PAPER_DT, 2)
    f = model.simulate(q)
    assert np.array_equal(f, model.backbone.simulate(q) + net.simulate(q))
    assert np.all(np.abs(f - model.backbone.simulate(q)) <= model.nn_bound())


def test_hybrid_bw_fit_runs_backbone_then_network():
    from bushenv.identify import fit

    q = random_independent(1.0, 6.5, PAPER_DT, 4)
    f = _truth().simulate(q)
    opts = {"evaluations": 1, "teacher_steps": 20, "free_run_steps": 0}
    result = fit([(q, f)], "hybrid-bw", opts, 0, False, dt=PAPER_DT)
    assert result.model.name == "hybrid-bw" and result.info["backbone evaluations"] >= 8
    err = result.model.simulate(q) - f
    assert np.all(np.sqrt(np.mean(err**2, axis=0) / np.mean(f**2, axis=0)) < 0.05)


def test_axis_yield_surface_keeps_each_coordinate_to_itself(tmp_path):
    T = 200
    q = np.zeros((T, 3))
    q[:, 1] = np.minimum(np.arange(T), 50) / 50 * 10 * D[1]
    q[100:, 0] = np.arange(T - 100) / 100 * 10 * D[0]
    axis = PlanarBoucWen(np.zeros((3, 3)), np.zeros((3, 3)), np.ones(3), D, (0.5, 0.5, 2.0),
                         yield_surface="axis")  # fmt: skip
    z = axis.hysteretic_state(q)
    assert z[-1, 1] == z[99, 1] > 0.99 and z[-1, 0] > 0.95
    one = np.zeros((T, 3))
    one[:, 1] = q[:, 1]
    assert np.array_equal(axis.hysteretic_state(one)[:, 1], z[:, 1])
    from bushenv.models import load_model

    back = load_model(axis.save(tmp_path / "axis.npz"))
    assert back.yield_surface == "axis" and np.array_equal(back.hysteretic_state(q), z)
    with pytest.raises(PlanarModelError, match="yield_surface 'box'"):
        PlanarBoucWen(np.zeros((3, 3)), np.zeros((3, 3)), np.ones(3), D, yield_surface="box")
