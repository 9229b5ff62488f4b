"""Certified MIMO training: the band holds the reference, the term is zero where a network
holds right and positive where it does not, its gradients are the implicit function theorem's,
and a certified training leaves no out-of-band or unstable fixed point where the plain one did."""

import numpy as np
import pytest
import torch

from bushenv.identify import fit
from bushenv.identify.mimo_certified import (
    MimoCertifiedHolds,
    MimoProblem,
    check,
    step_profile,
)
from bushenv.identify.mimo_options import MimoOptions
from bushenv.identify.mimo_train import _Net
from bushenv.identify.static_estimate import static_estimate
from bushenv.models.base import PAPER_DT
from bushenv.models.planar_base import PlanarModelError
from bushenv.motions import random_independent
from bushenv.reference.planar import PlanarRubber


@pytest.fixture(scope="module")
def record():
    q = random_independent(1.0, 30.0, PAPER_DT, 0)
    return q, PlanarRubber.preset(seed=0).simulate(q)


@pytest.fixture(scope="module")
def estimate(record):
    return static_estimate([record], PAPER_DT)


def test_the_estimate_finds_each_coordinates_slow_stiffness(estimate):
    # the reference's static stiffness near rest: the one-axis presets' slow slopes (docs/fit.md
    # table: 293 and 1138 N/mm), the assumed 3000 N m/rad stiffened by friction near rest
    assert estimate.k[0] == pytest.approx(290e3, rel=0.15)
    assert estimate.k[1] == pytest.approx(1100e3, rel=0.15)
    assert 3000 < estimate.k[2] < 5000


def test_the_reference_holds_inside_the_band_everywhere_on_the_box(estimate):
    term = MimoCertifiedHolds(1.0)
    q = term.check_holds_q()
    f = PlanarRubber.preset(seed=0).simulate(step_profile(q, PAPER_DT, hold_s=1.0))[-1]
    sign, lo, hi, scale = estimate.band(q, term.low, term.high)
    along = sign * f
    outside = (np.maximum(lo - along, 0) + np.maximum(along - hi, 0)) / scale
    assert outside.max() <= 0.02  # the admission's tolerance
    # without the coupling allowance the reference's coupled holds fall out of the band
    sign, lo, hi, scale = estimate.band(q, term.low, term.high, coupling=0.0)
    along = sign * f
    assert np.sum((np.maximum(lo - along, 0) + np.maximum(along - hi, 0)) / scale > 0.02) > 50
    # a coordinate at rest holds nothing beyond its floor, whatever the others do
    rest = q[:, 1] == 0
    assert np.all(np.abs(f[rest, 1]) <= 0.01 * estimate.force_rms[1])


def _problem(estimate, k=None):
    return MimoProblem(
        q_offset=np.zeros(3),
        q_scale=np.array([2e-3, 2e-3, 0.05]),
        f_offset=np.array([10.0, -20.0, 3.0]),
        f_scale=np.array([300.0, 1000.0, 100.0]),
        k=np.diag(1.2 * estimate.k) if k is None else k,
        dt=PAPER_DT,
        estimate=estimate,
    )


def _quiet_net(problem, shift=0.0, hidden=6, seed=0):
    """A hybrid's network that holds almost nothing: its backbone (1.2 times the estimate)
    holds the force; ``shift`` (scaled output) adds a constant force in every coordinate."""
    net = _Net(hidden, False, torch.Generator().manual_seed(seed))
    with torch.no_grad():
        net.w_out.mul_(1e-4)
        net.b_out.copy_(torch.from_numpy(-problem.f_offset / problem.f_scale + shift))
    return net


