"""Three-axis models as FMUs: three inputs (axial, radial, rotation), three outputs (force_axial,
force_radial, moment), checked in FMPy against ``model.simulate`` as the one-axis FMUs are."""

import numpy as np
import pytest

from bushenv.models import PAPER_DT, get_model

from .fmu_masters import backward_velocity, fmpy_simulate, held, set_then_read

VERSIONS = ("2.0", "3.0")
# The planar network kernel lets numba fuse multiply-adds where it chooses; the C does not:
# bushenv's forces to rounding (measured: at most 5e-13 of each coordinate's peak).
ROUNDING = 1e-9


def _model(kind):
    from bushenv.models.planar_narx import PlanarHybrid, PlanarNarx, PlanarNarxPerAxis

    made = {
        "linear": lambda: get_model("linear", coords=3),
        "nn": lambda: PlanarNarx.untrained(seed=1),
        "nn-axis": lambda: PlanarNarxPerAxis.untrained(seed=3),
        "hybrid": lambda: PlanarHybrid.untrained(seed=2),
    }
    return made[kind]()


@pytest.fixture(scope="module")
def fmu3(tmp_path_factory):
    from bushenv.export import export_fmu

    folder = tmp_path_factory.mktemp("fmus3")
    made = {}

    def get(kind, version):
        if (kind, version) not in made:
            out = folder / f"{kind}-{version}.fmu"
            # the untrained networks fail their certificates: carried, not refused
            made[kind, version] = export_fmu(_model(kind), out, version, allow_failing=True).path
        return made[kind, version]

    return get


def _motion(n=300):
    """Axial, radial, rotation: sines of their own periods plus a little noise, (T, 3)."""
    t = np.arange(n) * PAPER_DT
    rng = np.random.default_rng(0)
    return np.stack(
        [
            1e-3 * np.sin(2 * np.pi * 3.0 * t) + 2e-4 * rng.standard_normal(n),
            2e-3 * np.sin(2 * np.pi * 1.3 * t),
            0.05 * np.sin(2 * np.pi * 2.1 * t),
        ],
        axis=1,
    )


def _bushenv(kind, q):
    return _model(kind).simulate(q, backward_velocity(q, PAPER_DT))


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("kind", ("linear", "nn", "hybrid"))
def test_a_three_axis_fmu_is_valid_and_has_three_inputs_and_three_outputs(fmu3, kind, version):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    path = fmu3(kind, version)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    by = {c: [v.name for v in md.modelVariables if v.causality == c] for c in ("input", "output")}
    assert by["input"][:3] == ["deflection_axial", "deflection_radial", "rotation"]
    assert by["input"][3:] == ["velocity_axial", "velocity_radial", "rotation_rate"]
    assert by["output"][:3] == ["force_axial", "force_radial", "moment"]
    units = {v.name: v.declaredType or v.unit for v in md.modelVariables}
    assert units["rotation"] == "rad" and units["moment"] == "N.m"


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("kind", ("linear", "nn", "nn-axis", "hybrid"))
@pytest.mark.parametrize("per_sample", (1, 10))
def test_a_set_then_read_master_gets_the_three_axis_models_forces(fmu3, kind, version, per_sample):
    q = _motion()
    want = _bushenv(kind, q)
    h = PAPER_DT / per_sample
    tc = np.arange((len(q) - 1) * per_sample + 1) * h
    t = np.arange(len(q)) * PAPER_DT
    qc = np.stack([np.interp(tc, t, q[:, i]) for i in range(3)], axis=1)
    got = set_then_read(fmu3(kind, version), tc, qc)
    err = np.max(np.abs(got - held(want, tc, PAPER_DT)), axis=0) / np.max(np.abs(want), axis=0)
    assert np.all(err <= ROUNDING), err


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("kind", ("linear", "hybrid"))
def test_fmpy_simulates_the_three_axis_fmu_in_both_forms(fmu3, kind, version):
    """Co-simulation: the force one step late (FMPy reads after doStep); model exchange: the
    model's forces at every sample."""
    q = _motion(200)
    t = np.arange(len(q)) * PAPER_DT
    want = _bushenv(kind, q)
    peak = np.max(np.abs(want), axis=0)
    _, co = fmpy_simulate(fmu3(kind, version), t, q, PAPER_DT)
    assert np.all(np.max(np.abs(co[1:] - want[:-1]), axis=0) <= ROUNDING * peak)
    tc, me = fmpy_simulate(fmu3(kind, version), t, q, PAPER_DT / 2, "ModelExchange")
    on = np.abs(tc / PAPER_DT - np.round(tc / PAPER_DT)) < 1e-6
    assert np.all(np.max(np.abs(me[on] - want), axis=0) <= ROUNDING * peak)


