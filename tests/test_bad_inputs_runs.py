"""Interrupted and damaged runs of ``bushenv campaign`` (bushenv/search/matrix.py): Ctrl-C,
``kill`` and ``kill -9`` keep every finished cell on disk, ``--resume`` runs only the rest, and a
damaged results file is caught on load. The catalogue is docs/bad-inputs.md.

(``bushenv attack``, ``reproduce`` and training are not covered here yet: see the report in
docs/bad-inputs.md, "pending".)
"""

from __future__ import annotations

import concurrent.futures
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bushenv.execution import LocalBackend
from bushenv.progress import Progress
from bushenv.search.matrix import (
    CELL_KEYS,
    MatrixError,
    make_cells,
    parse_seeds,
    read_results,
    run_matrix,
)


def skip_slow_unless_asked(request) -> None:
    """Slow-marked cases run only under ``pytest -m slow`` (as in tests/rigs/conftest.py)."""
    if request.node.get_closest_marker("slow") and "slow" not in (
        request.config.getoption("-m") or ""
    ):
        pytest.skip("slow test; run with -m slow")


CELLS = make_cells(["linear"], ["axial"], ["random"], [0, 1, 2], budget=16)
QUIET = {"progress": Progress(quiet=True)}
N_SIGNAL_CELLS = 40  # far more than can finish between the first result and a signal


def campaign_command(out: Path, seeds: str, workers: int, *extra: str) -> list[str]:
    return [
        sys.executable,
        "-m",
        "bushenv.cli",
        "campaign",
        "--models",
        "linear",
        "--axes",
        "axial",
        "--searchers",
        "random",
        "--seeds",
        seeds,
        "--budget",
        "96",
        "--workers",
        str(workers),
        "--out",
        str(out),
        *extra,
    ]


def lines_of(path: Path) -> list[str]:
    return path.read_text().splitlines() if path.exists() else []


def start_and_signal(cmd: list[str], results: Path, sig: int, min_lines: int = 1):
    """Start ``cmd``, wait until ``results`` holds ``min_lines`` lines, send ``sig`` to the
    main process only; returns (exit code, stderr, seconds from signal to exit)."""
    proc = subprocess.Popen(
        cmd,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        # A job started in the background by a non-interactive shell (as CI may run us)
        # inherits SIGINT ignored, and Python then never raises KeyboardInterrupt: restore the
        # default so the child sees Ctrl-C as a user's terminal would send it.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        deadline = time.monotonic() + 240
        while len(lines_of(results)) < min_lines:
            if proc.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"run ended or stalled before {min_lines} result(s)")
            time.sleep(0.02)
        t0 = time.monotonic()
        proc.send_signal(sig)
        # communicate waits for stderr to close: a pool worker left behind would hold it open
        _, err = proc.communicate(timeout=60)
        return proc.returncode, err, time.monotonic() - t0
    finally:
        if proc.poll() is None:  # only on a failed assertion: end what this test started
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


