"""``bushenv zoo --env rig3 --certified on``: certified MIMO hybrids trained, checked and
attacked end to end, and summarised apart from the plain ones (never counted as certified)."""

import argparse
import json

from bushenv.commands.zoo import add_arguments, config_from
from bushenv.execution import LocalBackend
from bushenv.progress import Progress
from bushenv.zoo.cell import cell_name
from bushenv.zoo.study import ZooConfig, run_study
from bushenv.zoo.summary import NO_CERTIFIED, summarise
from bushenv.zoo.tables import markdown

TINY = {"teacher_steps": 12, "free_run_steps": 0, "hidden": 6, "certified_holds": 7}


def _parse(*argv):
    p = argparse.ArgumentParser()
    add_arguments(p)
    return p.parse_args(["--out", "x", *argv])


def test_structure_trains_the_planar_networks_tied_and_names_them_apart():
    import pytest

    from bushenv.zoo.rates import recipe_label
    from bushenv.zoo.study import ZooError

    args = ("--env", "rig3", "--seeds", "0", "--certified", "on", "--structure", "mirror")
    mirror = config_from(_parse(*args)).cells()[0]
    assert mirror["train_options"] == {"certified": "on", "structure": "mirror"}
    free = config_from(_parse(*args[:-2])).cells()[0]
    assert cell_name(mirror) != cell_name(free)
    assert recipe_label(mirror) == "free-run +certified +mirror"
    assert recipe_label(free) == "free-run +certified"
    with pytest.raises(ZooError, match="--structure.*--env rig3"):
        config_from(_parse("--seeds", "0", "--structure", "mirror"))


def _row(certified, diverged, admitted=True, passed=True):
    attack = {
        "diverged": diverged,
        "moving_failures": int(diverged),
        "evaluations_to_failure": 3 if diverged else None,
        "in_a_coordinate_at_rest": 0,
        "by_axis": {"radial": 1} if diverged else {},
    }
    return {
        "recipe": "free-run",
        "model": "hybrid",
        "train_options": {"certified": "on"} if certified else {},
        "certified_admitted": admitted if certified else None,
        "passed_single_axis": passed,
        "diverged": diverged,
        "diverged_moving": diverged,
        "single_axis": {
            "random": {"passed": passed, "driven_failures": 0, "cross_axis_failures": 0}
        },
        "attacks": {"random": attack},
        "accuracy": {"correlated": {"axial": 0.1, "radial": 0.1, "rotation": 0.1}},
        "certificate": {"out_of_band": 0 if certified else 5, "unstable": 0, "unsettled_holds": 0},
        "network_share": dict.fromkeys(
            ("axial", "radial", "rotation"), 0.01 if certified else 0.08
        ),
        "train_s": 1.0,
        "judge_s": 1.0,
    }


def test_certified_hybrids_get_their_own_rates_and_stay_out_of_the_pool():
    rows = [_row(False, True)] * 3 + [_row(True, False)] * 4 + [_row(True, True, admitted=False)]
    s = summarise(rows)
    assert set(s["groups"]) == {"free-run/hybrid", "free-run +certified/hybrid"}
    assert s["mimo_pooled"]["broken_of_passed"]["of"] == 3  # the plain ones only
    c = s["certified_hybrids"]
    assert (c["bounded_of_passed"]["failed"], c["bounded_of_passed"]["of"]) == (4, 5)
    assert (c["broken_of_passed"]["failed"], c["broken_of_passed"]["of"]) == (1, 5)
    assert (c["weights_admitted"]["failed"], c["weights_admitted"]["of"]) == (4, 5)
    lo, hi = c["bounded_of_passed"]["ci95"]
    assert 0.3 < lo < 0.4 and 0.96 < hi < 0.97  # Wilson, 4 of 5
    text = markdown(s)
    assert "bounded across axes 4/5 (38-96 %)" in text
    assert "Their networks' part of the force (median RMS ratio a / r / rot, unseen " in text
    assert "1.0 / 1.0 / 1.0 % (near 0: the backbone alone)" in text
    assert s["groups"]["free-run/hybrid"]["holds"]["out_of_band"]["failed"] == 3
    # plain hybrids alone are never reported as certified
    assert summarise([_row(False, False)] * 2)["certified_hybrids"] == NO_CERTIFIED


def test_a_tiny_certified_study_runs_end_to_end(tmp_path):
    config = ZooConfig(
        env="rig3",
        recipes=("teacher-forcing",),
        models=("hybrid",),
        seeds=(0,),
        searchers=("random", "cma"),
        budget=4,
        out=tmp_path,
        train_options={**TINY, "certified": "on"},
    ).checked()
    rows = run_study(config, LocalBackend(workers=1), Progress(quiet=True))
    row = rows[0]
    assert isinstance(row["certified_admitted"], bool)
    assert row["certificate"]["holds"] == 343
    assert set(row["network_share"]) == {"axial", "radial", "rotation"}
    assert (tmp_path / row["model_file"]).is_file() and "certified" in row["model_file"]
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["certified_hybrids"]["members"] == 1
    assert set(summary["certified_hybrids"]["by_searcher"]) <= {"random", "cma"}
    assert (
        "Certified MIMO hybrids (--certified on): 1 members"
        in (tmp_path / "summary.md").read_text()
    )


def test_the_network_share_of_a_silent_hybrid_is_zero_and_of_a_live_one_is_not():
    import numpy as np

    from bushenv.models.planar_narx import PlanarHybrid, PlanarNarx
    from bushenv.search.limits import COORDS
    from bushenv.zoo.cell import network_share, records

    live = PlanarHybrid.untrained(seed=0)
    p = live.params
    silent = PlanarHybrid(**{**p, "w_out": 0 * p["w_out"], "b_out": -p["f_offset"] / p["f_scale"]})
    _, unseen = records(3, 0)
    assert max(network_share(silent, unseen, COORDS).values()) < 1e-12
    assert min(network_share(live, unseen, COORDS).values()) > 0.01
    assert network_share(PlanarNarx.untrained(seed=0), unseen, COORDS) is None  # all network
    assert np.isfinite(list(network_share(live, unseen, COORDS).values())).all()


def test_certified_hybrids_whose_network_carries_force_are_not_called_silent():
    row = _row(True, False)
    row["network_share"] = dict.fromkeys(("axial", "radial", "rotation"), 0.07)
    text = markdown(summarise([row] * 3))
    assert "7.0 / 7.0 / 7.0 %." in text
    assert "near 0" not in text


def test_training_noisy_feedback_is_the_hybrids_and_names_its_members_apart():
    import pytest

    from bushenv.zoo.study import ZooError

    args = ("--env", "rig3", "--seeds", "0", "--models", "hybrid")
    noisy = config_from(_parse(*args, "--training", "noisy-feedback")).cells()[0]
    assert noisy["train_options"] == {"training": "noisy-feedback"}
    plain = config_from(_parse(*args)).cells()[0]
    assert plain["train_options"] == {}
    assert cell_name(noisy) != cell_name(plain)
    with pytest.raises(ZooError, match="--training.*--models hybrid"):
        config_from(_parse("--env", "rig3", "--seeds", "0", "--training", "noisy-feedback"))
    with pytest.raises(ZooError, match="--training.*--env rig3"):
        config_from(_parse("--seeds", "0", "--training", "noisy-feedback"))
