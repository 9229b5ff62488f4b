import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bushenv import divergence as dv
from bushenv import excitation as ex
from bushenv.divergence import DivergenceInputError, judge
from bushenv.models.base import PAPER_DT as DT
from bushenv.models.linear import LinearBushing
from bushenv.reference.rubber import RubberBushing
from bushenv.scales import MACHINE
from bushenv.search.families import FAMILIES, pad_batch
from bushenv.search.targets import TARGETS

RIG_FAMILIES = TARGETS["rig"].family_names()


def _step_case(size=4e-3, hold_s=6.0):
    x = ex.step_hold(size, hold_s, DT, pre_s=0.5, rise_s=0.01)
    fr = RubberBushing.preset("axial", measurement=False).simulate(x)
    return x, fr


def _only(verdict, criterion):
    return [c for c in dv.CRITERIA if verdict.flags[c][0]] == [criterion]


def test_identical_forces_never_diverge():
    x, fr = _step_case()
    v = judge(x, fr, fr, DT)
    assert not v.diverged[0]
    assert v.robustness[0] > 0
    assert np.isnan(v.first_time_s[0])


def test_nan_output_is_flagged_at_its_sample():
    x, fr = _step_case()
    fm = fr.copy()
    fm[300] = np.nan
    v = judge(x, fm, fr, DT)
    assert v.flags["non_finite"][0] and v.first_criterion[0] == "non_finite"
    assert v.first_time_s[0] == pytest.approx(300 * DT)
    assert v.robustness[0] == dv.NON_FINITE_ROBUSTNESS
    assert v.worst_deviation[0] == np.inf


def test_force_beyond_five_times_reference_peak_is_flagged_but_four_times_is_not():
    x, fr = _step_case()
    scale = np.abs(fr).max()
    for factor, flagged in ((5.2, True), (4.0, False)):
        fm = fr.copy()
        fm[50] = factor * scale  # one sample before the step: only the bound can see it
        v = judge(x, fm, fr, DT)
        assert v.flags["force_bound"][0] == flagged, factor
        assert v.diverged[0] == flagged
    assert dv.force_bound(np.array([20e3]))[0] == pytest.approx(40e3)  # rig limit regime
    assert dv.force_bound(np.array([6e3]))[0] == pytest.approx(25e3)
    assert dv.force_bound(np.array([1e3]))[0] == pytest.approx(5e3)


def test_force_bound_uses_the_rig_limit_of_seed002_table1():
    assert MACHINE.force_limit_n == ex.MAX_DYNAMIC_FORCE_N == 25.0e3


def _sine_case():
    # 1.6 Hz: zero crossings every 64 samples, so offsets starting there do no net work
    x = ex.sine(1.6, 3e-3, 5.0, DT)
    fr = 379.68e3 * x + 4.4e3 * ex.sine_velocity(1.6, 3e-3, 5.0, DT)
    return x, fr


def test_deviation_must_exceed_the_reference_peak_for_half_a_second():
    x, fr = _sine_case()
    scale = np.abs(fr).max()
    n_min = int(round(dv.DEVIATION_MIN_S / DT))
    for n, amount, flagged in ((n_min + 5, 1.1, True), (n_min - 5, 1.1, False), (300, 0.9, False)):
        fm = fr.copy()
        fm[256 : 256 + n] += amount * scale
        v = judge(x, fm, fr, DT)
        assert v.flags["deviation"][0] == flagged, (n, amount)
        assert v.diverged[0] == flagged, v.row(0)
    fm = fr.copy()
    fm[256 : 256 + n_min + 5] += 1.1 * scale
    v = judge(x, fm, fr, DT)
    assert _only(v, "deviation")
    assert v.first_time_s[0] == pytest.approx((256 + n_min - 1) * DT)


def test_growing_free_response_during_a_hold_is_self_sustained():
    x, fr = _step_case(hold_s=6.0)
    scale = np.abs(fr).max()
    t = np.arange(x.size) * DT
    fm = fr + np.where(t > 4.0, 0.3 * scale * np.sin(2 * np.pi * 3 * (t - 4.0)), 0.0)
    v = judge(x, fm, fr, DT)
    # the swing also takes the held force below half the reference's: ``static`` follows
    assert v.first_criterion[0] == "self_sustained" and v.flags["self_sustained"][0]
    assert 4.0 < v.first_time_s[0] < 4.3


def test_a_model_that_relaxes_like_the_reference_is_not_self_sustained():
    x, fr = _step_case()
    v = judge(x, 1.2 * fr, fr, DT)  # 20 % too stiff, same relaxation shape
    assert not v.diverged[0]


