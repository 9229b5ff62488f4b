"""The vetting's certificate check over C > 1 coordinates: each held vector its own certificate
lists is reached as a search reaches it -- a step with every coordinate at its own velocity
limit, sines inside the envelope along each coordinate and along the hold's direction -- and
judged per coordinate with the holds check's thresholds; a confirmed one fails the check and,
trusted, marks the verdicts whose profiles dwell in the box about it."""

import numpy as np
import pytest

from bushenv.certify.reached_holds import boxes_of, confirm_holds, reach_profiles
from bushenv.errors import BadInput
from bushenv.judge import build_judge
from bushenv.models import get_model
from bushenv.vetting import HOLDS, enters_unvetted, machine_rate, unvetted_regions, vet_reference

from .conftest import bistable, ringing3, ringing_hybrid

STROKE3, FLOORS3 = np.array([2e-3, 2e-3, 0.05]), np.array([200.0, 200.0, 20.0])
MACHINE3 = np.array([12.5e-3, 12.5e-3, 0.15])  # BushRig3-v0's stroke
FLOORS_MACHINE3 = np.array([200.0, 200.0, 20.0])
RING = np.array([0.0, -1.25e-3, 0.0])


def _cert(vetting):
    return {c.name: c for c in vetting.checks}["certificate holds"]


def test_every_reaching_profile_stays_inside_the_envelope_of_each_coordinate():
    dt, hold = 1 / 204.8, np.array([1.5e-3, -0.8e-3, 0.03])
    x_env, v_env = np.array([2e-3, 1e-3, 0.05]), np.array([0.02, 0.01, 0.3])
    profiles, how = reach_profiles(hold, x_env, v_env, 4.0, dt, ("a", "r", "t"), ("m", "m", "rad"))
    n_hold = int(round(4.0 / dt))
    assert len(profiles) == len(how) > 10
    for p in profiles:
        assert p.shape[1] == 3 and np.all(p[-n_hold:] == hold) and np.all(p[0] == 0.0)
        assert np.all(np.abs(p) <= np.maximum(x_env, np.abs(hold)) * (1 + 1e-12))
        assert np.all(np.max(np.abs(np.diff(p, axis=0)), axis=0) / dt <= v_env * (1 + 1e-9))
    # the step: each coordinate at its own limit (arriving at its own time)
    step = np.abs(np.diff(profiles[0], axis=0)) / dt
    np.testing.assert_allclose(step.max(axis=0), v_env, rtol=0.1)
    assert sum("along r" in h for h in how) > 0 and sum("along t" in h for h in how) > 0
    assert any("direction" in h for h in how)  # off the axes: along its own direction too
    # a hold on one coordinate: the sines along it already run along its direction
    _, how1 = reach_profiles(np.array([0.0, 1e-3, 0.0]), x_env, v_env, 4.0, dt)
    assert not any("direction" in h for h in how1)


def test_a_ring_on_one_coordinate_of_three_fails_the_check_naming_the_vector():
    """The slow ramps of the holds check do not excite it; the certificate lists it and a sine
    along the radial coordinate confirms it."""
    vet = vet_reference(ringing3(), "ring3", MACHINE3, FLOORS_MACHINE3)
    checks = {c.name: c for c in vet.checks}
    assert checks["holds"].passed is True
    cert = checks["certificate holds"]
    assert cert.passed is False and not vet.passed and vet.verdict == "FAILED"
    assert "lists 1 (oscillates)" in cert.detail and "1 confirmed" in cert.detail
    assert "(+0 mm, -1.25 mm, +0 mrad) oscillating" in cert.detail and "on radial" in cert.detail
    assert "sine along radial" in cert.detail and "radial 80.73 N" in cert.detail
    (box,) = vet.unvetted_boxes
    lo, hi = np.array(box).T
    assert np.all(lo < RING) and np.all(RING < hi) and hi[1] < 0  # about the ring only
    assert vet.describe()["unvetted_boxes"] == [[list(r) for r in box]]


def test_the_default_envelope_over_several_coordinates_is_the_machines_rule():
    np.testing.assert_allclose(machine_rate(MACHINE3), [1.2566370614359175] * 2 + [15.0796447])
    slow = vet_reference(ringing3(), "ring3", MACHINE3, FLOORS_MACHINE3,
                         velocity=np.array([0.02, 0.02, 0.2]))  # fmt: skip
    cert = _cert(slow)
    assert "|dq/dt| <= (0.02 m/s, 0.02 m/s, 0.2 rad/s)" in cert.detail


def test_a_pulling_network_of_three_coordinates_fails_with_its_vectors_and_coordinates():
    quiet = vet_reference(bistable(out=0.3), "quiet", STROKE3, FLOORS3)
    cert = _cert(quiet)
    assert cert.passed is True and "129 held vectors" in cert.detail and "lists none" in cert.detail
    pulling = vet_reference(bistable(gain_q=-2.0, out=0.3), "pulling", STROKE3, FLOORS3)
    checks = {c.name: c for c in pulling.checks}
    assert checks["holds"].passed is False and "wrong sign" in checks["holds"].detail
    cert = checks["certificate holds"]
    assert cert.passed is False and "wrong_sign" in cert.detail
    assert "confirmed (wrong sign" in cert.detail
    assert "(-2 mm, +0 mm, +0 mrad) wrong sign on axial" in cert.detail
    assert "on axial, radial, rotation" in cert.detail
    assert checks["holds"].boxes and cert.boxes


