"""The population study over C coordinates: rows per trained model, rates with intervals,
resumable, the same on Ray; what the one-coordinate study finds (the papers' step, the hold
certificate) and what the study over three finds (the single-axis check, the attack across
axes) each asserted for its own C."""

import argparse
import json
import re
from dataclasses import replace

import pytest

from bushenv.commands.zoo import add_arguments, config_from
from bushenv.execution import LocalBackend
from bushenv.progress import Progress
from bushenv.runlog import RunLog, run_cells
from bushenv.zoo.cell import cell_name, run_cell
from bushenv.zoo.rates import recipe_label, wilson
from bushenv.zoo.study import (
    ZooConfig,
    ZooError,
    cell_keys,
    refuse_other_kind,
    result_keys,
    run_study,
)
from bushenv.zoo.summary import summarise

QUICK = {"teacher_steps": 150}  # a small one-step-ahead training: seconds, not minutes
TINY = {"teacher_steps": 20, "free_run_steps": 0, "hidden": 6}  # the MIMO one: a few steps
ENV = {1: "rig", 3: "rig3"}
# two small members per C
SMALL = {
    1: {"models": ("nn",), "axes": ("axial",), "seeds": (0, 1), "train_options": QUICK},
    3: {"models": ("nn", "hybrid"), "seeds": (0,), "train_options": TINY},
}
SEARCHERS = {1: ("random", "certificate"), 3: ("random",)}


def _parse(*argv):
    p = argparse.ArgumentParser()
    add_arguments(p)
    return p.parse_args(["--out", "x", *argv])


def test_wilson_interval_matches_known_values():
    lo, hi = wilson(0, 10)
    assert lo == 0.0 and hi == pytest.approx(0.2775, abs=1e-4)
    lo, hi = wilson(5, 10)
    assert lo == pytest.approx(0.2366, abs=1e-4) and hi == pytest.approx(0.7634, abs=1e-4)


@pytest.mark.parametrize("coords", [1, 3])
def test_unknown_recipes_searchers_and_budgets_are_refused(coords):
    env = ENV[coords]
    for kwargs, fragment in (
        ({"recipes": ("adam",)}, "--recipes: unknown"),
        ({"searchers": ("dqn",)}, "--searchers: unknown"),
        ({"models": ("boucwen",)}, "--models: unknown"),
        ({"budget": 0}, "--budget"),
    ):
        with pytest.raises(ZooError, match=fragment):
            ZooConfig(env=env, **kwargs).checked()


@pytest.mark.parametrize("coords", [1, 3])
def test_certified_flag_reaches_the_training_the_file_names_and_the_summary_label(coords):
    env = ("--env", ENV[coords])
    config = config_from(_parse(*env, "--certified", "on", "--seeds", "0"))
    assert config.coords == coords
    cell = config.cells()[0]
    assert cell["train_options"] == {"certified": "on"}
    assert {x["train_options"]["certified"] for x in config.cells()} == {"on"}
    assert "train_options" in cell_keys(coords)  # a resumed study never mixes the two kinds
    plain = config_from(_parse(*env, "--seeds", "0")).cells()[0]
    assert plain["train_options"] == {}
    # certified and plain members of one study write different model files
    assert cell_name(cell) != cell_name(plain) and "-certified-" in cell_name(cell)
    assert recipe_label(cell) == f"{cell['recipe']} +certified"
    assert recipe_label(plain) == plain["recipe"]
    with pytest.raises(SystemExit):
        _parse(*env, "--certified", "yes")


def _one_axis_rows(rows, out):
    for r in rows:
        assert set(r["attacks"]) == {"random", "certificate"}
        assert 0 < r["accuracy"]["rms_ratio_n1"] < 1
        assert set(r["step"]) == {"+4mm", "-4mm"}
        assert isinstance(r["certificate"]["passes_holds"], bool)
    s = summarise(rows)["teacher-forcing/nn"]
    assert s["cells"] == 2
    lo, hi = s["diverged_any_searcher"]["ci95"]
    assert 0.0 <= lo <= s["diverged_any_searcher"]["rate"] <= hi <= 1.0
    assert json.loads(json.dumps(s)) == s
    assert (out / "accuracy_vs_robustness.png").is_file()


