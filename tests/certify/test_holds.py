"""The free-run verdicts of the certificate, checked against longer independent simulations."""

import numpy as np
import pytest

from bushenv.certify.fixed_points import fixed_points
from bushenv.certify.ghosts import ghosts
from bushenv.certify.holds import JUMP, free_runs, reference_static_force, step_profiles
from bushenv.certify.network import narx_net
from bushenv.divergence import judge
from bushenv.models import get_model
from bushenv.models.linear import LinearBushing
from bushenv.models.narx import NarxBushing
from bushenv.reference.rubber import RubberBushing

from .conftest import X_SCALE_M, fold_hybrid, fold_nn, fold_u


def _certified(model, x, hold_s=20.0):
    net = narx_net(model)
    fp = fixed_points(net, np.asarray(x, dtype=float))
    gh = ghosts(net, fp.x_m)
    runs, _, _ = free_runs(model, net, fp, gh, hold_s)
    return net, fp, gh, runs


def _long_run(model, x, hold_s):
    prof, start = step_profiles(np.asarray(x, dtype=float), hold_s, model.dt)
    return prof, start, model.copy().simulate(prof)


def _crossing_time(net, prof, start, f, level_y):
    """Seconds after the step at which the output first rises JUMP above ``level_y``."""
    y = net.output_of_force(prof, f)
    out = []
    for i in range(f.shape[1]):
        above = np.flatnonzero(y[start[i] :, i] > level_y[i] + JUMP)
        out.append(np.nan if above.size == 0 else above[0] * net.dt_s)
    return np.array(out)


def test_holds_past_the_fold_depart_when_the_certificate_says_and_the_judge_agrees():
    model = fold_nn()
    uf = fold_u(2.0)
    eps = np.array([2e-4, 1e-4, 4e-5, 2e-5])  # passage through the ghost ~ 1/sqrt(eps)
    x = uf * (1 + eps) * X_SCALE_M
    net, fp, gh, runs = _certified(model, x)
    assert all(r.departs and r.observed and r.departs_from == "ghost" for r in runs)
    dep = np.array([r.departure_s for r in runs])
    assert np.all(np.diff(dep) > 0) and dep[0] > 2.0 and dep[-1] < 20.0
    # the ghost's passage time (an analytic prediction) matches the observed departure
    passage = np.array([gh.passage_s[gh.hold == i].max() for i in range(x.size)])
    np.testing.assert_allclose(dep, passage, rtol=0.15)
    # independent: a 40 s run, judged against a linear reference, self-sustains at that time
    prof, start, f = _long_run(model, x, 40.0)
    ref = LinearBushing(1.0e6, 0.0).simulate(prof)
    v = judge(prof, f, ref, model.dt)
    assert v.flags["self_sustained"].all()
    final = np.array([fp.force_n[fp.of_hold(i)[r.reached]] for i, r in enumerate(runs)])
    np.testing.assert_allclose(f[-1], final, atol=1e-6)
    lower = -np.sqrt(1 - 1 / 2.0)  # the ghost sits where the lower pair merged
    t = _crossing_time(net, prof, start, f, np.full(x.size, lower))
    np.testing.assert_allclose(t, dep, atol=1.0)


def test_holds_just_inside_the_fold_stay_on_their_branch_for_a_long_hold():
    model = fold_nn()
    x = fold_u(2.0) * (1 - np.array([1e-2, 1e-3, 1e-4])) * X_SCALE_M
    net, fp, _, runs = _certified(model, x)
    for i, r in enumerate(runs):
        assert not r.departs and r.reached == 0  # the lower branch, index 0 of three
        assert fp.stable[fp.of_hold(i)[0]]
    prof, _, f = _long_run(model, x, 100.0)
    want = [fp.force_n[fp.of_hold(i)[0]] for i in range(x.size)]
    np.testing.assert_allclose(f[-1], want, atol=1e-3)
    ref = LinearBushing(1.0e6, 0.0).simulate(prof)
    assert not judge(prof, f, ref, model.dt).flags["self_sustained"].any()