def test_the_term_is_zero_for_a_network_that_holds_right_and_positive_otherwise(estimate):
    problem = _problem(estimate)
    term = MimoCertifiedHolds(1.0)
    good = _quiet_net(problem)
    assert term(good, problem).item() == 0.0
    assert term.check(_model(good, problem), estimate)["admitted"]
    # a constant cross-force: every coordinate held at rest now carries 0.05 f_scale
    assert term(_quiet_net(problem, shift=0.05), problem).item() > 0.0
    # the backbone's stiffness of the wrong sign in rotation
    flipped = _problem(estimate, k=np.diag(estimate.k * np.array([1.2, 1.2, -1.2])))
    parts = term.penalties(_quiet_net(flipped), flipped, term.holds_q(0))
    rot = term.holds_q(0)[parts["fixed_points"].hold, 2]
    moves_rotation = rot != 0
    clear = np.abs(estimate.k[2] * rot) > 0.02 * estimate.force_rms[2]  # beyond twice the floor
    assert clear.sum() >= 8
    assert np.all(parts["static"][clear, 2].detach().numpy() > 0.5)
    assert np.all(parts["static"][~moves_rotation].detach().numpy() == 0.0)


def _model(net, problem):
    from bushenv.models.planar_narx import PlanarHybrid

    return PlanarHybrid(
        k_matrix=problem.k,
        c_matrix=np.zeros((3, 3)),
        q_offset=problem.q_offset,
        q_scale=problem.q_scale,
        f_offset=problem.f_offset,
        f_scale=problem.f_scale,
        dt=problem.dt,
        **net.arrays(),
    )


def _lively_net(problem, seed=3):
    """A small network whose held recurrence is far from trivial (rho ~ 0.5-0.9)."""
    net = _Net(3, False, torch.Generator().manual_seed(seed))
    with torch.no_grad():
        net.w1.mul_(3.0)
        net.b1.copy_(torch.tensor([0.2, -0.3, 0.1], dtype=torch.float64))
        net.b_out.copy_(torch.tensor([0.1, -0.2, 0.05], dtype=torch.float64))
    return net


def test_fixed_points_and_spectral_radius_match_the_certificate(estimate):
    problem = _problem(estimate)
    net = _lively_net(problem)
    term = MimoCertifiedHolds(1.0)
    q = term.holds_q(0)
    parts = term.penalties(net, problem, q)
    fp = parts["fixed_points"]
    np.testing.assert_allclose(parts["spectral_radius"].detach().numpy(), fp.spectral_radius,
                               atol=1e-12)  # fmt: skip
    force = parts["force"].detach().numpy()
    held = check(_model(net, problem), estimate, q)  # the hybrid: its backbone in its force
    assert held["fixed_points"] == len(fp.hold)
    np.testing.assert_allclose(force, fp.force + q[fp.hold] @ problem.k.T, rtol=1e-10, atol=1e-9)
    assert 0.3 < fp.spectral_radius.max() < 1.0


def test_gradients_match_finite_differences_of_re_solved_fixed_points(estimate):
    problem = _problem(estimate)
    net = _lively_net(problem)
    term = MimoCertifiedHolds(1.0)
    q = term.holds_q(0)[:8]
    rng = np.random.default_rng(0)
    r_force = torch.from_numpy(rng.normal(size=(8, 3)) / problem.f_scale)
    r_rho = torch.from_numpy(rng.normal(size=8))

    def functional():
        parts = term.penalties(net, problem, q)
        assert np.all(parts["fixed_points"].count == 1)
        return torch.sum(parts["force"] * r_force) + torch.sum(parts["spectral_radius"] * r_rho)

    net.zero_grad()
    functional().backward()
    h = 1e-6
    for name, index in (("w1", (0, 20)), ("w1", (2, 5)), ("b1", (1,)), ("w_out", (1, 2)),
                        ("b_out", (0,)), ("w1", (1, 30))):  # fmt: skip
        p = getattr(net, name)
        analytic = p.grad[index].item()
        with torch.no_grad():
            p[index] += h
            up = functional().item()
            p[index] -= 2 * h
            down = functional().item()
            p[index] += h
        numeric = (up - down) / (2 * h)
        assert analytic == pytest.approx(numeric, rel=1e-4, abs=1e-7), (name, index)


