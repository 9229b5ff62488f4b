"""The vetting and the certificate agree: a reference is simulated through
the holds its own certificate lists, each reached after a sine inside its envelope, against a
threshold tied to its own noise and force scale."""

import numpy as np
import pytest

from bushenv.certify.reached_holds import (
    TAIL_S,
    confirm_holds,
    failing_holds,
    hold_entries,
    reach_profiles,
    ring_threshold,
    tail_ripple,
)
from bushenv.judge import JudgeError, build_judge
from bushenv.models import get_model
from bushenv.scales import BushingScales
from bushenv.vetting import of_scales, vet_reference
from bushenv.vetting_holds import hold_check

from .conftest import ringing_hybrid

SCALES = BushingScales()  # the papers' machine: +-12.5 mm, 1.26 m/s, 200 N floor
RING_MM = -1.25


def _tail_ripple_after(model, x):
    f = model.copy().simulate(np.asarray(x)[:, None])
    return float(tail_ripple(f[-int(round(TAIL_S / model.dt)) :])[0])


def test_the_test_hybrid_rings_after_a_sine_and_not_after_a_slow_ramp():
    model, dt = ringing_hybrid(), ringing_hybrid().dt
    x_h = RING_MM * 1e-3
    ramp = np.r_[np.linspace(0.0, x_h, int(round(0.25 / dt))), np.full(int(round(4 / dt)), x_h)]
    assert _tail_ripple_after(model, ramp) < 20.0  # a few N: quiet from rest
    profiles, how = reach_profiles(x_h, SCALES.stroke_m, SCALES.velocity_m_per_s, 4.0, dt)
    ripples = [_tail_ripple_after(model, p) for p in profiles]
    assert max(ripples) > 400.0  # hundreds of N peak to peak after a sine
    assert any("sine" in h for h, r in zip(how, ripples, strict=True) if r > 400.0)
    # every history stays inside the envelope
    for p in profiles:
        assert np.max(np.abs(p)) <= SCALES.stroke_m + 1e-12
        assert np.max(np.abs(np.diff(p))) / dt <= SCALES.velocity_m_per_s * (1 + 1e-9)


def test_the_holds_from_rest_pass_it_and_its_certificate_lists_the_ring():
    model = ringing_hybrid()
    holds, _ = hold_check(model, SCALES.stroke_m, SCALES.force_floor_n)
    assert holds.passed is True  # the slow ramps see nothing: why the old vetting passed it
    listed = failing_holds(hold_entries(model, None, SCALES.stroke_m))
    x = [h["x_m"] * 1e3 for h in listed]
    assert listed and all(h["kinds"] == ["oscillates"] for h in listed)
    assert min(x) < RING_MM < max(x) and max(x) - min(x) < 1.0


def test_the_vetting_refuses_a_hybrid_that_rings_after_excitation():
    vet = vet_reference(ringing_hybrid(), "ring", **of_scales(SCALES))
    cert = {c.name: c for c in vet.checks}["certificate holds"]
    assert cert.passed is False and not vet.passed and vet.verdict == "FAILED"
    assert "oscillating" in cert.detail and "sine" in cert.detail
    (lo, hi),  = vet.unvetted_ranges_m  # fmt: skip
    assert lo < RING_MM * 1e-3 < hi


@pytest.mark.parametrize("axis", ["axial", "radial"])
def test_the_vetting_passes_the_shipped_hybrid(axis):
    model = get_model("hybrid", axis=axis)
    vet = vet_reference(model, "hybrid", **of_scales(SCALES))
    checks = {c.name: c for c in vet.checks}
    assert checks["holds"].passed is True
    assert checks["certificate holds"].passed is True
    assert "lists none" in checks["certificate holds"].detail
    assert vet.passed and vet.unvetted_ranges_m == ()


def test_the_threshold_follows_the_references_noise_and_force_scale():
    dt = 1 / 204.8
    t = np.arange(int(4 / dt)) * dt
    quiet = np.outer(np.ones_like(t), np.linspace(-1000, 1000, 9))  # held forces, no noise
    th = ring_threshold(quiet, dt)
    assert th.force_n == pytest.approx(10.0) and th.noise_n == pytest.approx(0.0, abs=1e-9)
    rng = np.random.default_rng(0)
    noisy = quiet + rng.normal(0.0, 5.0, quiet.shape)  # sigma 5 N: about 30 N p-p
    th = ring_threshold(noisy, dt)
    assert th.force_n == pytest.approx(3 * th.noise_n) and 60 < th.force_n < 120
    # a ring of a few holds does not move the median noise
    ringing = noisy.copy()
    ringing[:, :3] += 500.0 * (-1.0) ** np.arange(t.size)[:, None]
    assert ring_threshold(ringing, dt).force_n == pytest.approx(th.force_n, rel=0.2)


def test_a_listed_hold_that_does_not_ring_is_refuted():
    model = get_model("hybrid", axis="axial")
    got, n = confirm_holds(model, [{"x_m": -1e-3}, {"x_m": 2e-3}], (12.5e-3, 1.26), 40.0)
    assert got == [] and n > 10


def test_the_judge_refuses_it_and_trusted_marks_verdicts_in_its_range(tmp_path):
    path = ringing_hybrid().save(tmp_path / "ring.npz")
    model = get_model("linear", axis="axial")
    with pytest.raises(JudgeError, match="certificate holds: .* confirmed .*oscillating"):
        build_judge("linear", str(path), axis="axial", dt=model.dt, model_object=model)
    judge = build_judge("linear", str(path), axis="axial", dt=model.dt, model_object=model,
                        trust_reference=True)  # fmt: skip
    assert judge.unvetted and judge.trusted_by_flag
    dt = model.dt
    hold_in = np.r_[np.zeros(10), np.full(int(1.0 / dt), RING_MM * 1e-3)]
    assert judge.in_unvetted_range(hold_in, dt) is True
    assert judge.in_unvetted_range(np.r_[np.zeros(10), np.full(400, 4e-3)], dt) is False
    sweep = 5e-3 * np.sin(2 * np.pi * 2.0 * np.arange(int(2.0 / dt)) * dt)  # through it, fast
    assert judge.in_unvetted_range(sweep, dt) is False
    described = judge.describe()
    assert described["vetting_verdict"] == "FAILED"
    assert described["unvetted_ranges_m"] == [list(r) for r in judge.unvetted_ranges_m]
