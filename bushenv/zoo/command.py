"""``bushenv zoo``: the population study, as a command (resumable, local pool or Ray).

    bushenv zoo --recipes teacher-forcing,free-run --models nn,hybrid --seeds 0-9 \\
        --axes axial,radial --out DIR [--searchers random,cma,certificate] [--budget 256]

Rows stream to ``DIR/cells.jsonl`` (``bushenv.runlog``), trained models to ``DIR/models``;
when every cell is done, ``DIR/summary.json``, ``summary.md`` and
``accuracy_vs_robustness.png``.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field
from itertools import product
from pathlib import Path
from typing import Any

from bushenv.errors import BadInput
from bushenv.execution import get_backend
from bushenv.identify.narx_options import RECIPES
from bushenv.models import AXES, check_axis
from bushenv.progress import Progress
from bushenv.runlog import RunLog, run_cells
from bushenv.search.matrix import parse_seeds
from bushenv.search.searchers import SEARCHERS
from bushenv.zoo.cell import run_cell
from bushenv.zoo.summary import recipe_label, write

EXAMPLE = (
    "bushenv zoo --recipes teacher-forcing,free-run --models nn,hybrid --seeds 0-9 "
    "--axes axial,radial --out runs/zoo"
)
NARX_MODELS = ("nn", "hybrid")  # the models with a recipe and a certificate
CELL_KEYS = ("recipe", "model", "axis", "seed", "budget", "searchers", "train_options")
RESULT_KEYS = ("accuracy", "attacks", "step", "certificate")
# Training time relative to teacher forcing, for the time left only (median of the 10-seed
# run in docs/recipes.md: teacher forcing 11 s, free run 52-72 s per model on a loaded machine).
RECIPE_EFFORT = {"teacher-forcing": 1.0, "free-run": 6.0}


class ZooError(BadInput):
    """Bad population-study settings or results file; the message says which."""


@dataclass
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
        self.out = Path(self.out)
        return self

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


def add_arguments(p: argparse.ArgumentParser) -> None:
    d = ZooConfig()
    p.add_argument("--recipes", default=",".join(d.recipes), help="training recipes")
    p.add_argument("--models", default=",".join(d.models), help="NARX models to train")
    p.add_argument("--axes", default=",".join(d.axes), help="bushing axes")
    p.add_argument("--seeds", default="0-9", help="training and record seeds, e.g. 0-9 or 1,4")
    p.add_argument("--searchers", default=",".join(d.searchers), help="searchers per model")
    p.add_argument("--budget", type=int, default=d.budget, help="evaluations per search")
    p.add_argument(
        "--certified",
        choices=("off", "on"),
        default="off",
        help="train every model with the certified-holds loss term (bushenv fit --certified on)",
    )
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--resume", action="store_true", help="continue an interrupted study")
    p.add_argument("--workers", type=int, default=None, help="local worker processes")
    p.add_argument("--ray", action="store_true", help="run on Ray (a local instance)")
    p.add_argument("--ray-address", default=None, help="run on an existing Ray cluster")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def _names(text: str) -> tuple[str, ...]:
    return tuple(n.strip() for n in text.split(",") if n.strip())


def _describe(row: dict[str, Any]) -> str:
    acc = row["accuracy"]["rms_ratio_n1"]
    verdict = "DIVERGED" if row["diverged"] else "bounded"
    return (
        f"{recipe_label(row):15s} {row['model']:6s} {row['axis']:6s} seed {row['seed']}: "
        f"RMS {100 * acc:.1f} %, {verdict} (trained in {row['train_s']:.0f} s)"
    )


def config_from(args: argparse.Namespace) -> ZooConfig:
    """The study the arguments describe (checked)."""
    return ZooConfig(
        recipes=_names(args.recipes),
        models=_names(args.models),
        axes=_names(args.axes),
        seeds=tuple(parse_seeds(args.seeds)),
        searchers=_names(args.searchers),
        budget=args.budget,
        out=Path(args.out),
        resume=args.resume,
        train_options={"certified": "on"} if args.certified == "on" else {},
    ).checked()


def run(args: argparse.Namespace) -> int:
    config = config_from(args)
    progress = Progress(quiet=args.quiet)
    log = RunLog(config.out / "cells.jsonl", CELL_KEYS, RESULT_KEYS, ZooError, progress.say)
    backend = get_backend(
        "ray" if (args.ray or args.ray_address) else "local",
        workers=args.workers,
        address=args.ray_address,
    )
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
    print((config.out / "summary.md").read_text())
    print(f"wrote {config.out}/cells.jsonl, summary.json, summary.md, accuracy_vs_robustness.png")
    return 0
