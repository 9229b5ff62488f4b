"""The population study: rows per trained model, rates with intervals, resumable."""

import json

import pytest

from bushenv.execution import LocalBackend
from bushenv.progress import Progress
from bushenv.runlog import RunLog, run_cells
from bushenv.zoo.cell import run_cell
from bushenv.zoo.study import CELL_KEYS, RESULT_KEYS, ZooConfig, ZooError
from bushenv.zoo.summary import summarise, wilson

QUICK = {"teacher_steps": 150}  # a small one-step-ahead training: seconds, not minutes


def test_wilson_interval_matches_known_values():
    lo, hi = wilson(0, 10)
    assert lo == 0.0 and hi == pytest.approx(0.2775, abs=1e-4)
    lo, hi = wilson(5, 10)
    assert lo == pytest.approx(0.2366, abs=1e-4) and hi == pytest.approx(0.7634, abs=1e-4)


def test_unknown_recipes_and_searchers_are_refused():
    with pytest.raises(ZooError, match="--recipes: unknown"):
        ZooConfig(recipes=("adam",)).checked()
    with pytest.raises(ZooError, match="--searchers: unknown"):
        ZooConfig(searchers=("dqn",)).checked()


def test_a_small_population_trains_judges_summarises_and_resumes(tmp_path):
    config = ZooConfig(
        recipes=("teacher-forcing",),
        models=("nn",),
        axes=("axial",),
        seeds=(0, 1),
        searchers=("random", "certificate"),
        budget=8,
        out=tmp_path,
        train_options=QUICK,
    ).checked()
    log = RunLog(tmp_path / "cells.jsonl", CELL_KEYS, RESULT_KEYS, ZooError)
    with LocalBackend(workers=1) as backend:
        cells = config.cells()
        first = run_cells(cells[:1], run_cell, log, backend, False, Progress(quiet=True), str)
        rows = run_cells(cells, run_cell, log, backend, True, Progress(quiet=True), str)
    assert rows[0] == first[0]  # resumed: the finished cell is not trained again
    assert (tmp_path / rows[1]["model_file"]).is_file()
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


def test_certified_flag_reaches_the_training_the_file_names_and_the_summary_label():
    import argparse

    from bushenv.commands.zoo import add_arguments, config_from
    from bushenv.zoo.cell import cell_name
    from bushenv.zoo.summary import recipe_label

    p = argparse.ArgumentParser()
    add_arguments(p)
    args = p.parse_args(["--out", "x", "--certified", "on", "--seeds", "0"])
    cell = config_from(args).cells()[0]
    assert cell["train_options"] == {"certified": "on"}
    assert "train_options" in CELL_KEYS  # a resumed study never mixes the two kinds of cell
    plain = config_from(p.parse_args(["--out", "x", "--seeds", "0"])).cells()[0]
    assert cell_name(cell) != cell_name(plain) and "-certified-" in cell_name(cell)
    assert recipe_label(cell) == f"{cell['recipe']} +certified"
    assert recipe_label(plain) == plain["recipe"]
    with pytest.raises(SystemExit):
        p.parse_args(["--out", "x", "--certified", "yes"])


def test_a_cell_run_on_ray_gives_the_local_result(tmp_path):
    ray = pytest.importorskip("ray", reason="Ray not installed (pip install 'bushenv[ray]')")
    from bushenv.execution import RayBackend

    def cells(out):
        config = ZooConfig(
            recipes=("teacher-forcing",),
            models=("nn",),
            axes=("radial",),
            seeds=(3,),
            searchers=("random",),
            budget=8,
            out=out,
            train_options=QUICK,
        ).checked()
        return config.cells()

    def run(out, backend):
        log = RunLog(out / "cells.jsonl", CELL_KEYS, RESULT_KEYS, ZooError)
        return run_cells(cells(out), run_cell, log, backend, False, Progress(quiet=True), str)

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
