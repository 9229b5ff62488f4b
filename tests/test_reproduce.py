"""bushenv reproduce: the report holds every figure of the tables, and refuses to overwrite;
``--planar``: the three-axis table beside seed 000 Table 3, apart from report.json."""

import json

import numpy as np
import pytest

import bushenv.reproduce as r3
from bushenv.cli import main
from bushenv.identify import fit
from bushenv.metrics import rms_ratio
from bushenv.models.base import PAPER_DT
from bushenv.records import Record
from bushenv.reference.planar import PlanarRubber


def _records(pairs):
    return [Record.from_arrays(q, f, PAPER_DT) for q, f in pairs]


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("repro")
    code = main(
        [
            "reproduce",
            "--out",
            str(out),
            "--axes",
            "radial",
            "--shipped",
            "--identification-s",
            "6.44",
            "--verification-s",
            "6.44",
        ]
    )
    assert code == 0
    return out


def test_report_json_holds_every_table_figure(quick_report):
    report = json.loads((quick_report / "report.json").read_text())
    for name in ("linear", "nn", "hybrid", "boucwen"):
        row = report["radial"][name]
        for key in ("rms_ratio", "esr", "max_error", "peak_error", "identification_s"):
            assert isinstance(row[key], float), (name, key)
        assert 0.0 < row["rms_ratio"] < 1.0
        # judged on an unseen record of the training amplitude too (the papers' protocol)
        assert 0.0 < row["same_amplitude"]["rms_ratio"] < 1.0
        assert row["same_amplitude"]["rms_ratio"] != row["rms_ratio"]
        assert row["verification_s"] > 0.0
        step = report["step"]["radial"][name]
        assert isinstance(step["bounded"], bool)
        assert step["departure_s"] is None or step["departure_s"] > 0
    assert report["paper"]["table2"]["axial"]["nn"] == [5.1, 7.7]
    k = report["radial"]["linear"]["linear_fit"]["k_n_per_mm"]
    assert 1000 < k < 2500  # near seed 000 Table 1 (1518.73 N/mm)


def test_report_writes_plots_and_markdown(quick_report):
    for name in ("radial_force_vs_time.png", "radial_loops.png", "radial_step.png", "report.md"):
        assert (quick_report / name).stat().st_size > 1000


def test_existing_report_is_not_overwritten(quick_report, capsys):
    code = main(["reproduce", "--out", str(quick_report), "--axes", "radial", "--shipped"])
    assert code == 2
    assert "exists; pass --force" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--seed", "-1"], "--seed must be >= 0"),
        (["--identification-s", "1"], "--identification-s must be at least 6.44 s"),
        (["--axes", "vertical"], "unknown axis 'vertical'"),
    ],
)
def test_bad_arguments_are_refused_before_measuring(tmp_path, capsys, argv, message):
    code = main(["reproduce", "--out", str(tmp_path / "r"), *argv])
    assert code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