def _across_axes_rows(rows, out):
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["groups"]) == {"teacher-forcing/nn", "teacher-forcing/hybrid"}
    assert "broken_of_passed" in summary["mimo_pooled"]
    assert "| teacher-forcing/hybrid | 1 |" in (out / "summary.md").read_text()
    judge = summary["judge"]  # the reference every member was judged by, vetted first
    assert judge["vetting"]["passed"] is True and judge["vetting"]["reference"] == "rubber"
    assert [c["check"] for c in judge["vetting"]["checks"]][0] == "holds"
    assert "vetted first (holds ok" in (out / "summary.md").read_text()
    assert not (out / "accuracy_vs_robustness.png").exists()


@pytest.mark.parametrize("coords", [1, 3])
def test_a_small_population_trains_judges_summarises_and_resumes(tmp_path, coords):
    config = ZooConfig(
        env=ENV[coords],
        recipes=("teacher-forcing",),
        searchers=SEARCHERS[coords],
        budget=8,
        out=tmp_path,
        **SMALL[coords],
    ).checked()
    log = RunLog(tmp_path / "cells.jsonl", cell_keys(coords), result_keys(coords), ZooError)
    with LocalBackend(workers=1) as backend:
        cells = config.cells()
        first = run_cells(cells[:1], run_cell, log, backend, False, Progress(quiet=True), str)
    rows = run_study(replace(config, resume=True), LocalBackend(workers=1), Progress(quiet=True))
    assert rows[0] == first[0]  # resumed: the finished cell is not trained again
    assert len(rows) == 2
    assert all((tmp_path / r["model_file"]).is_file() for r in rows)
    assert json.loads((tmp_path / "summary.json").read_text()) == json.loads(
        json.dumps(summarise(rows, coords) | _judge_of(tmp_path))
    )
    (_one_axis_rows if coords == 1 else _across_axes_rows)(rows, tmp_path)


def _judge_of(out):
    written = json.loads((out / "summary.json").read_text())
    return {"judge": written["judge"]} if "judge" in written else {}


@pytest.mark.parametrize("coords", [1, 3])
def test_resuming_the_other_kind_of_study_is_refused_and_its_file_kept(tmp_path, capsys, coords):
    from bushenv.cli import main

    other = {1: {"env": "rig3", "seed": 0}, 3: {"recipe": "free-run", "axis": "axial", "seed": 0}}
    kind = {1: "a MIMO (--env rig3)", 3: "a one-axis (--env rig)"}
    results = tmp_path / "cells.jsonl"
    results.write_text(json.dumps(other[coords]) + "\n")
    before = results.read_bytes()
    argv = ["zoo", "--env", ENV[coords], "--seeds", "0", "--resume", "--out", str(tmp_path)]
    assert main(argv) == 2
    assert f"cells.jsonl line 1: {kind[coords]} study's results" in capsys.readouterr().err
    assert results.read_bytes() == before  # not read as a torn line and cut
    refuse_other_kind(results, 4 - coords)  # the same kind resumes as before
    with pytest.raises(ZooError, match=re.escape(f"line 1: {kind[coords]}")):
        refuse_other_kind(results, coords)


@pytest.mark.parametrize("coords", [1, pytest.param(3, marks=pytest.mark.slow)])
def test_a_cell_run_on_ray_gives_the_local_result(tmp_path, coords):
    ray = pytest.importorskip("ray", reason="Ray not installed (pip install 'bushenv[ray]')")
    from bushenv.execution import RayBackend

    def run(out, backend):
        config = ZooConfig(
            env=ENV[coords],
            recipes=("teacher-forcing",),
            searchers=("random",),
            budget={1: 8, 3: 4}[coords],
            out=out,
            **{
                1: {"models": ("nn",), "axes": ("radial",), "seeds": (3,), "train_options": QUICK},
                3: {"models": ("hybrid",), "seeds": (1,), "train_options": TINY},
            }[coords],
        ).checked()
        log = RunLog(out / "cells.jsonl", cell_keys(coords), result_keys(coords), ZooError)
        return run_cells(config.cells(), run_cell, log, backend, False, Progress(quiet=True), str)

    def same(row):  # what a cell found, without where and how long
        drop = {"out", "train_s", "judge_s", "worker_backend"}
        return {k: v for k, v in row.items() if k not in drop}

    with LocalBackend(workers=1) as one:
        local = run(tmp_path / "local", one)
    backend = RayBackend(num_cpus=1)
    try:
        remote = run(tmp_path / "ray", backend)
    finally:
        backend.close()
    assert not ray.is_initialized()
    assert [same(r) for r in remote] == [same(r) for r in local]
