"""The population over three coordinates (``bushenv zoo --env rig3``): MIMO networks, the
single-axis check, the attack across axes, its rates with intervals; the one-axis study
unchanged (what both do alike: ``test_zoo.py``)."""

import argparse

import numpy as np
import pytest

from bushenv.commands.zoo import add_arguments, config_from
from bushenv.search.base import Candidate
from bushenv.search.limits import COORDS
from bushenv.zoo.attack import driven_failed
from bushenv.zoo.cell import run_cell
from bushenv.zoo.study import (
    ZooConfig,
    ZooError,
)
from bushenv.zoo.summary import summarise
from bushenv.zoo.tables import markdown

# seconds, not minutes: a few full-batch steps, no free run
TINY = {"teacher_steps": 20, "free_run_steps": 0, "hidden": 6}


def _parse(*argv):
    p = argparse.ArgumentParser()
    add_arguments(p)
    return p.parse_args(["--out", "x", *argv])


def test_the_one_axis_study_is_what_it_was_without_env():
    plain = config_from(_parse("--seeds", "0"))
    assert plain.coords == 1
    assert plain == ZooConfig(seeds=(0,), out=plain.out).checked()
    assert "env" not in plain.cells()[0]  # its cells (and so its results files) keep their keys


def test_env_rig3_builds_the_mimo_population_and_refuses_what_does_not_apply():
    c = config_from(_parse("--env", "rig3", "--seeds", "0-1", "--models", "nn,nn-axis,hybrid"))
    assert c.coords == 3 and c.env == "rig3"
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
    assert driven_failed(_candidate(q, (0.5, -0.1, 0.5)), COORDS)
    assert not driven_failed(_candidate(q, (-0.5, 0.1, None)), COORDS)  # failed at rest: cross-axis


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
    row = run_cell(cell)
    assert (tmp_path / row["model_file"]).is_file()
    for s in ("random", "cma"):
        assert row["single_axis"][s]["evaluations"] == 8 == row["attacks"][s]["evaluations"]
        assert row["single_axis"][s]["passed"] == (row["single_axis"][s]["driven_failures"] == 0)
        a = row["attacks"][s]
        assert a["moving_failures"] <= a["n_failures"]
        assert (a["moving_evaluations_to_failure"] is None) == (a["moving_failures"] == 0)
    assert row["passed_single_axis"] == all(v["passed"] for v in row["single_axis"].values())
    assert set(row["accuracy"]) == {"independent", "correlated"}
    again = run_cell(cell)
    drop = {"train_s", "judge_s"}
    assert {k: v for k, v in again.items() if k not in drop} == {
        k: v for k, v in row.items() if k not in drop
    }


def test_only_the_searchers_that_can_be_held_to_one_family_run_the_single_axis_check():
    from bushenv.search.base import SearchError
    from bushenv.search.campaign_search import family_search, held_to
    from bushenv.search.searchers import RandomSearch

    assert held_to("random", "one_axis") == {"families": ("one_axis",)}
    assert held_to("cma", "one_axis") == {"family": "one_axis"}
    with pytest.raises(SearchError, match="certificate cannot be held"):
        held_to("certificate", "one_axis")
    with pytest.raises(SearchError, match="by name only"):
        family_search(None, None, RandomSearch(), 1, 0, family="one_axis")
