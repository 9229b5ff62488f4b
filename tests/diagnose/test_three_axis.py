"""The diagnosis on three-axis records: which coordinate, which effect, how far it shrinks.

Cases: the coupled reference rubber with one effect on one coordinate
(``bushenv.diagnose.validation.three_axis_cases``, the study's fast subset)."""

import csv
import json
from functools import cache

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.diagnose.coordinate_answer import unit_keys
from bushenv.diagnose.errors import DiagnoseError
from bushenv.diagnose.fit import diagnose
from bushenv.diagnose.validation.three_axis_cases import (
    FAST,
    get_spec,
    make_case,
    reference,
    score,
)
from bushenv.record_files import save_columns
from bushenv.records import Record, save_csv


@cache
def case(name: str, seed: int = 0):
    train, test = make_case(name, seed)
    return train, test, diagnose(train, [test])


@pytest.mark.parametrize("name", FAST)
def test_withheld_effect_is_named_on_its_coordinate(name):
    _, _, result = case(name)
    got = score(result, name)
    assert got["hit"], got
    assert got["false_coordinates"] == []  # no effect named where none acts
    spec = get_spec(name)
    if spec.coords:
        assert result["coordinate"] == spec.coords[0]
        assert result["shrink"] > 0.2  # the gap shrinks once the effect is added
        assert result["coordinates_carrying_gap"] == [spec.coords[0]]
    else:
        assert result["coordinate"] is None and result["shrink"] == 0.0


def test_elastic_coupling_is_named_with_its_partner_coordinate():
    _, _, result = case("coupling")
    assert score(result, "coupling")["hit"]
    row = next(r for r in result["coordinates"] if r["coordinate"] == "axial")
    # no one-axis candidate holds it; the terms axial x radial^2 close it
    assert row["effect_one_axis"] == "outside_candidates"
    assert row["effect"] == "coupling" and row["coupled_to"] == ["radial"]
    assert row["coupling"]["closes"] > 0.8 and row["shrink"] > 0.5
    assert result["answer"] == "axial: coupling (to radial)"
    i = result["coords"].index("axial")  # the augmented predictions are the coupled fit's
    f = np.concatenate([p["force_measured"][:, i] for p in result["predictions"]])
    aug = np.concatenate([p["force_augmented"][:, i] for p in result["predictions"]])
    assert np.sqrt(np.mean((f - aug) ** 2) / np.mean(f**2)) == pytest.approx(row["gap_after"])


def test_coupling_is_not_named_where_a_candidate_explains_the_gap():
    _, _, result = case("friction@radial")
    row = next(r for r in result["coordinates"] if r["coordinate"] == "radial")
    assert row["coupled_to"] == [] and row["coupling"]["closes"] < 0.2


def test_coordinates_are_ranked_by_their_gap_with_units():
    _, _, result = case("friction@radial")
    rows = result["coordinates"]
    assert [r["coordinate"] for r in rows][0] == "radial"
    gaps = [r["gap_before"] for r in rows]
    assert gaps == sorted(gaps, reverse=True)
    units = {r["coordinate"]: (r["unit"], r["force_unit"]) for r in rows}
    assert units == {"axial": ("m", "N"), "radial": ("m", "N"), "rotation": ("rad", "N m")}
    assert sum(r["share_above_noise"] for r in rows) == pytest.approx(1.0)
    assert rows[0]["share_above_noise"] > 0.95


def test_gaps_are_recomputed_from_the_three_axis_predictions():
    _, _, result = case("friction@radial")
    i = result["coords"].index("radial")
    f = np.concatenate([p["force_measured"][:, i] for p in result["predictions"]])
    base = np.concatenate([p["force_baseline"][:, i] for p in result["predictions"]])
    aug = np.concatenate([p["force_augmented"][:, i] for p in result["predictions"]])
    rms = lambda a: np.sqrt(np.mean(a**2))  # noqa: E731
    assert rms(f - base) / rms(f) == pytest.approx(result["gap_before"], rel=1e-12)
    assert rms(f - aug) / rms(f) == pytest.approx(result["gap_after"], rel=1e-12)


def test_rotation_parameters_carry_rotation_units():
    _, _, result = case("relaxation@rotation")
    params = result["diagnoses"]["rotation"]["parameters"]
    assert "k_nm_per_rad" in params and "c_nms_per_rad" in params
    assert "k_n_per_m" in result["diagnoses"]["radial"]["parameters"]
    assert unit_keys({"slip_force_n": 1, "slip_length_m": 2, "mass_kg": 3}, "rad", "N m") == {
        "slip_force_nm": 1,
        "slip_length_rad": 2,
        "inertia_kg_m2": 3,
    }


