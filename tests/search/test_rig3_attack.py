"""``bushenv attack --env rig3``: the one attack on a three-axis model end to end, its cases
replaying."""

import json

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.models.planar_linear import PlanarLinear
from bushenv.search.corpus import case_files, check, load_case


def _rotation_active(path):
    """The planar Table-1 model with negative damping in the rotation only, saved."""
    ref = PlanarLinear.preset()
    c = ref.c_matrix.copy()
    c[2, 2] *= -0.5
    return PlanarLinear(ref.k_matrix, c, ref.dt).save(path)


def test_a_planar_attack_finds_shrinks_and_keeps_the_axis_that_fails(tmp_path, capsys):
    model = _rotation_active(tmp_path / "active.npz")
    out, corpus = tmp_path / "run", tmp_path / "corpus"
    argv = ["attack", "--env", "rig3", "--model", str(model), "--budget", "24", "--quiet",
            "--reference", "rubber", "--searchers", "random", "--out", str(out),
            "--max-shrink", "1", "--shrink-budget", "60", "--save",
            "--corpus", str(corpus)]  # fmt: skip
    assert main(argv) == 0
    report = json.loads((out / "report.json").read_text())
    search = report["models"]["active"]["searchers"]["random"]
    assert search["n_failures"] > 0
    assert set(search["failures"]["by_axis"]) == {"rotation"}
    assert report["models"]["linear"]["role"] == "control"
    assert report["recheck"]["linear"]["diverged"] == 0
    (shrunk,) = report["shrunk"]
    assert shrunk["axis"] == "rotation" and shrunk["moving"] == ["rotation"]
    printed = capsys.readouterr().out
    assert "active       target   random" in printed and "moving rotation" in printed
    (path,) = case_files(corpus)
    raw = json.loads(path.read_text())
    assert raw["env"] == "rig3" and raw["profile"]["shape"][1] == 3
    case = load_case(path)
    assert case.profile.ndim == 2 and np.all(case.profile[:, :2] == 0)
    assert case.expect[str(model)]["diverged"] and not case.expect["linear"]["diverged"]
    assert check(case) == []


def _one_case(tmp_path):
    """(the rotation-active model's file, the one case a short attack on it keeps)."""
    model = _rotation_active(tmp_path / "active.npz")
    out = tmp_path / "run"
    argv = ["attack", "--env", "rig3", "--model", str(model), "--budget", "16", "--quiet",
            "--reference", "rubber", "--searchers", "random", "--out", str(out),
            "--max-shrink", "1", "--shrink-budget", "20"]  # fmt: skip
    assert main(argv) == 0
    (path,) = case_files(out / "cases")
    return model, path


def test_a_planar_case_whose_model_changed_no_longer_replays(tmp_path):
    model, path = _one_case(tmp_path)
    PlanarLinear.preset().save(model)  # the model fixed: the case's verdict changes
    kept = path.parent / "models"
    for f in kept.glob("*.npz"):
        PlanarLinear.preset().save(f)
    problems = check(load_case(path))
    assert problems and "expected to diverge but stayed bounded" in problems[0]


def test_a_planar_case_records_its_floors_and_a_replay_says_when_they_changed(tmp_path):
    """The rig3 judge's force floors follow from the reference (targets.reference_floors):
    a case keeps the floors it was judged at, and a replay at other floors says so, verdicts
    holding or not, as it does for a reference whose parameters changed."""
    _, path = _one_case(tmp_path)
    raw = json.loads(path.read_text())
    # the built-in reference judges at the papers' floors exactly
    assert raw["judge"]["force_floors"] == {"axial": 200.0, "radial": 200.0, "rotation": 20.0}
    notes = []
    assert check(load_case(path), notes=notes) == [] and notes == []

    raw["judge"]["force_floors"]["radial"] = 150.0  # as if judged at other floors
    path.write_text(json.dumps(raw))
    notes = []
    assert check(load_case(path), notes=notes) == []  # the verdicts hold at today's floors
    (note,) = notes
    assert "force_floors changed since the case was recorded: radial 150.0 -> 200" in note

    del raw["judge"]  # a case from before the floors were kept
    path.write_text(json.dumps(raw))
    notes = []
    assert check(load_case(path), notes=notes) == []
    assert "does not record the judge's force_floors" in notes[0]


def test_a_one_axis_model_name_on_rig3_is_refused_in_one_line(tmp_path, capsys):
    argv = ["attack", "--env", "rig3", "--model", "nn-paper", "--budget", "4", "--quiet",
            "--out", str(tmp_path / "run")]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nn-paper" in err[0] and "not 3: for a three-axis model" in err[0]


def test_the_matrix_refuses_a_planar_target_pointing_at_the_attack(tmp_path):
    from bushenv.search.matrix import MatrixConfig, MatrixError

    with pytest.raises(MatrixError, match="bushenv attack --env rig3"):
        MatrixConfig(target="rig3", out=tmp_path).checked()


def test_a_users_three_axis_file_without_a_reference_is_told_to_give_one(tmp_path, capsys):
    model = _rotation_active(tmp_path / "active.npz")
    argv = ["attack", "--env", "rig3", "--model", str(model), "--budget", "4", "--quiet",
            "--out", str(tmp_path / "run")]  # fmt: skip
    assert main(argv) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    assert "rig3 target judges against a reference and none was given" in err
    assert "--reference NAME|FILE" in err and "rubber, the built-in" in err


def test_a_trusted_three_axis_reference_marks_verdicts_where_it_failed(tmp_path, capsys):
    """A reference that rings when held near -1.25 mm radial (its certificate lists it, the
    vetting confirms it): trusted, the attack marks every verdict on a profile dwelling there
    as unvetted, as one axis marks its ranges."""
    from certify.conftest import ringing3

    from bushenv.search.campaign_config import CampaignConfig
    from bushenv.search.campaign_resolve import resolve

    ref = ringing3().save(tmp_path / "ring3.npz")
    model = _rotation_active(tmp_path / "active.npz")
    config = CampaignConfig(model=str(model), reference=str(ref), target="rig3",
                            trust_reference=True, out=tmp_path / "r")  # fmt: skip
    judge = resolve(config).judge
    assert judge.trusted_by_flag and judge.has_unvetted_regions
    dt = judge.reference.dt
    held = np.zeros((int(1.0 / dt), 3))
    held[:, 1] = -1.25e-3
    assert judge.in_unvetted_range(held, dt) is True
    assert judge.in_unvetted_range(np.zeros_like(held), dt) is False
    argv = ["attack", "--env", "rig3", "--model", str(model), "--reference", str(ref),
            "--trust-reference", "--budget", "8", "--searchers", "random", "--max-shrink",
            "0", "--no-plots", "--quiet", "--out", str(tmp_path / "a")]  # fmt: skip
    assert main(argv) == 0
    report = json.loads((tmp_path / "a" / "report.json").read_text())
    assert "failures_in_unvetted_range" in report["models"]["active"]["searchers"]["random"]
    assert "box(es) of held vectors" in capsys.readouterr().out
