"""The population study behind ``bushenv zoo`` (resumable, local pool or Ray; the command's
arguments are parsed in ``bushenv/commands/zoo.py``).

    bushenv zoo --recipes teacher-forcing,free-run --models nn,hybrid --seeds 0-9 \\
        --axes axial,radial --out DIR [--searchers random,cma,certificate] [--budget 256]
    bushenv zoo --env rig3 --recipes teacher-forcing,free-run --models nn,hybrid --seeds 0-9 \\
        --out DIR [--searchers random,cma] [--budget 256]

The study's number of coordinates C is its target's (``bushenv.search.targets``): one for
``rig`` (a cell per axis), three for ``rig3`` (a cell drives all coordinates). Rows stream to
``DIR/cells.jsonl`` (``bushenv.runlog``), trained models to ``DIR/models``; when every cell is
done, ``DIR/summary.json`` and ``summary.md`` (``summary.py``; with one coordinate also
``accuracy_vs_robustness.png``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from itertools import product
from pathlib import Path
from typing import Any

from bushenv.errors import BadInput
from bushenv.identify.mimo_options import MimoHybridOptions
from bushenv.identify.narx_options import RECIPES
from bushenv.models import AXES, check_axis
from bushenv.models.planar_narx import KINDS
from bushenv.progress import Progress
from bushenv.runlog import RunLog, run_cells
from bushenv.search.campaign_search import HELD_TO
from bushenv.search.searchers import SEARCHERS
from bushenv.search.targets import TARGETS
from bushenv.zoo.cell import coordinate_count, run_cell
from bushenv.zoo.rates import recipe_label
from bushenv.zoo.summary import write

ENVS = ("rig", "rig3")
NARX_MODELS = ("nn", "hybrid")  # the one-coordinate models with a recipe and a certificate
# Training time relative to teacher forcing, for the time left only. One coordinate: median
# of the 10-seed run in studies/2026-11-training-recipes (teacher forcing 11 s, free run
# 52-72 s per model on a loaded machine). Three: 60 members at budget 256, one worker (5.0 s
# teacher forcing, 7.1 s with the free-run stage); the certified term's fixed points and step
# runs at every step cost 4x (seed 0).
RECIPE_EFFORT = {
    1: {"teacher-forcing": 1.0, "free-run": 6.0},
    3: {"teacher-forcing": 1.0, "free-run": 1.4},
}
CERTIFIED_EFFORT = {1: 1.0, 3: 4.0}


class ZooError(BadInput):
    """Bad population-study settings or results file; the message says which."""


def cell_keys(coords: int) -> tuple[str, ...]:
    """What names a cell in the results file: one coordinate, its axis; more, the env (a
    one-coordinate file keeps the keys it always had)."""
    where = ("axis",) if coords == 1 else ()
    env = () if coords == 1 else ("env",)
    return (*env, "recipe", "model", *where, "seed", "budget", "searchers", "train_options")


def result_keys(coords: int) -> tuple[str, ...]:
    checks = ("step", "certificate") if coords == 1 else ("single_axis",)
    return ("accuracy", "attacks", *checks)


@dataclass(frozen=True)
class ZooConfig:
    """A population; ``None`` fields take the defaults of the env's number of coordinates."""

    env: str = "rig"
    recipes: tuple[str, ...] | None = None
    models: tuple[str, ...] = ("nn", "hybrid")
    axes: tuple[str, ...] | None = None  # one coordinate: the axes a cell is trained on
    seeds: tuple[int, ...] = tuple(range(10))
    searchers: tuple[str, ...] | None = None
    budget: int = 256
    out: Path | None = None
    resume: bool = False
    train_options: dict = field(default_factory=dict)  # training options beyond the recipe

    @property
    def coords(self) -> int:
        return coordinate_count(self.env)

    def checked(self) -> ZooConfig:
        if self.env not in ENVS:
            raise ZooError(f"--env: unknown {self.env!r}; known: {', '.join(ENVS)}")
        one = self.coords == 1
        if not one and self.axes is not None:
            raise ZooError(
                f"--axes: --env {self.env} drives all {self.coords} coordinates; leave --axes out"
            )
        recipes = self.recipes or (RECIPES if one else ("teacher-forcing", "free-run"))
        searchers = self.searchers or (
            ("random", "cma", "certificate") if one else TARGETS[self.env].default_searchers
        )
        known_models = NARX_MODELS if one else tuple(KINDS)
        known_searchers = SEARCHERS.names() if one else tuple(HELD_TO)
        on = "" if one else f" for --env {self.env}"
        for flag, names, known in (
            ("--recipes", recipes, RECIPES),
            ("--models", self.models, known_models),
            ("--searchers", searchers, known_searchers),
        ):
            bad = [n for n in names if n not in known]
            if bad or not names:
                raise ZooError(f"{flag}: unknown {bad}{on}; known names: {', '.join(known)}")
        axes = self.axes if self.axes is not None else (AXES if one else None)
        for a in axes or ():
            check_axis(a)
        if self.budget < 1:
            raise ZooError(f"--budget must be >= 1 evaluation, got {self.budget}")
        self._check_training(one)
        out = (
            Path(self.out) if self.out is not None else Path("runs/zoo" if one else "runs/zoo-rig3")
        )
        return replace(self, recipes=recipes, axes=axes, searchers=tuple(searchers), out=out)

    def _check_training(self, one: bool) -> None:
        if one:
            for flag, name in (("--training", "training"), ("--structure", "structure")):
                if name in self.train_options:
                    raise ZooError(
                        f"{flag}: an option of the networks over several coordinates; "
                        "use it with --env rig3"
                    )
            return
        unknown = sorted(set(self.train_options) - set(MimoHybridOptions.__dataclass_fields__))
        if unknown:
            raise ZooError(f"training options over {self.coords} coordinates: unknown {unknown}")
        if "training" in self.train_options and set(self.models) != {"hybrid"}:
            raise ZooError("--training is the hybrid's option: give it with --models hybrid")

    def cells(self) -> list[dict[str, Any]]:
        c = self.checked()
        where = [{"axis": a} for a in c.axes] if c.coords == 1 else [{"env": c.env}]
        return [
            {
                **w,
                "recipe": r,
                "model": m,
                "seed": int(s),
                "budget": c.budget,
                "searchers": ",".join(c.searchers),
                "out": str(c.out),
                # sorted: the results file's key is its text, and JSON lines are written sorted
                "train_options": dict(sorted(c.train_options.items())),
            }
            for r, m, w, s in product(c.recipes, c.models, where, c.seeds)
        ]