def test_negative_damping_generates_energy_and_is_flagged():
    x = ex.sine(2.0, 3e-3, 4.0, DT)
    v_ = ex.sine_velocity(2.0, 3e-3, 4.0, DT)
    k, c = 379.68e3, 4.4e3
    fr = k * x + c * v_
    active = k * x - 3 * c * v_  # anticlockwise loop: gives back more than it takes
    verdict = judge(x, active, fr, DT)
    assert verdict.flags["energy"][0]
    assert not judge(x, k * x + 0.2 * c * v_, fr, DT).flags["energy"][0]


def test_constant_force_offset_is_not_energy_generation():
    x = ex.sine(2.0, 3e-3, 4.0, DT)
    fr = 379.68e3 * x + 4.4e3 * ex.sine_velocity(2.0, 3e-3, 4.0, DT)
    v = judge(x, fr + 150.0, fr, DT)
    assert not v.diverged[0]


def test_lengths_make_a_padded_batch_judge_each_profile_alone():
    x1, f1 = _step_case(hold_s=2.0)
    x2, f2 = _step_case(size=-6e-3, hold_s=5.0)
    bad2 = f2 + np.where(np.arange(x2.size) * DT > 3.5, 5e3, 0.0)
    x, lengths = pad_batch([x1, x2])
    fm = np.column_stack([np.r_[f1, np.full(x.shape[0] - x1.size, 1e9)], bad2])
    fr = np.column_stack([np.r_[f1, np.zeros(x.shape[0] - x1.size)], f2])
    v = judge(x, fm, fr, DT, lengths=lengths)
    assert list(v.diverged) == [False, True]
    alone = judge(x2, bad2, f2, DT)
    assert v.robustness[1] == alone.robustness[0]


def test_robustness_is_negative_exactly_when_diverged():
    rng = np.random.default_rng(1)
    x, fr = _step_case()
    scale = np.abs(fr).max()
    for _ in range(40):
        fm = fr.copy()
        a = rng.integers(0, x.size - 10)
        n = rng.integers(1, 400)
        fm[a : a + n] += rng.uniform(-6, 6) * scale
        v = judge(x, fm, fr, DT)
        assert (v.robustness[0] < 0) == v.diverged[0]


def test_bad_shapes_are_refused_and_a_non_finite_reference_gives_no_verdict():
    with pytest.raises(DivergenceInputError, match="shape"):
        judge(np.zeros((10, 2)), np.zeros((10, 3)), np.zeros((10, 2)), DT)
    x = np.zeros((10, 2))
    fr = np.zeros((10, 2))
    fr[9, 0] = np.nan
    fm = np.full((10, 2), np.nan)  # the model is not finite either: it must not be blamed
    v = judge(x, fm, fr, DT)
    assert v.row(0)["reference_unusable"] and not v.diverged[0]
    assert not v.row(1)["reference_unusable"] and v.diverged[1]
    with pytest.raises(DivergenceInputError, match="lengths"):
        judge(np.zeros((10, 1)), np.zeros((10, 1)), np.zeros((10, 1)), DT, lengths=[11])


# ----- the control: nothing the search can produce flags the linear model or the reference ----
def _controls(axis):
    truth = RubberBushing.preset(axis, measurement=False)
    return truth, {
        "linear": LinearBushing.preset(axis),
        "reference": truth,
        "measured reference": RubberBushing.preset(axis, measurement=True, seed=4),
    }


@pytest.mark.parametrize("axis", ["axial", "radial"])
def test_controls_never_diverge_on_corner_and_random_profiles(axis):
    truth, controls = _controls(axis)
    rng = np.random.default_rng(11)
    profiles = []
    for name in RIG_FAMILIES:
        fam = FAMILIES[name]
        for corner in (0.0, 1.0):
            profiles.append(fam.profile(np.full(fam.dim, corner)))
        for _ in range(25):
            profiles.append(fam.profile(rng.random(fam.dim)))
    x, lengths = pad_batch(profiles)
    fr = truth.simulate(x)
    for name, model in controls.items():
        v = judge(x, model.simulate(x), fr, DT, lengths=lengths)
        assert not v.diverged.any(), (name, [v.row(b) for b in np.flatnonzero(v.diverged)][:3])


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    name=st.sampled_from(RIG_FAMILIES),
    u=st.lists(st.floats(0.0, 1.0), min_size=24, max_size=24),
    axis=st.sampled_from(["axial", "radial"]),
)
def test_linear_control_never_diverges_on_any_family_profile(name, u, axis):
    fam = FAMILIES[name]
    x = fam.profile(np.asarray(u[: fam.dim]))
    fr = RubberBushing.preset(axis, measurement=False).simulate(x)
    v = judge(x, LinearBushing.preset(axis).simulate(x), fr, DT)
    assert not v.diverged[0], v.row(0)
