"""Exported FMUs in FMPy: valid, and the forces bushenv's own models give (docs/export.md)."""

import numpy as np
import pytest

from bushenv.models import PAPER_DT, get_model

from .fmu_masters import AXIS, converged, inputs, set_then_read

MODELS = ("linear", "nn", "hybrid", "boucwen")
VERSIONS = ("2.0", "3.0")
EXACT = 1e-9  # of the peak force: linear, nn, hybrid
BOUCWEN_VS_BUSHENV = 2e-3  # bushenv's kernel's stated error against a converged RK4
BOUCWEN_VS_CONVERGED = 1e-4  # the C's RK4 at 128 sub-steps against 512 (measured: < 3e-6)


def _reference(model_name, x, v):
    return get_model(model_name, axis=AXIS[model_name]).simulate(x, v)


def _signal(model_name, t, x, v):
    """The master's input: deflection and a connected velocity (which the FMU then uses)."""
    names = [("time", float), ("deflection", float), ("velocity", float)]
    return np.array(list(zip(t, x, v, strict=True)), dtype=names)


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model_name", MODELS)
def test_exported_fmu_passes_fmpy_validation(fmu, model_name, version):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu(model_name, version))) == []


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model_name", MODELS)
def test_simulate_fmu_at_the_sample_time_gives_bushenv_forces_one_step_late(
    fmu, model_name, version
):
    """FMPy's master reads outputs after doStep, before it sets the next input: the FMU then
    shows its latest sample whose input it knows, so FMPy's force at t_(k+1) is bushenv's F_k."""
    from fmpy import simulate_fmu

    dt = PAPER_DT
    for name, x in inputs().items():
        v = np.gradient(x, dt)
        t = np.arange(len(x)) * dt
        res = simulate_fmu(
            str(fmu(model_name, version)),
            stop_time=t[-1],
            output_interval=dt,
            input=_signal(model_name, t, x, v),
            output=["force"],
        )
        ref = _reference(model_name, x, v)
        err = np.max(np.abs(res["force"][1:] - ref[:-1])) / np.max(np.abs(ref))
        bound = BOUCWEN_VS_BUSHENV if model_name == "boucwen" else EXACT
        assert err <= bound, f"{name}: {err:.3g} of the peak"
        assert res["force"][0] == pytest.approx(ref[0], abs=bound * np.max(np.abs(ref)))


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model_name", ("nn", "hybrid"))
def test_simulate_fmu_at_a_step_of_2_5_samples_runs_the_model_on_the_interpolated_input(
    fmu, model_name, version
):
    """Between communication points the FMU interpolates the input linearly at its own samples:
    its force is bushenv's on that interpolated input (exactly), shown one step late."""
    from fmpy import simulate_fmu

    dt = PAPER_DT
    x = inputs()["random n=1"]
    v = np.gradient(x, dt)
    t = np.arange(len(x)) * dt
    h = 2.5 * dt
    res = simulate_fmu(
        str(fmu(model_name, version)),
        stop_time=t[-1],
        output_interval=h,
        input=_signal(model_name, t, x, v),
        output=["force"],
    )
    tc = res["time"]
    ts = np.arange(int(tc[-1] / dt + 1e-6) + 1) * dt
    xs, vs = (np.interp(ts, tc, np.interp(tc, t, a)) for a in (x, v))
    seen = _reference(model_name, xs, vs)
    latest = np.floor(tc[:-1] / dt + 1e-6).astype(int)  # the latest sample known at t_(j-1)
    err = np.max(np.abs(res["force"][1:] - seen[latest])) / np.max(np.abs(seen))
    assert err <= EXACT


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("model_name", MODELS)
def test_a_master_that_sets_then_reads_gets_the_force_on_time_at_variable_steps(
    fmu, model_name, version
):
    """Random communication steps (0.3 to 3.7 samples): the force read after setting the input
    at t is the model's at its latest sample <= t, on the input interpolated between points."""
    dt = PAPER_DT
    x = inputs()["random n=1"][:400]
    v = np.gradient(x, dt)
    t = np.arange(len(x)) * dt
    rng = np.random.default_rng(0)
    tc = np.concatenate([[0.0], np.cumsum(rng.uniform(0.3, 3.7, 300) * dt)])
    tc = tc[tc <= t[-1]]
    xc, vc = np.interp(tc, t, x), np.interp(tc, t, v)
    got = set_then_read(fmu(model_name, version), tc, xc, vc)
    ts = np.arange(int(tc[-1] / dt + 1e-6) + 1) * dt
    xs, vs = np.interp(ts, tc, xc), np.interp(ts, tc, vc)
    latest = np.floor(tc / dt + 1e-6).astype(int)
    if model_name == "boucwen":
        p = get_model("boucwen", axis="radial").vector()[:, None]
        seen = converged(p, xs[:, None], vs[:, None])[:, 0]
        bound = BOUCWEN_VS_CONVERGED
    else:
        seen = _reference(model_name, xs, vs)
        bound = EXACT
    err = np.max(np.abs(got - seen[latest])) / np.max(np.abs(seen))
    assert err <= bound


