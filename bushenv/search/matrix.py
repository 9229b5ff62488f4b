"""A campaign matrix: models x axes x searchers x seeds, fanned out over an execution backend.

    bushenv campaign --models nn,hybrid,boucwen --axes axial,radial \\
        --searchers random,cma,ppo --seeds 0-9 --budget 256 --out runs/matrix [--ray]

Each cell is one search run (``run_cell``): the model's default for the axis against the
reference rubber bushing, one searcher, one seed, ``budget`` model evaluations. Cells are pure
functions of their description, so the local process pool and a Ray cluster give the same
results for the same seeds (wall-clock fields aside: ``seconds``, ``seconds_to_failure``).

Results stream to ``DIR/cells.jsonl`` (one JSON line per finished cell, flushed and fsynced) as
they finish, in whatever order; an interrupted matrix resumes with ``--resume`` and runs only
the missing cells. A torn last line (the process was killed mid-write) is detected and dropped
with a message; any other corrupt line is an error naming the line. When all cells are done,
``DIR/summary.json``, ``DIR/summary.md`` and ``DIR/summary.png`` give, per model and searcher,
the divergence rate and the median evaluations to failure.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from itertools import product
from pathlib import Path
from typing import Any

import numpy as np

EXAMPLE = (
    "bushenv campaign --models nn,hybrid --axes axial --searchers random,cma "
    "--seeds 0-3 --budget 128 --out runs/matrix"
)
WALL_CLOCK_FIELDS = ("seconds", "seconds_to_failure", "wall_s", "worker_backend")
CELL_KEYS = ("model", "axis", "searcher", "seed", "budget", "env")
MAX_SEEDS = 100_000  # a typo like 0-1000000000 must not build a billion cells


class MatrixError(ValueError):
    """Bad matrix arguments or a corrupt results file."""


def parse_seeds(text: str) -> list[int]:
    """``"0-9"`` -> 0..9, ``"1,4,7"`` -> [1, 4, 7], ``"3"`` -> [3]."""
    seeds: list[int] = []
    try:
        for part in text.split(","):
            part = part.strip()
            if "-" in part[1:]:
                lo, hi = part.split("-", 1) if not part.startswith("-") else (part, "")
                a, b = int(lo), int(hi)
                if b < a:
                    raise MatrixError(f"seed range {part!r} runs backwards")
                if b - a + 1 + len(seeds) > MAX_SEEDS:
                    raise MatrixError(
                        f"--seeds {text!r} names {b - a + 1 + len(seeds)} seeds, more than "
                        f"{MAX_SEEDS} (one search run each)"
                    )
                seeds.extend(range(a, b + 1))
            elif part:
                seeds.append(int(part))
    except ValueError as exc:
        if isinstance(exc, MatrixError):
            raise
        raise MatrixError(f"--seeds {text!r}: expected e.g. 0-9 or 1,4,7") from None
    if not seeds:
        raise MatrixError(f"--seeds {text!r} names no seed")
    negative = [s for s in seeds if s < 0]
    if negative:
        raise MatrixError(f"--seeds {text!r}: seeds must be >= 0, got {negative[0]}")
    return seeds


def cell_key(cell: dict[str, Any]) -> str:
    return "|".join(str(cell[k]) for k in CELL_KEYS)


def make_cells(
    models: list[str],
    axes: list[str],
    searchers: list[str],
    seeds: list[int],
    budget: int,
    env: str = "rig",
) -> list[dict[str, Any]]:
    return [
        {"model": m, "axis": a, "searcher": s, "seed": int(seed), "budget": int(budget), "env": env}
        for m, a, s, seed in product(models, axes, searchers, seeds)
    ]


def run_cell(cell: dict[str, Any]) -> dict[str, Any]:
    """One search run; a pure function of ``cell`` (module-level, so any backend can ship it)."""
    import torch

    torch.set_num_threads(1)
    from bushenv.models import get_model
    from bushenv.search.corpus import truth_reference
    from bushenv.search.evaluate import BatchEvaluator
    from bushenv.search.searchers import get_searcher

    reference = truth_reference(cell["axis"])
    model = get_model(cell["model"], axis=cell["axis"], dt=reference.dt)
    t0 = time.perf_counter()
    with BatchEvaluator(model, reference, target=cell["env"], threads=1, axis=cell["axis"]) as ev:
        result = get_searcher(cell["searcher"]).run(ev, cell["budget"], seed=cell["seed"])
    out = {**cell, **result.summary()}
    out["wall_s"] = time.perf_counter() - t0
    return out


def comparable(row: dict[str, Any]) -> dict[str, Any]:
    """A result without its wall-clock fields: what two backends must agree on exactly."""
    return {
        k: v for k, v in row.items() if k not in (*WALL_CLOCK_FIELDS, "wall_s", "worker_backend")
    }


RESULT_KEYS = ("diverged", "evaluations", "evaluations_to_failure")


def read_results(path: Path, require_results: bool = False) -> dict[str, dict[str, Any]]:
    """Finished cells by key; drops a torn final line, refuses corruption elsewhere.

    A line is a finished cell when it is a JSON object holding the cell's keys (``CELL_KEYS``)
    and, with ``require_results`` (as ``run_matrix`` reads), the result fields
    ``RESULT_KEYS``. Only the last line may be torn (a kill mid-write): it is dropped and cut
    from the file, so the cell runs again on resume. A complete last line that lost only its
    newline is kept and the newline restored, so the next append starts a line of its own.
    """
    done: dict[str, dict[str, Any]] = {}
    if not path.exists():
        return done
    if not path.is_file():
        raise MatrixError(f"{path}: not a regular file")
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise MatrixError(
            f"{path}: not a results file (not UTF-8 text at byte {exc.start}); "
            "move it away or pass another --out"
        ) from None
    lines = text.splitlines()
    for i, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        row = _result_row(line, require_results)
        if row is None:
            if i == len(lines):
                print(f"{path} line {i}: incomplete last line (interrupted write) dropped")
                _truncate_last_line(path)
                continue
            raise MatrixError(f"{path} line {i}: corrupt result line; fix or remove it") from None
        done[cell_key(row)] = row
    if text and not text.endswith("\n") and path.read_bytes() == raw:
        with path.open("a") as fh:
            fh.write("\n")
    return done


def _result_row(line: str, require_results: bool) -> dict[str, Any] | None:
    """The row a results line holds, or None when it is not a complete result."""
    try:
        row = json.loads(line)
    except json.JSONDecodeError:
        return None
    needed = (*CELL_KEYS, *RESULT_KEYS) if require_results else CELL_KEYS
    if not isinstance(row, dict) or any(k not in row for k in needed):
        return None
    return row


def _truncate_last_line(path: Path) -> None:
    text = path.read_text()
    keep = text[: text.rstrip("\n").rfind("\n") + 1] if "\n" in text.rstrip("\n") else ""
    tmp = path.with_suffix(".tmp")
    tmp.write_text(keep)
    os.replace(tmp, path)


def _append(path: Path, row: dict[str, Any]) -> None:
    with path.open("a") as fh:
        fh.write(json.dumps(row, sort_keys=True, default=_plain) + "\n")
        fh.flush()
        os.fsync(fh.fileno())


def _plain(o: Any) -> Any:
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(type(o))


def run_matrix(
    cells: list[dict[str, Any]],
    out: Path,
    backend,
    resume: bool = False,
    progress=print,
) -> list[dict[str, Any]]:
    """Run every cell not yet in ``out/cells.jsonl``; returns all rows in cell order."""
    out.mkdir(parents=True, exist_ok=True)
    results_path = out / "cells.jsonl"
    done = read_results(results_path, require_results=True) if resume else {}
    if not resume and results_path.exists():
        raise MatrixError(f"{results_path} exists; pass --resume to continue or --out elsewhere")
    todo = [c for c in cells if cell_key(c) not in done]
    progress(
        f"matrix: {len(cells)} cells, {len(cells) - len(todo)} already done, "
        f"{len(todo)} to run on {backend.name} ({backend.workers} workers)"
    )
    t0 = time.perf_counter()
    for n, (i, row) in enumerate(backend.imap_unordered(run_cell, todo), start=1):
        row["worker_backend"] = backend.name
        _append(results_path, row)
        done[cell_key(todo[i])] = row
        progress(
            f"  [{n}/{len(todo)}] {row['model']:8s} {row['axis']:6s} {row['searcher']:6s} "
            f"seed {row['seed']}: {'DIVERGED' if row['diverged'] else 'bounded'} "
            f"({row['evaluations']} evals, {time.perf_counter() - t0:.0f} s)"
        )
    return [done[cell_key(c)] for c in cells]


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per model and searcher: runs, divergence rate, median evaluations to failure."""
    table: dict[str, dict[str, Any]] = {}
    for r in rows:
        cell = table.setdefault(r["model"], {}).setdefault(
            r["searcher"], {"runs": 0, "diverged": 0, "evals": []}
        )
        cell["runs"] += 1
        if r["diverged"]:
            cell["diverged"] += 1
            cell["evals"].append(r["evaluations_to_failure"])
    for per in table.values():
        for cell in per.values():
            ev = cell.pop("evals")
            cell["divergence_rate"] = cell["diverged"] / cell["runs"]
            cell["median_evaluations_to_failure"] = float(np.median(ev)) if ev else None
    return table


