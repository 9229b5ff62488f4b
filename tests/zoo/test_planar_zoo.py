"""The MIMO population (``bushenv zoo --env rig3``): trained planar networks, the single-axis
check, the attack across axes, rates with intervals, resumable; the one-axis study unchanged."""

import argparse
import json

import numpy as np
import pytest

from bushenv.commands.zoo import add_arguments, config_from
from bushenv.execution import LocalBackend
from bushenv.progress import Progress
from bushenv.runlog import RunLog, run_cells
from bushenv.search.base import Candidate
from bushenv.zoo.planar_cell import driven_failed, run_planar_cell
from bushenv.zoo.planar_study import (
    PLANAR_CELL_KEYS,
    PLANAR_RESULT_KEYS,
    PlanarZooConfig,
    refuse_other_kind,
    run_planar_study,
)
from bushenv.zoo.planar_summary import markdown, summarise
from bushenv.zoo.study import ZooConfig, ZooError

# seconds, not minutes: a few full-batch steps, no free run
TINY = {"teacher_steps": 20, "free_run_steps": 0, "hidden": 6}


def _parse(*argv):
    p = argparse.ArgumentParser()
    add_arguments(p)
    return p.parse_args(["--out", "x", *argv])


def test_the_one_axis_study_is_what_it_was_without_env():
    plain = config_from(_parse("--seeds", "0"))
    assert isinstance(plain, ZooConfig)
    assert plain == ZooConfig(seeds=(0,), out=plain.out).checked()
    assert "env" not in plain.cells()[0]  # its cells (and so its results files) keep their keys


def test_env_rig3_builds_the_mimo_population_and_refuses_what_does_not_apply():
    c = config_from(_parse("--env", "rig3", "--seeds", "0-1", "--models", "nn,nn-axis,hybrid"))
    assert isinstance(c, PlanarZooConfig)
    assert c.searchers == ("random", "cma")
    cells = c.cells()
    assert len(cells) == 2 * 3 * 2 and {x["env"] for x in cells} == {"rig3"}
    for argv, fragment in (
        (("--axes", "axial"), "--axes"),
        (("--models", "boucwen"), "--models: unknown"),
        (("--searchers", "certificate"), "--searchers: unknown"),
        (("--recipes", "adam"), "--recipes: unknown"),
        (("--budget", "0"), "--budget"),
    ):
        with pytest.raises(ZooError, match=fragment):
            config_from(_parse("--env", "rig3", *argv))


def _candidate(profile, rob):
    verdict = {"axis_robustness": dict(zip(("axial", "radial", "rotation"), rob, strict=True))}
    worst = min(r for r in rob if r is not None)
    return Candidate(profile, "one_axis", None, worst, True, verdict, 1, 0.0)


def test_a_single_axis_failure_counts_only_in_the_coordinate_it_drives():
    q = np.zeros((10, 3))
    q[3:, 1] = 1e-3  # drives radial only
    assert driven_failed(_candidate(q, (0.5, -0.1, 0.5)))
    assert not driven_failed(_candidate(q, (-0.5, 0.1, None)))  # failed at rest: cross-axis


def _row(model, passed, diverged, at_rest=0, moving=None, cross=0):
    moving = diverged if moving is None else moving
    attack = {
        "diverged": diverged,
        "moving_failures": int(moving),
        "evaluations_to_failure": 3 if diverged else None,
        "in_a_coordinate_at_rest": at_rest,
        "by_axis": {"radial": 1} if diverged else {},
    }
    acc = {"axial": 0.1, "radial": 0.2, "rotation": 0.3}
    return {
        "recipe": "free-run",
        "model": model,
        "passed_single_axis": passed,
        "diverged": diverged,
        "diverged_moving": moving,
        "single_axis": {
            "random": {
                "passed": passed,
                "driven_failures": 0 if passed else 2,
                "cross_axis_failures": cross,
            }
        },
        "attacks": {"random": attack},
        "accuracy": {"correlated": acc},
        "train_s": 1.0,
        "judge_s": 1.0,
    }