def refuse_other_kind(path: Path, coords: int) -> None:
    """Refuse to resume a results file of a study over another number of coordinates (rows
    over one lack ``env``, rows over several ``axis``): the results file would read them as
    torn lines and cut the last one."""
    if not path.is_file():
        return
    with path.open(encoding="utf-8", errors="replace") as fh:
        first = next((line for line in fh if line.strip()), "")
    try:
        row = json.loads(first)
    except json.JSONDecodeError:
        return  # the results file's own reading names a corrupt line
    if isinstance(row, dict) and ("env" in row) != (coords > 1):
        kind = f"MIMO (--env {row['env']})" if "env" in row else "one-axis (--env rig)"
        raise ZooError(f"{path} line 1: a {kind} study's results; resume it with that --env")


def _describe(row: dict[str, Any]) -> str:
    trained = f"(trained in {row['train_s']:.0f} s)"
    if "axis" in row:
        acc = row["accuracy"]["rms_ratio_n1"]
        verdict = "DIVERGED" if row["diverged"] else "bounded"
        return (
            f"{recipe_label(row):15s} {row['model']:6s} {row['axis']:6s} seed {row['seed']}: "
            f"RMS {100 * acc:.1f} %, {verdict} {trained}"
        )
    single = "passes single-axis" if row["passed_single_axis"] else "fails single-axis"
    broken = "BROKEN across axes" if row["diverged"] else "bounded across axes"
    who = f"{recipe_label(row):15s} {row['model']:7s} seed {row['seed']}"
    return f"{who}: {single}, {broken} {trained}"


def _weight(cell: dict[str, Any]) -> float:
    c = coordinate_count(cell.get("env", "rig"))
    certified = cell["train_options"].get("certified") == "on"
    return RECIPE_EFFORT[c][cell["recipe"]] * (CERTIFIED_EFFORT[c] if certified else 1.0)


def run_study(config: ZooConfig, backend, progress: Progress) -> list[dict[str, Any]]:
    """Every cell of ``config`` not yet in ``config.out/cells.jsonl``, on ``backend``; the
    summary written; all rows returned."""
    config = config.checked()
    c = config.coords
    judge = None if c == 1 else _vetted_reference(config.env, progress)
    log = RunLog(config.out / "cells.jsonl", cell_keys(c), result_keys(c), ZooError, progress.say)
    what = "zoo" if c == 1 else f"zoo {config.env}"
    with backend:
        rows = run_cells(
            config.cells(),
            run_cell,
            log,
            backend,
            config.resume,
            progress,
            _describe,
            what,
            _weight,
        )
    write(config.out, rows, c, judge)
    return rows


def _vetted_reference(env: str, progress: Progress) -> dict[str, Any]:
    """Every member over several coordinates is judged by the coupled reference: it is vetted
    once, before any member."""
    from bushenv.judge import BUILTIN_REFERENCE
    from bushenv.models.base import PAPER_DT
    from bushenv.resolved import resolve_model
    from bushenv.search.campaign_limits import vetted_within

    target = TARGETS[env]
    reference = resolve_model(BUILTIN_REFERENCE, dt=PAPER_DT, reference=True,
                              coords=len(target.coords)).model  # fmt: skip
    return vetted_within(reference, BUILTIN_REFERENCE, target, progress.say, error=ZooError)[1]
