"""The population study behind ``bushenv zoo`` (resumable, local pool or Ray; the command's
arguments are parsed in ``bushenv/commands/zoo.py``).

    bushenv zoo --recipes teacher-forcing,free-run --models nn,hybrid --seeds 0-9 \\
        --axes axial,radial --out DIR [--searchers random,cma,certificate] [--budget 256]

Rows stream to ``DIR/cells.jsonl`` (``bushenv.runlog``), trained models to ``DIR/models``;
when every cell is done, ``DIR/summary.json``, ``summary.md`` and
``accuracy_vs_robustness.png``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from itertools import product
from pathlib import Path
from typing import Any

from bushenv.errors import BadInput
from bushenv.identify.narx_options import RECIPES
from bushenv.models import AXES, check_axis
from bushenv.progress import Progress
from bushenv.runlog import RunLog, run_cells
from bushenv.search.searchers import SEARCHERS
from bushenv.zoo.cell import run_cell
from bushenv.zoo.summary import recipe_label, write

NARX_MODELS = ("nn", "hybrid")  # the models with a recipe and a certificate
CELL_KEYS = ("recipe", "model", "axis", "seed", "budget", "searchers", "train_options")
RESULT_KEYS = ("accuracy", "attacks", "step", "certificate")
# Training time relative to teacher forcing, for the time left only (median of the 10-seed
# run in studies/2026-11-training-recipes: teacher forcing 11 s, free run 52-72 s per model
# on a loaded machine).
RECIPE_EFFORT = {"teacher-forcing": 1.0, "free-run": 6.0}


class ZooError(BadInput):
    """Bad population-study settings or results file; the message says which."""


@dataclass(frozen=True)
class ZooConfig:
    recipes: tuple[str, ...] = RECIPES
    models: tuple[str, ...] = NARX_MODELS
    axes: tuple[str, ...] = AXES
    seeds: tuple[int, ...] = tuple(range(10))
    searchers: tuple[str, ...] = ("random", "cma", "certificate")
    budget: int = 256
    out: Path = Path("runs/zoo")
    resume: bool = False
    train_options: dict = field(default_factory=dict)  # NARX options beyond the recipe

    def checked(self) -> ZooConfig:
        for flag, names, known in (
            ("--recipes", self.recipes, RECIPES),
            ("--models", self.models, NARX_MODELS),
            ("--searchers", self.searchers, SEARCHERS.names()),
        ):
            bad = [n for n in names if n not in known]
            if bad or not names:
                raise ZooError(f"{flag}: unknown {bad}; known names: {', '.join(known)}")
        for a in self.axes:
            check_axis(a)
        if self.budget < 1:
            raise ZooError(f"--budget must be >= 1 evaluation, got {self.budget}")
        return replace(self, out=Path(self.out))

    def cells(self) -> list[dict[str, Any]]:
        return [
            {
                "recipe": r,
                "model": m,
                "axis": a,
                "seed": int(s),
                "budget": self.budget,
                "searchers": ",".join(self.searchers),
                "out": str(self.out),
                "train_options": dict(self.train_options),
            }
            for r, m, a, s in product(self.recipes, self.models, self.axes, self.seeds)
        ]


def _describe(row: dict[str, Any]) -> str:
    acc = row["accuracy"]["rms_ratio_n1"]
    verdict = "DIVERGED" if row["diverged"] else "bounded"
    return (
        f"{recipe_label(row):15s} {row['model']:6s} {row['axis']:6s} seed {row['seed']}: "
        f"RMS {100 * acc:.1f} %, {verdict} (trained in {row['train_s']:.0f} s)"
    )


def run_study(config: ZooConfig, backend, progress: Progress) -> list[dict[str, Any]]:
    """Every cell of ``config`` not yet in ``config.out/cells.jsonl``, on ``backend``; the
    summary written; all rows returned."""
    log = RunLog(config.out / "cells.jsonl", CELL_KEYS, RESULT_KEYS, ZooError, progress.say)
    with backend:
        rows = run_cells(
            config.cells(),
            run_cell,
            log,
            backend,
            config.resume,
            progress,
            _describe,
            "zoo",
            weight=lambda cell: RECIPE_EFFORT.get(cell["recipe"], 6.0),
        )
    write(config.out, rows)
    return rows