def test_the_summary_counts_broken_among_those_passing_with_wilson_intervals():
    rows = [_row("nn", True, True), _row("nn", False, True), _row("nn", False, False)]
    rows += [_row("hybrid", True, True)] * 9 + [_row("hybrid", True, False)]
    s = summarise(rows)
    nn = s["groups"]["free-run/nn"]
    assert nn["passed_single_axis"]["failed"] == 1 and nn["passed_single_axis"]["of"] == 3
    assert (nn["broken_of_passed"]["failed"], nn["broken_of_passed"]["of"]) == (1, 1)
    assert (nn["broken"]["failed"], nn["broken"]["of"]) == (2, 3)
    hy = s["groups"]["free-run/hybrid"]["broken_of_passed"]
    assert (hy["failed"], hy["of"]) == (9, 10)
    lo, hi = hy["ci95"]
    assert lo == pytest.approx(0.5958, abs=1e-3) and hi == pytest.approx(0.9821, abs=1e-3)
    pooled = s["mimo_pooled"]
    assert (pooled["broken_of_passed"]["failed"], pooled["broken_of_passed"]["of"]) == (10, 11)
    assert not pooled["target_met"]  # 10/11 is above 90 %, its interval's lower end is not
    assert "Certified MIMO hybrids: none in this study" in markdown(s)
    none_passed = markdown(summarise([_row("nn", False, True)]))
    assert "| free-run/nn | 1 | 0/1 (0-79 %) | - | - | 1/1 (21-100 %) |" in none_passed


def test_failures_only_in_coordinates_at_rest_are_counted_apart():
    rows = [_row("hybrid", True, True, at_rest=3, moving=False, cross=5)] * 3
    rows += [_row("hybrid", True, True)]
    g = summarise(rows)["groups"]["free-run/hybrid"]
    assert g["broken_of_passed"]["failed"] == 4
    assert g["broken_moving_of_passed"]["failed"] == 1
    assert g["failed_in_a_coordinate_at_rest"]["failed"] == 3
    # three members pass on the driven coordinate only: a rig reading every channel fails them
    assert g["passed_single_axis_all_channels"]["failed"] == 1


def test_the_nn_axis_baseline_stays_out_of_the_mimo_pool():
    s = summarise([_row("nn-axis", True, True), _row("hybrid", True, False)])
    assert s["mimo_pooled"]["broken_of_passed"]["of"] == 1
    assert s["mimo_pooled"]["broken_of_passed"]["failed"] == 0


def test_a_member_trains_checks_single_axes_and_is_attacked_deterministically(tmp_path):
    cell = {
        "env": "rig3",
        "recipe": "teacher-forcing",
        "model": "hybrid",
        "seed": 2,
        "budget": 8,
        "searchers": "random,cma",
        "out": str(tmp_path),
        "train_options": TINY,
    }
    row = run_planar_cell(cell)
    assert (tmp_path / row["model_file"]).is_file()
    for s in ("random", "cma"):
        assert row["single_axis"][s]["evaluations"] == 8 == row["attacks"][s]["evaluations"]
        assert row["single_axis"][s]["passed"] == (row["single_axis"][s]["driven_failures"] == 0)
        a = row["attacks"][s]
        assert a["moving_failures"] <= a["n_failures"]
        assert (a["moving_evaluations_to_failure"] is None) == (a["moving_failures"] == 0)
    assert row["passed_single_axis"] == all(v["passed"] for v in row["single_axis"].values())
    assert set(row["accuracy"]) == {"independent", "correlated"}
    again = run_planar_cell(cell)
    drop = {"train_s", "judge_s"}
    assert {k: v for k, v in again.items() if k not in drop} == {
        k: v for k, v in row.items() if k not in drop
    }