def test_a_listed_vector_the_reaching_does_not_confirm_passes_saying_so(monkeypatch):
    """A quiet network whose certificate (here made to) list a hold off the axes: the step and
    the sines, along each coordinate and its direction, all settle there."""
    import bushenv.vetting_holds as vh

    listed = [{"q": [1.2e-3, -0.8e-3, 0.02], "kinds": ["oscillates"], "departure_s": None}]
    monkeypatch.setattr(vh, "failing_holds", lambda entries: listed)
    vet = vet_reference(bistable(out=0.3), "quiet", STROKE3, FLOORS3)
    cert = _cert(vet)
    assert cert.passed is True and "lists 1 (oscillates)" in cert.detail
    assert "none confirmed by" in cert.detail and not cert.boxes
    assert "first at (+1.2 mm, -0.8 mm, +20 mrad)" in cert.detail
    assert vet.unvetted_boxes == () and "unvetted_boxes" not in vet.describe()
    got, n = confirm_holds(bistable(out=0.3), listed, (STROKE3, machine_rate(STROKE3)),
                           np.array([1.0, 1.0, 0.1]))  # fmt: skip
    assert got == [] and n > 20


def test_a_trusted_vetting_marks_profiles_that_dwell_in_the_box_over_three_coordinates():
    vet = vet_reference(ringing3(), "ring3", MACHINE3, FLOORS_MACHINE3)
    dt = ringing3().dt
    rest = np.zeros((10, 3))
    hold_in = np.r_[rest, np.repeat(RING[None], int(1.0 / dt), axis=0)]
    assert enters_unvetted(vet, hold_in, dt, MACHINE3) is True
    beside = RING + np.array([5e-3, 0.0, 0.0])  # the same radial, axial far off: not seen
    assert enters_unvetted(vet, np.r_[rest, np.repeat(beside[None], 400, 0)], dt, MACHINE3) is False
    t = np.arange(int(2.0 / dt)) * dt
    sweep = np.zeros((t.size, 3))
    sweep[:, 1] = 5e-3 * np.sin(2 * np.pi * 2.0 * t)  # through it, fast
    assert enters_unvetted(vet, sweep, dt, MACHINE3) is False
    with pytest.raises(BadInput, match="a profile of 1 coordinates against a vetting of 3"):
        enters_unvetted(vet, np.zeros(400), dt, MACHINE3)


def test_over_one_coordinate_the_marking_is_the_judges(tmp_path):
    path = ringing_hybrid().save(tmp_path / "ring.npz")
    model = get_model("linear", axis="axial")
    judge = build_judge("linear", str(path), axis="axial", dt=model.dt, model_object=model,
                        trust_reference=True)  # fmt: skip
    dt, stroke = model.dt, judge.scales.stroke_m
    (box,) = unvetted_regions(judge.vetting, stroke)
    assert box.shape == (1, 2)
    rng = np.random.default_rng(0)
    profiles = [np.r_[np.zeros(10), np.full(int(s / dt), x)]
                for x in (-1.25e-3, -1.6e-3, -0.9e-3, 4e-3) for s in (0.3, 0.6)]  # fmt: skip
    profiles += [3e-3 * np.sin(2 * np.pi * rng.uniform(0.2, 5) * np.arange(900) * dt)
                 for _ in range(6)]  # fmt: skip
    for p in profiles:
        assert enters_unvetted(judge.vetting, p, dt, stroke) is judge.in_unvetted_range(p, dt)


def test_boxes_chain_neighbouring_vectors_only():
    q = np.array([[0.0, 1.0], [0.0, 2.0], [0.0, 5.0], [3.0, 5.0]])
    boxes = boxes_of(q, 1.0)
    assert boxes == [((-1.0, 1.0), (0.0, 3.0)), ((-1.0, 1.0), (4.0, 6.0)), ((2.0, 4.0), (4.0, 6.0))]


def test_failing_holds_over_three_coordinates_give_boxes_about_the_held_vectors():
    """The holds check too: a negative radial stiffness fails the radial holds, boxed along
    the radial coordinate and within one step of the grid on the others."""
    from bushenv.models.planar_linear import PlanarLinear

    ref = PlanarLinear.preset()
    k = ref.k_matrix.copy()
    k[1, 1] *= -0.5
    vet = vet_reference(PlanarLinear(k, ref.c_matrix, ref.dt), "neg", MACHINE3, FLOORS_MACHINE3)
    holds = {c.name: c for c in vet.checks}["holds"]
    assert holds.passed is False and holds.boxes and not holds.ranges_m
    step = 2 * MACHINE3 / (HOLDS - 1)
    for box in vet.unvetted_boxes:
        lo, hi = np.array(box).T
        assert hi[0] - lo[0] <= 2 * step[0] + 1e-12 and hi[2] - lo[2] <= 2 * step[2] + 1e-12
        assert hi[1] - lo[1] > 2 * step[1]  # a run of radial holds