@pytest.mark.parametrize(
    ("sig", "code", "message"),
    [
        (signal.SIGINT, 130, "interrupted; results written so far are kept"),
        pytest.param(
            signal.SIGTERM,
            143,
            "terminated; results written so far are kept",
            marks=pytest.mark.slow,
        ),
        (signal.SIGKILL, -9, ""),
    ],
    ids=["ctrl-c", "kill", "kill-9"],
)
def test_signalled_campaign_keeps_finished_cells_and_resume_completes_it(
    tmp_path, request, sig, code, message
):
    skip_slow_unless_asked(request)
    out = tmp_path / "matrix"
    results = out / "cells.jsonl"
    cmd = campaign_command(out, f"0-{N_SIGNAL_CELLS - 1}", 2)
    rc, err, seconds = start_and_signal(cmd, results, sig)
    assert rc == code
    assert message in err
    assert "Traceback" not in err
    assert seconds < 20  # no waiting for running cells; no orphaned worker holding the pipe
    kept = lines_of(results)
    assert kept, "every finished cell is on disk"
    for line in kept:  # complete lines only (appended whole, flushed, fsynced)
        row = json.loads(line)
        assert all(k in row for k in CELL_KEYS)
    assert results.read_text().endswith("\n")
    assert not (out / "summary.json").exists()

    if sig == signal.SIGINT:
        again = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        assert again.returncode == 2
        assert "exists; pass --resume" in again.stderr  # never overwritten without --resume
        assert lines_of(results) == kept

    resumed = subprocess.run([*cmd, "--resume"], capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{len(kept)} already done, {N_SIGNAL_CELLS - len(kept)} to run" in resumed.stderr
    final = lines_of(results)
    assert final[: len(kept)] == kept  # earlier results untouched
    seeds = sorted(json.loads(line)["seed"] for line in final)
    assert seeds == list(range(N_SIGNAL_CELLS))  # each cell exactly once
    summary = json.loads((out / "summary.json").read_text())
    assert summary["linear"]["random"]["runs"] == N_SIGNAL_CELLS


def test_torn_last_line_is_dropped_and_its_cell_rerun(tmp_path):
    out = tmp_path / "m"
    with LocalBackend(workers=1) as one:
        run_matrix(CELLS[:2], out, one, **QUIET)
        path = out / "cells.jsonl"
        whole = lines_of(path)
        with path.open("a") as fh:
            fh.write(whole[0][: len(whole[0]) // 2])  # killed mid-write
        rows = run_matrix(CELLS, out, one, resume=True, **QUIET)
    assert [r["seed"] for r in rows] == [0, 1, 2]
    assert lines_of(path)[:2] == whole
    assert len(lines_of(path)) == 3


def test_complete_last_line_without_newline_is_kept_and_the_next_append_starts_a_new_line(
    tmp_path,
):
    out = tmp_path / "m"
    with LocalBackend(workers=1) as one:
        run_matrix(CELLS[:2], out, one, **QUIET)
        path = out / "cells.jsonl"
        path.write_text(path.read_text().rstrip("\n"))  # cut exactly before the newline
        msgs: list[str] = []
        run_matrix(CELLS, out, one, resume=True, progress=Progress(sink=msgs.append))
    assert "2 already done, 1 to run" in msgs[0]
    assert [json.loads(line)["seed"] for line in lines_of(path)] == [0, 1, 2]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\x89PNG\r\n\x1a\n\xff\xfe", r"cells\.jsonl: not a results file \(not UTF-8"),
        (b'[1, 2]\n{"a": 1}\n', r"cells\.jsonl line 1: corrupt result line"),
        (b"{}\n{}\n", r"line 1: corrupt result line"),
    ],
    ids=["binary", "json-but-not-objects", "objects-without-cell-keys"],
)
def test_damaged_results_file_is_refused_on_resume_naming_the_line(tmp_path, content, message):
    out = tmp_path / "m"
    out.mkdir()
    (out / "cells.jsonl").write_bytes(content)
    with LocalBackend(workers=1) as one, pytest.raises(MatrixError, match=message):
        run_matrix(CELLS, out, one, resume=True, **QUIET)
    assert (out / "cells.jsonl").read_bytes() == content  # left for the user to inspect


def test_result_line_without_result_fields_is_refused_on_resume(tmp_path):
    out = tmp_path / "m"
    out.mkdir()
    cell_only = json.dumps(CELLS[0])  # the cell, but no 'diverged', 'evaluations', ...
    (out / "cells.jsonl").write_text(cell_only + "\n" + cell_only + "\n")
    with LocalBackend(workers=1) as one, pytest.raises(MatrixError, match="line 1: corrupt"):
        run_matrix(CELLS, out, one, resume=True, **QUIET)


def test_results_path_that_is_a_folder_is_refused(tmp_path):
    (tmp_path / "cells.jsonl").mkdir()
    with pytest.raises(MatrixError, match="not a regular file"):
        read_results(tmp_path / "cells.jsonl")


@pytest.mark.parametrize(
    ("text", "message"),
    [("-3", "seeds must be >= 0"), ("2,-1", "seeds must be >= 0"), (",", "names no seed")],
)
def test_bad_seed_lists_are_refused(text, message):
    with pytest.raises(MatrixError, match=message):
        parse_seeds(text)


def test_summary_files_are_replaced_atomically_leaving_no_temp_files(tmp_path):
    from bushenv.search.matrix import summarise, write_summary

    out = tmp_path / "m"
    with LocalBackend(workers=1) as one:
        rows = run_matrix(CELLS[:1], out, one, **QUIET)
    write_summary(out, summarise(rows))
    write_summary(out, summarise(rows))
    assert sorted(p.name for p in out.iterdir()) == [
        "cells.jsonl",
        "summary.json",
        "summary.md",
        "summary.png",
    ]


def _slow_square(n: int) -> int:
    time.sleep(30)
    return n * n


def _gone(pid: int) -> bool:
    """The process is dead: reaped (no such pid) or a zombie waiting to be reaped.

    Not ``Process.is_alive()``: the executor's own manager thread may reap a worker first,
    and multiprocessing then reads the ECHILD of its own waitpid as "still running".
    """
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except FileNotFoundError:
        return True


def test_abort_terminates_running_workers_without_waiting_for_them():
    backend = LocalBackend(workers=2)
    pool = backend._executor()
    futures = [pool.submit(_slow_square, n) for n in (1, 2)]
    time.sleep(1.0)  # let the workers pick the items up
    workers = list(pool._processes.values())
    t0 = time.monotonic()
    backend.abort()
    assert time.monotonic() - t0 < 15  # not the 30 s the items would take
    pids = [p.pid for p in workers]
    deadline = time.monotonic() + 10  # a loaded machine may take a moment
    while not all(_gone(pid) for pid in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert all(_gone(pid) for pid in pids)
    # their futures end too (cancelled or broken), set by the executor's manager thread
    assert not concurrent.futures.wait(futures, timeout=10).not_done


# ----- bushenv attack: regression corpus and report (bushenv/search/{corpus,campaign}.py) ------
def _corpus_case():
    from bushenv.search.corpus import load_case

    corpus = Path(__file__).parent / "regressions" / "corpus"
    files = sorted(corpus.glob("*.json"))
    if not files:
        pytest.skip("no regression case in tests/regressions/corpus yet")
    return load_case(files[0])


def test_regression_case_is_never_overwritten_without_force(tmp_path):
    from bushenv.search.corpus import save_case

    case = _corpus_case()
    path = save_case(case, tmp_path)
    before = path.read_bytes()
    case.notes = "a different finding under the same name"
    assert save_case(case, tmp_path) is None  # kept
    assert path.read_bytes() == before
    assert save_case(case, tmp_path, force=True) == path  # replaced only when asked
    assert path.read_bytes() != before
    # no temp files; models/ holds the model files the case names (kept with it)
    assert {p.name for p in tmp_path.iterdir()} <= {path.name, "models"}
    assert not [p for p in tmp_path.rglob("*") if p.name.endswith(".tmp")]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ('{"format": "bushenv-divergence-case", "na', "not a readable JSON case file"),
        ("[1, 2]", "not a bushenv divergence case"),
        ("{}", "not a bushenv divergence case"),
    ],
    ids=["half-written", "json-list", "empty-object"],
)
def test_damaged_regression_case_is_refused_naming_the_file(tmp_path, content, message):
    from bushenv.search.corpus import CorpusError, load_case

    path = tmp_path / "case.json"
    path.write_text(content)
    with pytest.raises(CorpusError, match=rf"case\.json: {message}"):
        load_case(path)


def test_binary_regression_case_is_refused_naming_the_file(tmp_path):
    from bushenv.search.corpus import CorpusError, load_case

    path = tmp_path / "case.json"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\xff")
    with pytest.raises(CorpusError, match=r"case\.json"):
        load_case(path)


def test_a_model_file_given_to_replay_is_named_a_model_file(tmp_path):
    from bushenv.models import get_model
    from bushenv.search.corpus import CorpusError, load_case

    path = get_model("linear", coords=3).save(tmp_path / "lin3.npz")
    with pytest.raises(CorpusError, match=r"lin3\.npz: a model file, not a divergence case"):
        load_case(path)


ATTACK = ["attack", "--model", "linear", "--hybrid", "linear", "--control", "linear"]


def test_attack_refuses_an_existing_report_without_resume_or_force(tmp_path, capsys):
    from bushenv.cli import main

    out = tmp_path / "a"
    out.mkdir()
    (out / "report.json").write_text('{"keep": true}')
    code = main([*ATTACK, "--budget", "1", "--out", str(out), "--no-plots"])
    err = capsys.readouterr().err
    assert code == 2
    assert "report.json exists; pass --resume to continue it or --force" in err
    assert (out / "report.json").read_text() == '{"keep": true}'


def test_attack_resume_refuses_a_report_of_another_format(tmp_path, capsys):
    from bushenv.cli import main

    out = tmp_path / "a"
    out.mkdir()
    (out / "report.json").write_text("{}")
    code = main([*ATTACK, "--budget", "1", "--out", str(out), "--resume", "--no-plots"])
    err = capsys.readouterr().err
    assert code == 2
    assert "report.json: not a bushenv attack report" in err
    assert (out / "report.json").read_text() == "{}"


@pytest.mark.parametrize("content", ['{"format": "bushenv-att', "[1, 2]"], ids=["torn", "list"])
def test_attack_resume_refuses_a_half_written_report_naming_it(tmp_path, capsys, content):
    from bushenv.cli import main

    out = tmp_path / "a"
    out.mkdir()
    (out / "report.json").write_text(content)
    code = main([*ATTACK, "--budget", "1", "--out", str(out), "--resume", "--no-plots"])
    err = capsys.readouterr().err
    assert code == 2
    assert "report.json" in err and "Traceback" not in err