def test_a_small_mimo_population_runs_summarises_and_resumes(tmp_path):
    config = PlanarZooConfig(
        recipes=("teacher-forcing",),
        models=("nn", "hybrid"),
        seeds=(0,),
        searchers=("random",),
        budget=8,
        out=tmp_path,
        train_options=TINY,
    ).checked()
    log = RunLog(tmp_path / "cells.jsonl", PLANAR_CELL_KEYS, PLANAR_RESULT_KEYS, ZooError)
    with LocalBackend(workers=1) as backend:
        cells = config.cells()
        first = run_cells(
            cells[:1], run_planar_cell, log, backend, False, Progress(quiet=True), str
        )
    rows = run_planar_study(
        PlanarZooConfig(**{**config.__dict__, "resume": True}),
        LocalBackend(workers=1),
        Progress(quiet=True),
    )
    assert rows[0] == first[0]  # resumed: the finished member is not trained again
    assert len(rows) == 2
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert set(summary["groups"]) == {"teacher-forcing/nn", "teacher-forcing/hybrid"}
    assert "broken_of_passed" in summary["mimo_pooled"]
    assert "| teacher-forcing/hybrid | 1 |" in (tmp_path / "summary.md").read_text()
    judge = summary["judge"]  # the reference every member was judged by, vetted first
    assert judge["vetting"]["passed"] is True and judge["vetting"]["reference"] == "reference"
    assert [c["check"] for c in judge["vetting"]["checks"]][0] == "holds"
    assert "vetted first (holds ok" in (tmp_path / "summary.md").read_text()


def test_resuming_the_other_kind_of_study_is_refused_and_its_file_kept(tmp_path, capsys):
    from bushenv.cli import main

    one_axis = tmp_path / "cells.jsonl"
    one_axis.write_text(json.dumps({"recipe": "free-run", "axis": "axial", "seed": 0}) + "\n")
    before = one_axis.read_bytes()
    argv = ["zoo", "--env", "rig3", "--seeds", "0", "--resume", "--out", str(tmp_path)]
    assert main(argv) == 2
    assert "cells.jsonl line 1: a one-axis (--env rig) study's results" in capsys.readouterr().err
    assert one_axis.read_bytes() == before  # not read as a torn line and cut
    refuse_other_kind(one_axis, planar=False)  # the same kind resumes as before
    one_axis.write_text(json.dumps({"env": "rig3", "seed": 0}) + "\n")
    with pytest.raises(ZooError, match="line 1: a MIMO"):
        refuse_other_kind(one_axis, planar=False)


@pytest.mark.slow
def test_a_member_run_on_ray_gives_the_local_result(tmp_path):
    ray = pytest.importorskip("ray", reason="Ray not installed (pip install 'bushenv[ray]')")
    from bushenv.execution import RayBackend

    def run(out, backend):
        config = PlanarZooConfig(
            models=("hybrid",),
            recipes=("teacher-forcing",),
            seeds=(1,),
            searchers=("random",),
            budget=4,
            out=out,
            train_options=TINY,
        ).checked()
        log = RunLog(out / "cells.jsonl", PLANAR_CELL_KEYS, PLANAR_RESULT_KEYS, ZooError)
        return run_cells(config.cells(), run_planar_cell, log, backend, False, Progress(True), str)

    def same(row):  # what a member found, without where and how long
        return {
            k: v for k, v in row.items() if k not in {"out", "train_s", "judge_s", "worker_backend"}
        }

    with LocalBackend(workers=1) as one:
        local = run(tmp_path / "local", one)
    backend = RayBackend(num_cpus=1)
    try:
        remote = run(tmp_path / "ray", backend)
    finally:
        backend.close()
    assert not ray.is_initialized()
    assert [same(r) for r in remote] == [same(r) for r in local]


def test_only_the_searchers_that_can_be_held_to_one_family_run_the_single_axis_check():
    from bushenv.search.base import SearchError
    from bushenv.search.campaign_planar import held_to, planar_search
    from bushenv.search.searchers import RandomSearch

    assert held_to("random", "one_axis") == {"families": ("one_axis",)}
    assert held_to("cma", "one_axis") == {"family": "one_axis"}
    with pytest.raises(SearchError, match="certificate cannot be held"):
        held_to("certificate", "one_axis")
    with pytest.raises(SearchError, match="by name only"):
        planar_search(None, None, RandomSearch(), 1, 0, family="one_axis")
