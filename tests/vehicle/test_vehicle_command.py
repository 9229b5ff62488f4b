"""``bushenv vehicle``: the standard manoeuvres in HalfCar-v0, bushing kinds against the reference.

Short manoeuvres (1.5 s of a pothole and a step steer) with linear bushings: the table has its
structure, tells the reference's linearisation from a 2x stiff copy of it, is deterministic, and
says when a model car ended early instead of crashing."""

import json

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.models.base import velocity_of
from bushenv.models.planar_linear import PlanarLinear, fit_linear
from bushenv.reproduce import identification_records
from bushenv.rigs.halfcar_params import ENV_ID, PIVOT_ROTATION, REFERENCE
from bushenv.rigs.specs import spec_kwargs
from bushenv.vehicle.checks import VehicleInputError
from bushenv.vehicle.compare import OUTPUT_NAMES
from bushenv.vehicle.manoeuvres import NAMES, standard_manoeuvres
from bushenv.vehicle.report import markdown
from bushenv.vehicle.study import JUDGED, run_vehicle

DT = float(spec_kwargs(ENV_ID, {})["dt_s"])
SHORT = ("pothole", "step_steer")


@pytest.fixture(scope="module")
def linearisation() -> PlanarLinear:
    """The coupled reference's linearisation (the car's torsion set): least-squares K, C on
    its identification records (n = 1 and the wide peaks)."""
    hist = identification_records(DT, 0, 10.0, rotation=PIVOT_ROTATION)
    q = np.vstack([h[0] for h in hist])
    v = np.vstack([velocity_of(h[0], DT) for h in hist])
    return fit_linear(q, v, np.vstack([h[1] for h in hist]), DT)


@pytest.fixture(scope="module")
def short_report(linearisation):
    stiff = PlanarLinear(2 * linearisation.k_matrix, linearisation.c_matrix, dt=DT)
    bushings = {"linear": linearisation, "linear-2x-stiff": stiff}
    manoeuvres = standard_manoeuvres(DT, 0, SHORT, duration_s=1.5)
    return run_vehicle(manoeuvres, bushings, REFERENCE)


def test_every_manoeuvre_is_a_halfcar_input_within_its_limits():
    spec = spec_kwargs(ENV_ID, {})
    for m in standard_manoeuvres(DT, 0):
        road_step, _ = m.largest_steps()
        assert m.road_m.shape == (m.samples, 2) and m.lateral_accel_m_per_s2.shape == (m.samples,)
        assert np.abs(m.road_m).max() <= spec["max_road_height_m"]
        assert road_step <= spec["max_road_step_m"]
        assert np.abs(m.lateral_accel_m_per_s2).max() <= spec["max_lateral_accel_m_per_s2"]
    fishhook = standard_manoeuvres(DT, 0, ["fishhook"])[0]
    assert np.abs(fishhook.lateral_accel_m_per_s2).max() == pytest.approx(7.0, rel=2e-3)


def test_an_unknown_manoeuvre_is_refused_naming_the_known_ones():
    with pytest.raises(VehicleInputError, match="known: " + ", ".join(NAMES)):
        standard_manoeuvres(DT, 0, ["pothole", "slalom"])


def test_report_holds_every_output_and_coordinate_per_manoeuvre_and_kind(short_report):
    report, runs = short_report
    assert [(r["manoeuvre"], r["kind"]) for r in report["rows"]] == [
        (m, k) for m in SHORT for k in ("linear", "linear-2x-stiff")
    ]
    for row in report["rows"]:
        assert row["steps"] == row["samples"] == 307 and not row["end"]["reason"]
        assert set(OUTPUT_NAMES) < set(row["vehicle"])
        for name in OUTPUT_NAMES:
            assert {"peak_pct", "rms_pct", "baseline_peak", "baseline_rms"} <= set(
                row["vehicle"][name]
            )
        assert row["vehicle"]["a_w_Wk"]["baseline"] > 0
        assert row["vehicle"]["wheel_load"]["rms_pct"] is not None
        assert set(row["component"]["open_loop"]) == {"axial", "radial", "rotation"}
        assert row["transfer"] > 0
    assert [p["kind"] for p in report["pairs"]] == ["linear-2x-stiff"] * 2
    assert report["finding"]["status"] == "not judged"
    text = markdown(report)
    assert text.startswith("# ") and "not judged" in text and "| pothole | linear |" in text
    run = runs[("pothole", "linear")]
    assert run.deflection.shape == (307, 4, 3) and run.model["wheel_load"].shape == (307, 2)


def test_the_table_tells_the_linearisation_from_a_2x_stiff_bushing(short_report):
    report, _ = short_report
    for name in SHORT:
        lin, stiff = (r for r in report["rows"] if r["manoeuvre"] == name)
        for c in ("axial", "radial", "rotation"):
            assert stiff["component"]["open_loop"][c]["rms_pct"] > (
                1.5 * lin["component"]["open_loop"][c]["rms_pct"]
            )
        assert stiff["worst_judged_rms_pct"] > lin["worst_judged_rms_pct"]
        stated = [o for o in OUTPUT_NAMES if lin["vehicle"][o]["rms_pct"] is not None]
        larger = [
            o for o in stated if stiff["vehicle"][o]["rms_pct"] > lin["vehicle"][o]["rms_pct"]
        ]
        assert len(stated) >= 5 and len(larger) >= len(stated) - 1, (name, stated, larger)
        assert all(lin["vehicle"][o]["rms_pct"] < 20.0 for o in JUDGED), name