def test_the_cli_exports_a_three_axis_preset_and_refuses_a_kind_without_c(tmp_path, capsys):
    from bushenv.cli import main

    out = tmp_path / "l3.fmu"
    assert main(["export", "linear", "--axes", "3", "--out", str(out)]) == 0
    assert out.is_file()
    err = capsys.readouterr().err  # one text over C: the ports and each coordinate's envelope
    assert (
        "deflection_axial, deflection_radial, rotation in; force_axial, force_radial, moment out"
        in err
    )
    assert "|x_radial| <= 12.5 mm, |dx_radial/dt| <= 1.257 m/s, |theta| <= 150 mrad" in err
    assert main(["export", "boucwen", "--axes", "3", "--out", str(tmp_path / "b3.fmu")]) == 2
    err = capsys.readouterr().err
    assert "exportable kinds over 3 coordinates: linear, nn, nn-axis, hybrid" in err


def test_a_three_axis_file_carries_its_cards_envelope_and_the_flags_move_its_translations(
    tmp_path,
):
    """As for one axis: the card's training records' largest |q| and |dq/dt| per coordinate;
    --stroke-mm and --velocity-m-per-s replace the translations' (a rotation keeps its
    card's)."""
    from bushenv.cli import main
    from bushenv.export import export_fmu
    from bushenv.identify.card import load_card

    rec = tmp_path / "rec"
    assert main(["measure", "--axes", "3", "--programme", "random", "--duration", "6",
                 "--out", str(rec), "--quiet"]) == 0  # fmt: skip
    model = tmp_path / "lin3.npz"
    assert main(["fit", str(sorted(rec.glob("*.csv"))[0]), "--model", "linear", "--out",
                 str(model), "--no-plots", "--quiet"]) == 0  # fmt: skip
    train = [r for r in load_card(model).data["records"] if r["role"] == "train"]
    coords = ("axial", "radial", "rotation")
    peak = [max(r["peak_deflection"][c] for r in train) for c in coords]
    rate = [max(r["peak_rate"][c] for r in train) for c in coords]
    assert 0 < peak[2] < 0.15 and 0 < peak[0] < 12.5e-3  # inside the machine's, not it

    env = export_fmu(str(model), tmp_path / "a.fmu").facts.envelope
    assert env.limits(3) == (pytest.approx(peak), pytest.approx(rate))
    assert "training records of lin3.card.json" in env.source
    env = export_fmu(str(model), tmp_path / "b.fmu", stroke_m=2e-3, velocity_m_per_s=0.1)
    strokes, rates = env.facts.envelope.limits(3)
    assert strokes == pytest.approx([2e-3, 2e-3, peak[2]])
    assert rates == pytest.approx([0.1, 0.1, rate[2]])


def test_a_rotation_beyond_the_machines_range_is_flagged_and_logged_naming_it(fmu3):
    """Only the rotation leaves the envelope (a ramp to 0.2 rad, the machine's range 0.15)."""
    from fmpy import simulate_fmu

    n = 300
    t = np.arange(n) * PAPER_DT
    theta = np.concatenate([np.linspace(0, 0.2, n // 2), np.linspace(0.2, 0, n - n // 2)])
    q = np.stack([np.zeros(n), np.zeros(n), theta], axis=1)
    messages = []
    set_then_read(fmu3("linear", "3.0"), t, q, log=lambda *a: messages.append(a[3]))
    entries = [m for m in messages if b"leaves the bushing's validity envelope" in m]
    assert len(entries) == 1 and b"rotation beyond the fitted stroke" in entries[0]
    sig = np.array(
        list(zip(t, *q.T, strict=True)),
        dtype=[("time", float), ("deflection_axial", float), ("deflection_radial", float),
               ("rotation", float)],
    )  # fmt: skip
    res = simulate_fmu(
        str(fmu3("linear", "3.0")),
        stop_time=t[-1],
        output_interval=PAPER_DT,
        input=sig,
        output=["outside_envelope", "time_outside_envelope_s"],
    )
    outside = np.abs(theta) > 0.15
    assert np.array_equal(res["outside_envelope"][1:], outside[:-1])
    assert res["time_outside_envelope_s"][-1] == pytest.approx(outside[:-1].sum() * PAPER_DT)


def test_connected_velocities_replace_the_fmus_own_per_coordinate(fmu3):
    q = _motion(200)
    t = np.arange(len(q)) * PAPER_DT
    v = np.gradient(q, PAPER_DT, axis=0)  # simulate's default, the central difference
    want = _model("linear").simulate(q, v)
    got = set_then_read(fmu3("linear", "2.0"), t, q, v)
    assert np.all(np.max(np.abs(got - want), axis=0) <= ROUNDING * np.max(np.abs(want), axis=0))