def test_a_departure_beyond_the_horizon_is_predicted_and_happens_in_a_longer_run():
    model = fold_nn()
    x = np.array([fold_u(2.0) * (1 + 1e-6) * X_SCALE_M])
    net, fp, gh, runs = _certified(model, x, hold_s=20.0)
    (r,) = runs
    assert r.departs and not r.observed and r.departs_from == "ghost"
    assert r.departure_s > 20.0
    assert fp.force_n[fp.of_hold(0)[r.reached]] > 1500  # the upper branch, the only root left
    prof, start, f = _long_run(model, x, 3 * r.departure_s)
    t = _crossing_time(net, prof, start, f, np.array([-np.sqrt(0.5)]))
    assert t[0] == pytest.approx(r.departure_s, rel=0.1)
    np.testing.assert_allclose(f[-1, 0], fp.force_n[fp.of_hold(0)[r.reached]], atol=1e-6)


def test_a_hybrid_held_past_its_fold_jumps_to_k_x_plus_the_far_residual():
    model = fold_hybrid()
    uf = fold_u(2.0)
    x = np.array([uf * 0.9, uf * (1 + 3e-5)]) * X_SCALE_M
    net, fp, _, runs = _certified(model, x)
    assert not runs[0].departs and runs[1].departs and runs[1].departs_from == "ghost"
    far = fp.force_n[fp.of_hold(1)[runs[1].reached]]
    assert far == pytest.approx(
        model.k_n_per_m * x[1] + model.f_scale_n * (fp.y[fp.of_hold(1)][0, 0] + 0.9)
    )
    _, _, f = _long_run(model, x, 30.0)
    assert f[-1, 1] == pytest.approx(far, abs=1e-6)


def test_a_flip_oscillation_is_reported_as_oscillating_not_settled():
    # y_t = tanh(-3 y_{t-1} + xs): its only fixed point has a = -3 sech^2 < -1: period two
    model = NarxBushing(
        0.0,
        1e-3,
        0.0,
        100.0,
        np.array([[0.5, 0.5, -3.0]]),
        np.zeros(1),
        np.zeros((0, 1)),
        np.zeros(0),
        np.ones(1),
        0.0,
        n_past_x=1,
        n_past_f=1,
    )
    net, fp, _, runs = _certified(model, np.array([0.0, 0.1e-3, -2e-3]))
    assert not fp.stable.any()
    # at x = 0 the run starts exactly on the unstable fixed point (y = 0) and stays there
    assert runs[0].reached == 0 and not runs[0].oscillates and not runs[0].departs
    assert all(r.oscillates and r.reached is None and not r.departs for r in runs[1:])
    _, _, f = _long_run(model, fp.x_m, 10.0)
    assert np.all(np.ptp(f[-100:, 1:], axis=0) > 50.0) and np.all(f[-100:, 0] == 0.0)


@pytest.mark.parametrize("axis", ["axial", "radial"])
@pytest.mark.parametrize("name", ["nn", "hybrid"])
def test_shipped_models_stay_at_the_certified_static_force_for_a_minute(name, axis):
    model = get_model(name, axis=axis)
    x = np.linspace(-12.5e-3, 12.5e-3, 26)
    net, fp, _, runs = _certified(model, x)
    assert all(r.reached is not None and not r.departs for r in runs)
    static = np.array([fp.force_n[fp.of_hold(i)[r.reached]] for i, r in enumerate(runs)])
    assert all(fp.stable[fp.of_hold(i)[r.reached]] for i, r in enumerate(runs))
    prof, _, f = _long_run(model, x, 60.0)
    np.testing.assert_allclose(f[-1], static, atol=1e-6 * np.max(np.abs(static)))
    assert np.max(np.abs(f[-2048:] - static), axis=0).max() < 1e-3 * np.max(np.abs(static))


def test_reference_static_force_is_k_x_for_a_spring_and_the_settled_rubber_force():
    x = np.array([-4e-3, 0.0, 1e-3, 4e-3])
    lin = LinearBushing(2.0e5, 3.0e3)
    np.testing.assert_allclose(reference_static_force(lin, x), 2.0e5 * x, atol=1e-9)
    rubber = RubberBushing.preset("axial", measurement=False)
    f = reference_static_force(rubber, x)
    # reference.rubber: the specimen holds 923 N 20 s after a 4 mm step (946 N at 5 s)
    assert f[-1] == pytest.approx(923.0, abs=5.0)
    assert f[0] < 0 < f[2] < f[3]