# ----- the three-axis table --------------------------------------------------------------------
def test_planar_only_writes_its_own_report_and_the_table_beside_table3(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.setattr(r3, "COUPLED_MODELS", ("linear",))
    args = ["reproduce", "--planar", "only", "--identification-s", "8", "--verification-s", "7"]
    assert main([*args, "--out", str(tmp_path), "--quiet"]) == 0
    assert not (tmp_path / "report.json").exists()  # the papers' report (and its golden) untouched
    report = json.loads((tmp_path / "planar.json").read_text())
    assert list(report["records"]) == list(r3.unseen_records(PAPER_DT, 0, 7.0))
    row = report["records"]["random correlated n=1"]["linear"]
    assert set(row) == {"axial", "radial", "rotation"}
    assert report["records"]["radial preload + rotation sweep"]["linear"]["axial"]["at_rest"]
    out = capsys.readouterr().out
    assert "seed 000 Table 3                 axial               10.9 / 24.9" in out
    # the JSON is what the models do: recompute linear's radial RMS ratio on one record
    lin = fit(_records(r3.identification_records(PAPER_DT, 0, 8.0)), "linear", progress=False)
    qt = r3.unseen_records(PAPER_DT, 0, 7.0)["random correlated n=1"]
    ft = PlanarRubber.preset(seed=101).simulate(qt)
    want = rms_ratio(ft[:, 1], lin.model.simulate(qt)[:, 1])
    assert np.isclose(row["radial"]["rms_ratio"], want, rtol=1e-12)
    assert main([*args, "--out", str(tmp_path), "--quiet"]) == 2  # planar.json exists, no --force


def test_the_table_carries_what_the_fits_could_not_identify(tmp_path, monkeypatch, capsys):
    """The random records have no motion below 1 Hz: the Bouc-Wen fit's 1 s relaxation branch
    cannot be told from its static stiffness, and the table says so as the card would. The
    programme's sets hold each coordinate in turn, and the warning is gone."""
    from bushenv.identify.vector_boucwen import VectorBoucWenOptions

    monkeypatch.setattr(r3, "COUPLED_MODELS", ("linear", "boucwen"))
    short = VectorBoucWenOptions(10, time_limit_s=0.0)  # the search's length changes nothing here
    monkeypatch.setattr(r3, "fit", lambda h, name, _, seed, progress: fit(
        h, name, short if name == "boucwen" else None, seed, progress))  # fmt: skip
    args = ["reproduce", "--planar", "only", "--identification-s", "8", "--verification-s", "7"]
    random = ["--planar-identification", "random", "--out", str(tmp_path / "random"), "--quiet"]
    assert main([*args, *random]) == 0
    report = json.loads((tmp_path / "random" / "planar.json").read_text())
    assert list(report["fit_notes"]) == ["boucwen"]  # the linear fit has none
    (said,) = report["fit_notes"]["boucwen"]
    assert said.startswith("relaxation warning:") and "1 s" in said
    assert f"boucwen: {said}" in capsys.readouterr().out
    assert main([*args, "--out", str(tmp_path / "programme"), "--quiet"]) == 0
    assert json.loads((tmp_path / "programme" / "planar.json").read_text())["fit_notes"] == {}


def test_the_programme_identification_adds_the_n1_coupled_sets_and_random_leaves_them_out():
    programme = r3.identification_records(PAPER_DT, 0, 8.0)
    random = r3.identification_records(PAPER_DT, 0, 8.0, "random")
    assert len(random) == 2 and len(programme) == 5
    for (q, f), (q0, f0) in zip(programme[:2], random, strict=True):
        assert np.array_equal(q, q0) and np.array_equal(f, f0)  # the random records unchanged
    radial_held, rotation_held, axial_held = (q for q, _ in programme[2:])
    assert radial_held.shape[0] == int(round(4.0 / PAPER_DT))  # half the random records' length
    assert radial_held[-1, 1] == pytest.approx(2e-3) and rotation_held[-1, 2] == pytest.approx(0.05)
    assert axial_held[-1, 0] == pytest.approx(2e-3) and np.all(axial_held[:, 2] == 0)
    with pytest.raises(ValueError, match="identification 'sweeps'"):
        r3.identification_records(PAPER_DT, 0, 8.0, "sweeps")


def test_the_table_says_what_it_was_identified_on(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(r3, "COUPLED_MODELS", ("linear",))
    args = ["reproduce", "--planar", "only", "--identification-s", "8", "--verification-s", "7"]
    assert (
        main([*args, "--planar-identification", "random", "--out", str(tmp_path), "--quiet"]) == 0
    )
    report = json.loads((tmp_path / "planar.json").read_text())
    assert report["settings"]["identification"] == "random"
    assert "identified on random n = 1 only (as seed 000)" in capsys.readouterr().out


@pytest.mark.slow
def test_hybrid_bw_meets_the_target_on_unseen_random_coupled_records():
    # docs/planar.md, "The 3-axis table in bushenv reproduce": seed 0, default options and the
    # programme's identification (random and the coupled sets at n = 1; about 5 min). Not on the
    # preload sets: radial 4.3-5.0 % RMS there, as the docs say
    report = r3.coupled_table(0, 40.0, 20.0, PAPER_DT, models=("hybrid-bw",))
    for rec, row in report["records"].items():
        if rec.startswith("random"):
            for axis, m in row["hybrid-bw"].items():
                assert m["rms_ratio"] <= 0.03 and m["max_error_ratio"] <= 0.06, (rec, axis, m)


def test_the_table_says_whether_the_hybrid_kept_its_network(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(r3, "COUPLED_MODELS", ("hybrid",))
    short = {"hidden": 9, "teacher_steps": 50, "free_run_steps": 25, "windows": 8, "window": 32}
    monkeypatch.setattr(r3, "fit", lambda h, name, _, seed, progress: fit(
        h, name, short, seed, progress))  # fmt: skip
    args = ["reproduce", "--planar", "only", "--identification-s", "8", "--verification-s", "7"]
    assert main([*args, "--out", str(tmp_path), "--quiet"]) == 0
    (said,) = json.loads((tmp_path / "planar.json").read_text())["fit_notes"]["hybrid"]
    assert said.startswith(("network: kept: ", "network: DROPPED")) and "backbone alone" in said
    assert f"hybrid: {said}" in capsys.readouterr().out


def test_the_unseen_records_are_the_programmes_one_list():
    from bushenv.motions import verification_motions

    unseen = r3.unseen_records(PAPER_DT, 2, 7.0)
    listed = verification_motions(PAPER_DT, 2, 1.5, 7.0)
    assert np.array_equal(unseen["random correlated n=1.5"], listed["random correlated"])
    for name in ("random correlated n=1", *(k for k in listed if not k.startswith("random"))):
        assert np.array_equal(unseen[name], listed[name]), name
    axial = listed["axial preload + radial sweep"]
    assert axial[-1, 0] == pytest.approx(3e-3) and np.all(axial[:, 2] == 0)
