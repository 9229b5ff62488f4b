"""A campaign matrix: models x axes x searchers x seeds, fanned out over an execution backend.

    bushenv campaign --models nn,hybrid,boucwen --axes axial,radial \\
        --searchers random,cma,ppo --seeds 0-9 --budget 256 --out runs/matrix [--ray]

Each cell is one search run (``run_cell``), the attack's own stages for one model (resolve,
then search: ``campaign_resolve``, ``campaign_search``): the model (a name's default for the
axis, or a file) against ``--reference`` (default the rubber; a name, a file, or none), one
searcher, one seed, ``budget`` model evaluations. Cells are pure
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

import time
from dataclasses import dataclass, replace
from itertools import product
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.errors import BadInput
from bushenv.models import MODELS, ModelError, check_axis
from bushenv.persist import write_figure, write_json, write_text
from bushenv.progress import Progress
from bushenv.resolved import resolve_model
from bushenv.runlog import RunLog, run_cells
from bushenv.search.campaign_resolve import resolve_target
from bushenv.search.campaign_search import run_search
from bushenv.search.searchers import SEARCHERS
from bushenv.search.targets import TARGETS

WALL_CLOCK_FIELDS = ("seconds", "seconds_to_failure", "wall_s", "worker_backend")
CELL_KEYS = ("model", "axis", "searcher", "seed", "budget", "env", "reference")
MAX_SEEDS = 100_000  # a typo like 0-1000000000 must not build a billion cells


class MatrixError(BadInput):
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
    reference: str = "rubber",
) -> list[dict[str, Any]]:
    """One cell per model x axis x searcher x seed; ``reference`` "none": judged without one."""
    return [
        {
            "model": m,
            "axis": a,
            "searcher": s,
            "seed": int(seed),
            "budget": int(budget),
            "env": env,
            "reference": reference,
        }
        for m, a, s, seed in product(models, axes, searchers, seeds)
    ]


def run_cell(cell: dict[str, Any]) -> dict[str, Any]:
    """One search run; a pure function of ``cell`` (module-level, so any backend can ship it):
    the attack's stages for one model, resolve then search (``campaign_resolve``,
    ``campaign_search``)."""
    import torch

    torch.set_num_threads(1)
    resolved = resolve_target(
        cell["model"],
        cell.get("reference", "rubber"),
        axis=cell["axis"],
        target=cell["env"],
        trust_reference=bool(cell.get("trust_reference", False)),
    )
    t0 = time.perf_counter()
    key = resolved.target_key
    result = run_search(resolved, key, cell["searcher"], cell["budget"], cell["seed"])
    out = {**cell, **result.summary(), "judge": resolved.judge.describe()}
    out["wall_s"] = time.perf_counter() - t0
    return out


def comparable(row: dict[str, Any]) -> dict[str, Any]:
    """A result without its wall-clock fields: what two backends must agree on exactly."""
    return {
        k: v for k, v in row.items() if k not in (*WALL_CLOCK_FIELDS, "wall_s", "worker_backend")
    }


RESULT_KEYS = ("diverged", "evaluations", "evaluations_to_failure")


def _log(path: Path, progress: Progress | None = None) -> RunLog:
    say = progress.say if progress is not None else None
    return RunLog(path, CELL_KEYS, RESULT_KEYS, error=MatrixError, say=say)


def read_results(path: Path, require_results: bool = False) -> dict[str, dict[str, Any]]:
    """Finished cells by key (``RunLog.read``): holding ``CELL_KEYS`` and, with
    ``require_results``, ``RESULT_KEYS``; a torn last line is dropped, other corruption refused."""
    log = _log(path)
    if not require_results:
        log.result_keys = ()
    return log.read()


def _describe(row: dict[str, Any]) -> str:
    return (
        f"{row['model']:8s} {row['axis']:6s} {row['searcher']:6s} seed {row['seed']}: "
        f"{'DIVERGED' if row['diverged'] else 'bounded'} ({row['evaluations']} evals)"
    )


def run_matrix(
    cells: list[dict[str, Any]],
    out: Path,
    backend,
    resume: bool = False,
    progress: Progress | None = None,
) -> list[dict[str, Any]]:
    """Run every cell not yet in ``out/cells.jsonl``; returns all rows in cell order."""
    progress = progress or Progress(quiet=True)
    log = _log(Path(out) / "cells.jsonl", progress)
    return run_cells(cells, run_cell, log, backend, resume, progress, _describe, "matrix")


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
    write_json(out / "summary.json", summary, indent=2)
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
    write_text(
        out / "summary.md",
        "Divergence rate and median evaluations to failure, per model and searcher\n\n"
        + "\n".join(lines)
        + "\n",
    )
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
    write_figure(fig, out / "summary.png", dpi=110)


@dataclass(frozen=True)
class MatrixConfig:
    """A campaign matrix; ``bushenv campaign`` translates its arguments into this."""

    models: tuple[str, ...] = ("nn", "hybrid")
    axes: tuple[str, ...] = ("axial",)
    searchers: tuple[str, ...] = ("random", "cma")
    seeds: tuple[int, ...] = (0, 1, 2, 3)
    budget: int = 128
    target: str = "rig"
    reference: str = "rubber"  # a name, a model file, or "none": judged without one
    out: Path = Path("runs/matrix")
    resume: bool = False

    def checked(self) -> MatrixConfig:
        """Every name known, every model resolvable now (a missing default file must stop the
        matrix before it starts, not fail in a worker); raises ``MatrixError``."""
        if self.budget <= 0:
            raise MatrixError(
                f"--budget must be a positive number of evaluations, got {self.budget}"
            )
        if self.target in TARGETS and TARGETS[self.target].coords:
            raise MatrixError(
                f"--env {self.target}: the matrix runs one-axis models; attack a planar model "
                f"with: bushenv attack --env {self.target} --model PLANAR_MODEL"
            )
        for what, names, registry in (
            ("--models", self.models, MODELS),
            ("--searchers", self.searchers, SEARCHERS),
            ("--env", (self.target,), TARGETS),
        ):
            if not names:
                raise MatrixError(f"{what} names nothing")
            for n in names:
                if n not in registry:
                    raise MatrixError(registry.unknown_message(n))
        if not self.axes:
            raise MatrixError("--axes names nothing")
        for m, a in product(self.models, self.axes):
            check_axis(a)
            try:
                model = resolve_model(m, a, card=True)
            except ModelError as exc:
                raise MatrixError(f"model {m!r} ({a}): {exc}") from None
            try:  # the judge every cell of this model and axis gets, vetted before any runs
                resolve_target(model, self.reference, axis=a, target=self.target)
            except ModelError as exc:
                raise MatrixError(f"--reference {self.reference!r} ({a}): {exc}") from None
        out = Path(self.out)
        if out.exists() and not out.is_dir():
            raise MatrixError(f"--out {out}: exists and is not a folder")
        return replace(self, out=out)

    def cells(self) -> list[dict[str, Any]]:
        return make_cells(
            list(self.models),
            list(self.axes),
            list(self.searchers),
            list(self.seeds),
            self.budget,
            self.target,
            self.reference,
        )
