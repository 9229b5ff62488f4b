"""The MIMO population study behind ``bushenv zoo --env rig3`` (resumable, local pool or Ray).

    bushenv zoo --env rig3 --recipes teacher-forcing,free-run --models nn,hybrid --seeds 0-9 \\
        --out DIR [--searchers random,cma] [--budget 256]

Members (``planar_cell.py``) stream to ``DIR/cells.jsonl`` (``bushenv.runlog``), trained
networks to ``DIR/models``; when every member is done, ``DIR/summary.json`` and ``summary.md``
(``planar_summary.py``). The one-axis study (``study.py``) is untouched by this one.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from itertools import product
from pathlib import Path
from typing import Any

from bushenv.identify.mimo_options import MimoHybridOptions
from bushenv.models.planar_narx import KINDS
from bushenv.progress import Progress
from bushenv.runlog import RunLog, run_cells
from bushenv.search.campaign_planar import HELD_TO
from bushenv.search.targets import TARGETS
from bushenv.zoo.planar_cell import PLANAR_RECIPES, run_planar_cell
from bushenv.zoo.planar_summary import write
from bushenv.zoo.study import ZooError
from bushenv.zoo.summary import recipe_label

PLANAR_CELL_KEYS = ("env", "recipe", "model", "seed", "budget", "searchers", "train_options")
PLANAR_RESULT_KEYS = ("accuracy", "single_axis", "attacks")
# A member's wall time relative to teacher forcing, for the time left only (60 members at
# budget 256, one worker: 5.0 s teacher forcing, 7.1 s with the free-run stage).
PLANAR_EFFORT = {"teacher-forcing": 1.0, "free-run": 1.4}
CERTIFIED_EFFORT = 4.0  # the certified term's fixed points and step runs at every step (seed 0)


@dataclass(frozen=True)
class PlanarZooConfig:
    recipes: tuple[str, ...] = tuple(PLANAR_RECIPES)
    models: tuple[str, ...] = ("nn", "hybrid")
    seeds: tuple[int, ...] = tuple(range(10))
    searchers: tuple[str, ...] = TARGETS["rig3"].default_searchers
    budget: int = 256
    out: Path = Path("runs/zoo-rig3")
    resume: bool = False
    train_options: dict = field(default_factory=dict)  # planar network options beyond the recipe

    def checked(self) -> PlanarZooConfig:
        for flag, names, known in (
            ("--recipes", self.recipes, tuple(PLANAR_RECIPES)),
            ("--models", self.models, tuple(KINDS)),
            ("--searchers", self.searchers, tuple(HELD_TO)),
        ):
            bad = [n for n in names if n not in known]
            if bad or not names:
                raise ZooError(
                    f"{flag}: unknown {bad} for --env rig3; known names: {', '.join(known)}"
                )
        if self.budget < 1:
            raise ZooError(f"--budget must be >= 1 evaluation, got {self.budget}")
        unknown = sorted(set(self.train_options) - set(MimoHybridOptions.__dataclass_fields__))
        if unknown:
            raise ZooError(f"planar training options: unknown {unknown}")
        if "training" in self.train_options and set(self.models) != {"hybrid"}:
            raise ZooError("--training is the hybrid's option: give it with --models hybrid")
        return replace(self, out=Path(self.out))

    def cells(self) -> list[dict[str, Any]]:
        return [
            {
                "env": "rig3",
                "recipe": r,
                "model": m,
                "seed": int(s),
                "budget": self.budget,
                "searchers": ",".join(self.searchers),
                "out": str(self.out),
                # sorted: the results file's key is its text, and JSON lines are written sorted
                "train_options": dict(sorted(self.train_options.items())),
            }
            for r, m, s in product(self.recipes, self.models, self.seeds)
        ]


def refuse_other_kind(path: Path, planar: bool) -> None:
    """Refuse to resume a results file of the other study (one-axis rows lack ``env``, planar
    rows ``axis``): the results file would read them as torn lines and cut the last one."""
    if not path.is_file():
        return
    with path.open(encoding="utf-8", errors="replace") as fh:
        first = next((line for line in fh if line.strip()), "")
    try:
        row = json.loads(first)
    except json.JSONDecodeError:
        return  # the results file's own reading names a corrupt line
    if isinstance(row, dict) and ("env" in row) != planar:
        kind = "MIMO (--env rig3)" if "env" in row else "one-axis (--env rig)"
        raise ZooError(f"{path} line 1: a {kind} study's results; resume it with that --env")


def _describe(row: dict[str, Any]) -> str:
    single = "passes single-axis" if row["passed_single_axis"] else "fails single-axis"
    broken = "BROKEN across axes" if row["diverged"] else "bounded across axes"
    return (
        f"{recipe_label(row):15s} {row['model']:7s} seed {row['seed']}: {single}, {broken} "
        f"(trained in {row['train_s']:.0f} s)"
    )


def run_planar_study(config: PlanarZooConfig, backend, progress: Progress) -> list[dict[str, Any]]:
    """Every member of ``config`` not yet in ``config.out/cells.jsonl``, on ``backend``; the
    summary written; all rows returned."""
    judge = _vetted_reference(progress)
    log = RunLog(
        config.out / "cells.jsonl", PLANAR_CELL_KEYS, PLANAR_RESULT_KEYS, ZooError, progress.say
    )
    with backend:
        rows = run_cells(
            config.cells(),
            run_planar_cell,
            log,
            backend,
            config.resume,
            progress,
            _describe,
            "zoo rig3",
            weight=lambda cell: (
                PLANAR_EFFORT.get(cell["recipe"], 1.4)
                * (CERTIFIED_EFFORT if cell["train_options"].get("certified") == "on" else 1.0)
            ),
        )
    write(config.out, rows, judge)
    return rows


def _vetted_reference(progress: Progress) -> dict[str, Any]:
    """Every member is judged by the coupled reference: it is vetted once, before any member."""
    from bushenv.models.base import PAPER_DT
    from bushenv.search.campaign_planar import DEFAULT_REFERENCE, vetted_judge
    from bushenv.search.planar_models import resolve_planar_spec

    reference = resolve_planar_spec(DEFAULT_REFERENCE, PAPER_DT, "reference")
    return vetted_judge(reference, DEFAULT_REFERENCE, TARGETS["rig3"], progress, error=ZooError)