def test_the_whole_term_has_the_gradient_of_its_value(estimate):
    problem = _problem(estimate)
    net = _lively_net(problem, seed=5)
    term = MimoCertifiedHolds(1.0, holds=7)

    def value():
        term.calls = 0
        return term(net, problem)

    net.zero_grad()
    v = value()
    assert v.item() > 0
    v.backward()
    h = 1e-6
    for name, index in (("w1", (0, 3)), ("b1", (2,)), ("w_out", (0, 1)), ("w1", (1, 25))):
        p = getattr(net, name)
        with torch.no_grad():
            p[index] += h
            up = value().item()
            p[index] -= 2 * h
            down = value().item()
            p[index] += h
        assert p.grad[index].item() == pytest.approx((up - down) / (2 * h), rel=1e-4, abs=1e-6)


def test_the_holds_cover_single_coordinates_pairs_and_the_box():
    term = MimoCertifiedHolds(1.0)
    q = np.vstack([term.holds_q(c) for c in range(20)])
    moved = q != 0
    for pattern in ((1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (0, 1, 1), (1, 1, 1)):
        assert np.any(np.all(moved == np.array(pattern, dtype=bool), axis=1))
    assert np.all(np.abs(q) <= np.array(term.stroke))
    assert np.abs(q).max(axis=0) == pytest.approx(np.array(term.stroke), rel=0.05)
    assert not np.array_equal(term.holds_q(0), term.holds_q(1))  # new holds each step


def test_options_refuse_a_band_without_one_and_the_bouc_wen_hybrid():
    from bushenv.identify.mimo import HybridBWOptions
    from bushenv.identify.options import options_of

    with pytest.raises(PlanarModelError, match="certified_low"):
        options_of(MimoOptions, {"certified_low": "1.2"}, "hybrid")
    with pytest.raises(PlanarModelError, match="hybrid-bw"):
        options_of(HybridBWOptions, {"certified": "on"}, "hybrid-bw")


DEFAULT = {}  # the default budgets: about a minute certified on the shared machine


@pytest.mark.slow
def test_a_certified_training_holds_where_the_plain_one_does_not(record, estimate):
    q, f = record
    n = q.shape[0] - int(0.2 * q.shape[0])
    est = static_estimate([(q[:n], f[:n])], PAPER_DT)
    plain = fit([record], "hybrid", DEFAULT, 0, progress=False, dt=PAPER_DT).model
    cert = fit([record], "hybrid", {**DEFAULT, "certified": "on"}, 0, progress=False, dt=PAPER_DT)
    grid = MimoCertifiedHolds(1.0).check_holds_q()
    before, after = check(plain, est, grid), check(cert.model, est, grid)
    assert before["out_of_band"] > 0
    assert after["out_of_band"] == 0 and after["unstable"] == 0
    assert after["holds_without_one_fixed_point"] == 0
    assert "certified" in cert.info and cert.model.training["certified"] == after


def test_bushenv_fit_takes_certified_on_for_3_axis_records(tmp_path, capsys):
    from bushenv.cli import main

    rec = tmp_path / "rec"
    assert main(["measure", "--axes", "3", "--programme", "random", "--duration", "6",
                 "--out", str(rec), "--quiet"]) == 0  # fmt: skip
    train = sorted(map(str, rec.glob("*.csv")))
    args = ["fit", *train, "--model", "hybrid", "--certified", "on", "--certified-holds", "7",
            "--hidden", "6", "--teacher-steps", "8", "--free-run-steps", "0", "--window", "16",
            "--out", str(tmp_path / "c.npz"), "--quiet"]  # fmt: skip
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "certified: " in out and "343 holds" in out
    # admission ordered the weights, so the network gate did not judge: the card says so
    assert "network: kept without the gate: --certified on" in out
    bad = [*args[:-3], "--certified-low", "1.5", "--out", str(tmp_path / "d.npz"), "--quiet"]
    assert main(bad) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "certified_low 1.5" in err[0]