def write_summary(out: Path, summary: dict[str, Any]) -> None:
    tmp = out / "summary.json.tmp"
    tmp.write_text(json.dumps(summary, indent=2))
    os.replace(tmp, out / "summary.json")
    searchers = sorted({s for per in summary.values() for s in per})
    lines = [
        "| model | " + " | ".join(searchers) + " |",
        "|---|" + "---|" * len(searchers),
    ]
    for model, per in summary.items():
        cells = []
        for s in searchers:
            c = per.get(s)
            if c is None:
                cells.append("")
                continue
            med = c["median_evaluations_to_failure"]
            cells.append(
                f"{100 * c['divergence_rate']:.0f} % of {c['runs']}"
                + (f", median {med:.0f} evals" if med is not None else "")
            )
        lines.append(f"| {model} | " + " | ".join(cells) + " |")
    tmp = out / "summary.md.tmp"
    tmp.write_text(
        "Divergence rate and median evaluations to failure, per model and searcher\n\n"
        + "\n".join(lines)
        + "\n"
    )
    os.replace(tmp, out / "summary.md")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    models = list(summary)
    rate = np.array(
        [[summary[m].get(s, {}).get("divergence_rate", np.nan) for s in searchers] for m in models]
    )
    fig, ax = plt.subplots(figsize=(1.6 + 1.3 * len(searchers), 1.2 + 0.6 * len(models)))
    im = ax.imshow(rate, vmin=0, vmax=1, cmap="Reds")
    ax.set_xticks(range(len(searchers)), searchers)
    ax.set_yticks(range(len(models)), models)
    for i, m in enumerate(models):
        for j, s in enumerate(searchers):
            c = summary[m].get(s)
            if c:
                med = c["median_evaluations_to_failure"]
                ax.text(
                    j,
                    i,
                    f"{100 * c['divergence_rate']:.0f}%\n{'' if med is None else f'{med:.0f} ev'}",
                    ha="center",
                    va="center",
                    fontsize=8,
                )
    fig.colorbar(im, ax=ax, label="divergence rate")
    ax.set_title("campaign matrix")
    fig.tight_layout()
    fig.savefig(out / "summary.png", dpi=110)
    plt.close(fig)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--models", default="nn,hybrid", help="comma list of model names")
    p.add_argument("--axes", default="axial", help="comma list: axial, radial")
    p.add_argument("--searchers", default="random,cma", help="comma list: random, cma, ppo, sac")
    p.add_argument("--seeds", default="0-3", help="e.g. 0-9 or 1,4,7")
    p.add_argument("--budget", type=int, default=128, help="model evaluations per cell (> 0)")
    p.add_argument("--env", choices=("rig", "quartercar"), default="rig")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--resume", action="store_true", help="continue an interrupted matrix")
    p.add_argument("--workers", type=int, default=None, help="local worker processes")
    p.add_argument("--ray", action="store_true", help="run on Ray (a local instance)")
    p.add_argument("--ray-address", default=None, help="run on an existing Ray cluster")


