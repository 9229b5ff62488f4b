import json

import pytest

from bushenv.cli import main

from .conftest import bad_narx, tame_hybrid


@pytest.fixture()
def model_files(tmp_path):
    bad = bad_narx().save(tmp_path / "bad_nn.npz")
    good = tame_hybrid().save(tmp_path / "tame_hybrid.npz")
    return str(bad), str(good)


def _args(model_files, out, *extra):
    bad, good = model_files
    return [
        "attack",
        "--model",
        bad,
        "--hybrid",
        good,
        "--budget",
        "48",
        "--searchers",
        "random,cma",
        "--out",
        str(out),
        "--max-shrink",
        "1",
        "--shrink-budget",
        "40",
        "--threads",
        "2",
        "--reference",
        "rubber",  # the test models are models of the built-in rubber
        *extra,
    ]


def test_campaign_reports_every_model_and_searcher_and_refuses_to_overwrite(
    tmp_path, model_files, capsys
):
    out = tmp_path / "run"
    corpus = tmp_path / "corpus"
    assert main(_args(model_files, out, "--save", "--corpus", str(corpus))) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["complete"]
    assert set(report["models"]) == {"bad_nn", "tame_hybrid", "linear"}
    roles = {k: v["role"] for k, v in report["models"].items()}
    assert roles == {"bad_nn": "target", "tame_hybrid": "hybrid", "linear": "control"}
    for entry in report["models"].values():
        for s in ("random", "cma"):
            row = entry["searchers"][s]
            for key in (
                "diverged",
                "evaluations_to_failure",
                "seconds_to_failure",
                "worst_deviation",
            ):
                assert key in row
    bad = report["models"]["bad_nn"]["searchers"]
    assert bad["random"]["diverged"] or bad["cma"]["diverged"]
    assert not any(r["diverged"] for r in report["models"]["linear"]["searchers"].values())
    assert report["recheck"]["profiles"] > 0 and "linear" in report["recheck"]
    assert report["shrunk"] and list(corpus.glob("*.json"))
    assert (out / "plots" / "worst-bad_nn.png").stat().st_size > 0
    text = capsys.readouterr().out
    assert "evals->fail" in text and "control" in text
    # an existing report is refused without --resume or --force
    assert main(_args(model_files, out)) == 2
    assert "--resume" in capsys.readouterr().err


def test_resume_finishes_an_interrupted_campaign_with_the_same_results(tmp_path, model_files):
    full = tmp_path / "full"
    assert main(_args(model_files, full, "--no-plots")) == 0
    cut = tmp_path / "cut"
    assert main(_args(model_files, cut, "--no-plots")) == 0
    report = json.loads((cut / "report.json").read_text())
    # pretend the run died during the hybrid's CMA search
    del report["models"]["tame_hybrid"]["searchers"]["cma"]
    del report["models"]["linear"]["searchers"]["cma"]
    report["shrunk"], report["complete"] = [], False
    (cut / "report.json").write_text(json.dumps(report))
    assert main(_args(model_files, cut, "--no-plots", "--resume")) == 0
    a = json.loads((full / "report.json").read_text())
    b = json.loads((cut / "report.json").read_text())
    for key in a["models"]:
        for s in ("random", "cma"):
            ra, rb = a["models"][key]["searchers"][s], b["models"][key]["searchers"][s]
            for k in ("diverged", "evaluations_to_failure", "worst_robustness", "n_failures"):
                assert ra[k] == rb[k], (key, s, k)
    assert b["complete"]


def test_unknown_searchers_are_refused(tmp_path, model_files, capsys):
    args = _args(model_files, tmp_path / "x")
    args[args.index("random,cma")] = "random,dqn"
    assert main(args) == 2
    assert "unknown ['dqn']" in capsys.readouterr().err


def test_a_model_file_without_a_reference_runs_only_the_criteria_that_need_none(
    tmp_path, model_files, capsys
):
    bad, _ = model_files
    out = tmp_path / "free"
    args = ["attack", "--model", bad, "--budget", "32", "--searchers", "random", "--out", str(out)]
    assert main([*args, "--no-plots", "--max-shrink", "1", "--shrink-budget", "20"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["reference"]["spec"] is None
    run = report["criteria"]["run"]
    assert "deviation" not in run and "static" not in run
    assert {"non_finite", "force_bound", "self_sustained", "energy"} <= set(run)
    assert "no reference" in report["criteria"]["why"]
    # no rows of the built-in rubber's shipped models: they are models of another bushing
    assert set(report["models"]) == {"bad_nn"}
    text = capsys.readouterr().out
    assert "reference: none" in text and "no hybrid row" in text
    md = (out / "report.md").read_text()
    assert "s->fail" in md and "wall-clock seconds" in md