def test_shipped_nn_round_trip_loads_the_fmu_as_a_model_with_the_same_forces(fmu):
    x = inputs()["random n=1"]
    model = get_model(str(fmu("nn", "3.0")))
    assert model.dt == PAPER_DT
    ref = get_model("nn").simulate(x)
    both = model.simulate(np.stack([x, 0.5 * x], axis=1))
    assert np.max(np.abs(both[:, 0] - ref)) <= EXACT * np.max(np.abs(ref))
    assert np.max(np.abs(both[:, 1] - get_model("nn").simulate(0.5 * x))) <= EXACT * np.max(
        np.abs(ref)
    )


@pytest.mark.parametrize("model_name", ("nn", "hybrid"))
def test_fmi2_input_derivatives_give_the_force_on_time_even_read_before_the_next_input(
    fmu, model_name
):
    """A master that sets the inputs' slopes (canInterpolateInputs): the FMU extrapolates the
    input along them, so the force read right after doStep is the model's at that time."""
    from .fmu_masters import derivatives_then_step

    dt = PAPER_DT
    x = inputs()["random n=1"][:400]
    v = np.gradient(x, dt)
    t = np.arange(len(x)) * dt
    got = derivatives_then_step(fmu(model_name, "2.0"), t, x, v)
    ref = _reference(model_name, x, v)
    assert np.max(np.abs(got - ref[1:])) <= EXACT * np.max(np.abs(ref))


def test_fmpy_rebuilds_the_binary_from_the_sources_inside_with_the_same_forces(fmu, tmp_path):
    """The sources (FMI 2: listed in modelDescription; FMI 3: buildDescription.xml) are all a
    user needs: FMPy's own CMake build of them gives the same forces."""
    import zipfile

    from fmpy.build import build_platform_binary

    x = inputs()["random n=1"][:300]
    ref = get_model("nn").simulate(x)
    for version in VERSIONS:
        folder = tmp_path / version
        with zipfile.ZipFile(fmu("nn", version)) as zf:
            zf.extractall(folder, [n for n in zf.namelist() if not n.startswith("binaries/")])
        build_platform_binary(folder.resolve())
        rebuilt = tmp_path / f"rebuilt-{version}.fmu"
        with zipfile.ZipFile(rebuilt, "w") as zf:
            for p in folder.rglob("*"):
                if p.is_file():
                    zf.write(p, p.relative_to(folder).as_posix())
        got = get_model(str(rebuilt)).simulate(x)
        assert np.max(np.abs(got - ref)) <= EXACT * np.max(np.abs(ref))


def test_simulate_fmu_runs_the_papers_programme_as_bushenv_does(fmu):
    """Every record of the papers' programme through FMPy (hybrid, FMI 3.0), one step late."""
    from fmpy import simulate_fmu

    from bushenv.programmes import papers_programme

    model = get_model("hybrid")
    for item in papers_programme(PAPER_DT):
        x = item.x
        v = np.gradient(x, PAPER_DT)
        t = np.arange(len(x)) * PAPER_DT
        res = simulate_fmu(
            str(fmu("hybrid", "3.0")),
            stop_time=t[-1],
            output_interval=PAPER_DT,
            input=_signal("hybrid", t, x, v),
            output=["force"],
        )
        ref = model.simulate(x, v)
        err = np.max(np.abs(res["force"][1:] - ref[:-1])) / np.max(np.abs(ref))
        assert err <= EXACT, item.name


def test_an_fmu_stands_as_the_reference_too(fmu):
    from bushenv.models import get_reference

    ref = get_reference(str(fmu("linear", "2.0")))
    x = inputs()["sines"]
    want = get_model("linear").simulate(x)
    assert np.max(np.abs(ref.simulate(x) - want)) <= EXACT * np.max(np.abs(want))