def run(args: argparse.Namespace) -> int:
    from bushenv.cli import CliError
    from bushenv.execution import BackendError, get_backend
    from bushenv.models import AXES, model_names
    from bushenv.search.searchers import SEARCHERS

    if args.budget <= 0:
        raise CliError(f"--budget must be a positive number of evaluations, got {args.budget}")
    models = [m for m in args.models.split(",") if m]
    known = set(model_names())
    for m in models:
        if m not in known:
            raise CliError(f"unknown model {m!r}; known: {sorted(known)}")
    axes = [a for a in args.axes.split(",") if a]
    for a in axes:
        if a not in AXES:
            raise CliError(f"unknown axis {a!r}; known: {list(AXES)}")
    searchers = [s for s in args.searchers.split(",") if s]
    for s in searchers:
        if s not in (*SEARCHERS, "ppo", "sac"):
            raise CliError(f"unknown searcher {s!r}; known: {sorted(SEARCHERS) + ['ppo', 'sac']}")
    for what, names in (("--models", models), ("--axes", axes), ("--searchers", searchers)):
        if not names:
            raise CliError(f"{what} {getattr(args, what[2:])!r} names nothing")
    try:
        seeds = parse_seeds(args.seeds)
    except MatrixError as exc:
        raise CliError(str(exc)) from None
    # Resolve every model now: a missing default file must stop the matrix before it starts,
    # not fail in a worker after the output folder exists.
    from bushenv.models import ModelError, get_model

    for m, a in product(models, axes):
        try:
            get_model(m, axis=a)
        except ModelError as exc:
            raise CliError(f"model {m!r} ({a}): {exc}") from None
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise CliError(f"--out {out}: exists and is not a folder")
    cells = make_cells(models, axes, searchers, seeds, args.budget, args.env)
    try:
        backend = get_backend(
            "ray" if (args.ray or args.ray_address) else "local",
            workers=args.workers,
            address=args.ray_address,
        )
    except BackendError as exc:
        raise CliError(str(exc)) from None
    with backend:
        try:
            rows = run_matrix(cells, out, backend, resume=args.resume)
        except MatrixError as exc:
            raise CliError(str(exc)) from None
    summary = summarise(rows)
    write_summary(out, summary)
    print((out / "summary.md").read_text())
    print(f"wrote {out}/cells.jsonl, summary.json, summary.md, summary.png")
    return 0
