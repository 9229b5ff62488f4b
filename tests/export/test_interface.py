"""One FMU interface for every model kind: deflection in, force out, the velocity inside, in
co-simulation and model exchange, measured in the masters (docs/export.md)."""

import numpy as np
import pytest

from bushenv.models import PAPER_DT, get_model

from .fmu_masters import (
    AXIS,
    backward_velocity,
    converged,
    fmpy_simulate,
    held,
    inputs,
    libcosim,
    set_then_read,
)

KINDS = ("linear", "nn", "hybrid", "boucwen")
VERSIONS = ("2.0", "3.0")
SET_THEN_READ = 1e-6  # of the peak force: the set-then-read master against bushenv's force
EXACT = 1e-9  # of the peak force: linear, nn, hybrid in C against bushenv (measured: 0)
BOUCWEN_VS_CONVERGED = 1e-5  # the C's RK4 at 128 sub-steps against 512 (measured: < 3e-6)


def _bushenv(kind, x):
    """bushenv's force with the FMU's own velocity rule; Bouc-Wen: the converged run."""
    v = backward_velocity(x, PAPER_DT)
    if kind == "boucwen":
        p = get_model("boucwen", axis="radial").vector()[:, None]
        return converged(p, x[:, None], v[:, None])[:, 0], BOUCWEN_VS_CONVERGED
    return get_model(kind, axis=AXIS[kind]).simulate(x, v), EXACT


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("kind", KINDS)
def test_every_kind_has_the_same_inputs_and_outputs_in_both_forms(fmu, kind, version):
    from fmpy import read_model_description

    md = read_model_description(str(fmu(kind, version)))
    inputs_ = sorted(v.name for v in md.modelVariables if v.causality == "input")
    outputs = sorted(v.name for v in md.modelVariables if v.causality == "output")
    assert inputs_ == ["deflection", "velocity"]
    assert outputs == ["force", "in_flagged_range", "outside_envelope", "time_outside_envelope_s"]
    assert md.coSimulation is not None and md.modelExchange is not None
    assert md.numberOfContinuousStates == 0
    assert md.version == "2"  # the interface version: docs/export.md


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("per_sample", (1, 10))
def test_a_set_then_read_master_setting_only_the_deflection_gets_bushenv_force(
    fmu, kind, version, per_sample
):
    """No velocity input: the FMU's backward difference, as the rigs feed their models. At
    h = dt and dt/10 the force read is bushenv's held over each sample."""
    x = inputs()["random n=1"][:300]
    want, _ = _bushenv(kind, x)
    h = PAPER_DT / per_sample
    tc = np.arange((len(x) - 1) * per_sample + 1) * h
    got = set_then_read(fmu(kind, version), tc, np.interp(tc, np.arange(len(x)) * PAPER_DT, x))
    err = np.max(np.abs(got - held(want, tc, PAPER_DT))) / np.max(np.abs(want))
    assert err <= (BOUCWEN_VS_CONVERGED if kind == "boucwen" else SET_THEN_READ)


@pytest.mark.parametrize("kind", ("hybrid", "boucwen"))
def test_the_backward_difference_is_not_the_central_one_and_the_fmu_says_which_it_uses(fmu, kind):
    """The FMU's own velocity differs from simulate's default (central): the FMU's force is
    bushenv's with the backward one, and is not bushenv's with the central one."""
    x = inputs()["4 mm step"][:300]
    t = np.arange(len(x)) * PAPER_DT
    got = set_then_read(fmu(kind, "2.0"), t, x)
    model = get_model(kind, axis=AXIS[kind])
    backward = model.simulate(x, backward_velocity(x, PAPER_DT))
    central = model.simulate(x)
    peak = np.max(np.abs(backward))
    assert np.max(np.abs(got - backward)) <= 2e-3 * peak
    assert np.max(np.abs(got - central)) >= 0.05 * peak


def test_a_velocity_set_only_as_a_start_value_does_not_replace_the_fmus_own(fmu):
    """FMPy applies start values before initialisation ends: that is not a connection."""
    from fmpy import simulate_fmu

    x = inputs()["random n=1"][:300]
    t = np.arange(len(x)) * PAPER_DT
    signal = np.array(list(zip(t, x, strict=True)), dtype=[("time", float), ("deflection", float)])
    res = simulate_fmu(
        str(fmu("linear", "3.0")),
        stop_time=t[-1],
        output_interval=PAPER_DT,
        start_values={"velocity": 0.0},
        input=signal,
        output=["force"],
    )
    want, _ = _bushenv("linear", x)
    assert np.max(np.abs(res["force"][1:] - want[:-1])) <= EXACT * np.max(np.abs(want))


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("kind", KINDS)
def test_model_exchange_in_fmpy_gives_bushenv_force_at_the_samples(fmu, kind, version):
    """FMPy's ``simulate_fmu`` in model exchange (CVode; each sample a time event), output at
    a quarter of the sample time: at every sample the force is bushenv's."""
    x = inputs()["random n=1"][:200]
    t = np.arange(len(x)) * PAPER_DT
    want, bound = _bushenv(kind, x)
    tc, got = fmpy_simulate(fmu(kind, version), t, x, PAPER_DT / 4, "ModelExchange")
    on = np.abs(tc / PAPER_DT - np.round(tc / PAPER_DT)) < 1e-6
    assert on.sum() == len(x)
    err = np.max(np.abs(got[on] - want)) / np.max(np.abs(want))
    assert err <= bound


def test_model_exchange_between_samples_is_continuous_and_linear_for_the_linear_model(fmu):
    """Between samples n and n+1 the force is (1 - a) F_n(x(t)) + a F_(n+1)(x(t)), a direct
    function of the current deflection; for the linear model and an input linear between
    samples (FMPy interpolates it so) that is bushenv's forces interpolated linearly."""
    x = inputs()["sines"][:120]
    t = np.arange(len(x)) * PAPER_DT
    tc, got = fmpy_simulate(fmu("linear", "2.0"), t, x, PAPER_DT / 4, "ModelExchange")
    want, _ = _bushenv("linear", x)
    assert np.max(np.abs(got - np.interp(tc, t, want))) <= 1e-9 * np.max(np.abs(want))


def test_libcosim_sets_steps_then_reads_and_gets_bushenv_force_one_step_late(fmu):
    """libcosim (FMI Library) sets the input, calls doStep, then reads: the force after the
    step from t_k is bushenv's of sample k (the nanosecond rounding of dt moves it slightly)."""
    pytest.importorskip("libcosimpy")
    x = inputs()["random n=1"][:400]
    t = np.arange(len(x)) * PAPER_DT
    want, _ = _bushenv("hybrid", x)
    tc, got = libcosim(fmu("hybrid", "2.0"), t, x, PAPER_DT)
    assert len(got) >= len(x) - 2
    assert np.max(np.abs(got - want[: len(got)])) <= 1e-4 * np.max(np.abs(want))