def test_a_coordinate_held_still_in_a_record_is_left_out_of_its_diagnosis_only():
    from bushenv.motions import preload_sweep
    from bushenv.reference.planar import PlanarRubber

    train, test, _ = case("friction@radial")
    overrides, effects = reference(get_spec("friction@radial"), 0)
    q = preload_sweep(2, 0.075, 3e-3, 10.0, train.dt)  # rotation held, radial swept, axial at 0
    f = PlanarRubber.preset(effects=effects, seed=7, dt=train.dt, **overrides).simulate(q)
    sweep = Record(np.arange(len(q)) * train.dt, q, f.reshape(q.shape), "sweep")
    result = diagnose(train, [test, sweep])
    assert (result["coordinate"], result["effect"]) == ("radial", "friction")
    rows = {r["coordinate"]: r for r in result["coordinates"]}
    assert rows["axial"]["left_out"] == ["sweep"] and rows["radial"]["left_out"] == []
    assert result["records"]["per_coordinate"]["axial"] == ["train", "test"]
    alone = diagnose(train, [sweep])  # no TEST moves axially: axial is not diagnosed
    assert alone["effects"]["axial"] == "not_diagnosed" and "axial" not in alone["diagnoses"]
    assert alone["coordinate"] == "radial"


def test_other_baselines_and_mixed_records_are_refused_by_the_library():
    train, test, _ = case("none")
    with pytest.raises(DiagnoseError, match="linear 3-coordinate baseline"):
        diagnose(train, [test], baseline="nn", cross=False)
    one = Record.from_arrays(train.q[:, 0], train.f[:, 0], train.dt, name="one")
    with pytest.raises(DiagnoseError, match="TEST one has 1 coordinate"):
        diagnose(train, [one])
    two = [Record(r.time, r.q[:, :2], r.f[:, :2], n) for r, n in ((train, "a"), (test, "b"))]
    with pytest.raises(DiagnoseError, match="records of 2 coordinates: .* for 1, 3 coordinate"):
        diagnose(two[0], [two[1]])  # generic over C: refused only for want of a linear form


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    root = tmp_path_factory.mktemp("three_axis")
    train, test, _ = case("friction@radial")
    for name, rec in (("train3", train), ("test3", test)):
        save_columns(root / f"{name}.csv", rec.time, rec.q, rec.f)
    one = Record.from_arrays(train.q[:, 1], train.f[:, 1], train.dt, name="one")
    save_csv(one, root / "one_axis.csv")
    return root


def test_command_writes_the_report_per_coordinate(files, capsys):
    out = files / "out"
    code = main(["diagnose", str(files / "train3.csv"), str(files / "test3.csv"), "--out",
                 str(out)])  # fmt: skip
    assert code == 0
    assert "coordinate radial, effect friction" in capsys.readouterr().err
    report = json.loads((out / "report.json").read_text())
    assert (report["coordinate"], report["effect"]) == ("radial", "friction")
    assert report["diagnoses"] == {c: f"{c}/report.json" for c in ("axial", "radial", "rotation")}
    assert "coordinates.png" in report["plots"]
    for c in ("axial", "radial", "rotation"):
        sub = json.loads((out / c / "report.json").read_text())
        assert sub["coordinate"] == c and (out / c / "report.md").is_file()
        assert (out / c / "loops_test3.png").is_file()
    assert json.loads((out / "radial" / "report.json").read_text())["effect"] == "friction"
    with open(out / "predictions" / "test3.csv") as fh:
        head = next(csv.reader(fh))
    assert (
        head[0] == "time" and "force_augmented_radial" in head and "force_measured_rotation" in head
    )
    md = (out / "report.md").read_text()
    assert "**radial: friction**" in md and "rad, N m" in md


def test_mixed_record_files_are_refused_naming_both(files, capsys):
    code = main(["diagnose", str(files / "train3.csv"), str(files / "one_axis.csv"), "--out",
                 str(files / "mixed")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2
    assert "train3.csv is a three-axis record but" in err and "one_axis.csv is a one-axis" in err
    assert not (files / "mixed").exists()


def test_a_run_order_reaches_every_coordinates_diagnosis():
    train, test = make_case(FAST[0], 0)
    order = [(train.name, None), (test.name, 60.0)]
    result = diagnose(train, [test], run_order=order)
    for d in result["diagnoses"].values():
        assert d["records"]["sessions"] == [[train.name, test.name]]
    with pytest.raises(DiagnoseError, match="run order row 1: no record named 'nope'"):
        diagnose(train, [test], run_order=[("nope", None)])