def test_a_bushing_equal_to_the_reference_gives_no_difference(linearisation):
    manoeuvres = standard_manoeuvres(DT, 0, ["pothole"], duration_s=1.0)
    report, _ = run_vehicle(manoeuvres, {"same": linearisation}, linearisation)
    row = report["rows"][0]
    for name in OUTPUT_NAMES:
        assert row["vehicle"][name]["peak_pct"] in (0.0, None)
    assert all(v["rms_pct"] == 0.0 for v in row["component"]["open_loop"].values())


def test_a_car_that_leaves_its_bounds_is_reported_not_raised():
    k = np.diag([-2.0e5, -1.0e6, -3.0e3])
    bad = PlanarLinear(k, np.zeros((3, 3)), dt=DT)
    manoeuvres = standard_manoeuvres(DT, 0, ["pothole"], duration_s=1.5)
    report, runs = run_vehicle(manoeuvres, {"negative": bad}, REFERENCE)
    row = report["rows"][0]
    assert row["end"]["reason"] and row["steps"] < row["samples"]
    assert "TERMINATED" in markdown(report)
    assert runs[("pothole", "negative")].steps == row["steps"]
    assert runs[("pothole", "reference")].steps == row["samples"]  # for the figures


def test_two_runs_give_the_same_numbers(short_report, linearisation):
    stiff = PlanarLinear(2 * linearisation.k_matrix, linearisation.c_matrix, dt=DT)
    again, _ = run_vehicle(
        standard_manoeuvres(DT, 0, SHORT, duration_s=1.5),
        {"linear": linearisation, "linear-2x-stiff": stiff},
        REFERENCE,
    )
    first = short_report[0]
    for a, b in zip(first["rows"], again["rows"], strict=True):
        assert json.dumps({**a, "seconds": 0}) == json.dumps({**b, "seconds": 0})
    assert json.dumps(first["pairs"]) == json.dumps(again["pairs"])


def test_command_writes_the_report_and_reuses_its_fitted_bushings(tmp_path, capsys):
    out = tmp_path / "veh"
    args = ["vehicle", "--out", str(out), "--manoeuvres", "pothole", "--duration-s", "1.0",
            "--kinds", "linear", "--identification-s", "5", "--quiet"]  # fmt: skip
    assert main(args) == 0
    first = json.loads((out / "report.json").read_text())
    assert (out / "report.md").read_text().startswith("# ")
    assert (out / "pothole.png").stat().st_size > 1000
    assert "identified now" in first["bushings"]["linear"]["how"]
    assert main([*args, "--no-plots"]) == 0
    second = json.loads((out / "report.json").read_text())
    assert "cached" in second["bushings"]["linear"]["how"]
    assert second["bushings"]["linear"]["sha256"] == first["bushings"]["linear"]["sha256"]
    assert second["rows"][0]["vehicle"] == first["rows"][0]["vehicle"]
    given = ["--linear", str(out / "bushings" / "linear.npz")]
    assert main([*args, "--no-plots", *given]) == 0
    third = json.loads((out / "report.json").read_text())
    assert third["bushings"]["linear"]["how"].startswith("given")
    assert third["rows"][0]["vehicle"] == first["rows"][0]["vehicle"]
    assert "not judged" in capsys.readouterr().out


def test_command_refuses_an_unknown_kind_and_a_file_for_a_kind_not_run(tmp_path, capsys):
    out = str(tmp_path / "x")
    assert main(["vehicle", "--out", out, "--kinds", "linear,spline", "--quiet"]) == 2
    assert "spline" in capsys.readouterr().err
    assert main(["vehicle", "--out", out, "--kinds", "linear", "--nn", "a.npz"]) == 2
    assert "--nn FILE given" in capsys.readouterr().err


# 3x: in seed 000's car (the upper pivots only) a 2x stiff copy of the linearisation on the
# records with the wide peaks differs by 4.95 % in camber, at the threshold; 3x by 6.8 %
@pytest.mark.parametrize(("scale", "status"), [(1.01, "reproduced"), (3.0, "refuted")])
def test_with_hybrid_and_linear_the_finding_is_judged_also_in_seed_000s_car(
    linearisation, scale, status
):
    near = PlanarLinear(scale * linearisation.k_matrix, linearisation.c_matrix, dt=DT)
    manoeuvres = standard_manoeuvres(DT, 0, ["pothole"], duration_s=1.5)
    report, runs = run_vehicle(manoeuvres, {"linear": linearisation, "hybrid": near}, REFERENCE)
    assert report["kinds"] == ["linear", "hybrid", "hybrid-upper"]
    assert set(runs) == {("pothole", k) for k in report["kinds"]}
    for finding in (report["finding"], report["finding_upper_only"]):
        assert finding["status"] == status
        assert set(finding["worst_by_output"]) <= {*JUDGED, "a_w_Wk"}
    assert (
        report["finding"]["worst"]["peak_pct"] >= report["finding_upper_only"]["worst"]["peak_pct"]
    )
    assert f"{status.upper()} with the hybrid in all four" in markdown(report)
