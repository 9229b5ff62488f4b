"""One member of the population: train a NARX model of the target's number of coordinates C,
judge its accuracy, check its holds, attack it.

A cell is (recipe, model, seed) and, with one coordinate, the axis. Its training record and
two unseen ones are made from the cell's seed (so the records vary too):

- one coordinate: the reference rubber measured through its load cell (noise, delay, fixture
  inertia) on an n = 1 random drive of 40 s; unseen n = 1 and n = 1.5 records of 20 s, as
  ``bushenv reproduce`` does; the holds and the papers' step (``holds.py``) and the attack's
  searches (``attack.py``) on the member resolved as the attack resolves it;
- several: the coupled reference on 60 s of independent random motion at n = 1 in every
  coordinate (``scripts/planar_benchmark.py``'s record); unseen independent and correlated
  records of 20 s, accuracy per coordinate; the hold check, the single-axis check and the
  attack across axes, judged by the coupled reference.

``run_cell`` is a pure function of the cell (module-level, so any backend can ship it); the
model file it trains is written under the cell's ``out``.
"""

from __future__ import annotations

import time
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from bushenv import metrics
from bushenv.identify import fit
from bushenv.machine import random_test
from bushenv.models.base import PAPER_DT
from bushenv.motions import random_correlated, random_independent
from bushenv.reference.planar import PlanarRubber
from bushenv.reference.rubber import RubberBushing
from bushenv.resolved import resolved as resolved_as
from bushenv.search.campaign_resolve import resolve_target
from bushenv.search.targets import TARGETS
from bushenv.zoo import attack, holds
from bushenv.zoo.rates import shown_options

TRAIN_S = {1: 40.0, 3: 60.0}  # the reproduction's record length; the planar benchmark's
UNSEEN_S = 20.0
# The recipes as training options: a one-coordinate network takes the recipe by name (at the
# papers' size, no choice of size on validation); the MIMO training's two stages are one step
# ahead only, or then free-run windows too (its default).
RECIPE_OPTIONS = {
    1: {"teacher-forcing": {"recipe": "teacher-forcing"}, "free-run": {"recipe": "free-run"}},
    3: {"teacher-forcing": {"free_run_steps": 0}, "free-run": {}},
}
DEFAULT_OPTIONS = {1: {"choose": "off"}, 3: {}}


def coordinate_count(env: str) -> int:
    """C of the env's target (1 for a target whose profiles are (T,))."""
    return max(1, len(TARGETS[env].coords))


def cell_name(cell: dict[str, Any]) -> str:
    extra = "".join(f"-{x}" for x in shown_options(cell.get("train_options", {})))
    where = [cell["axis"]] if "axis" in cell else []
    env = [cell["env"]] if "env" in cell else []
    return "-".join([*env, f"{cell['recipe']}{extra}", cell["model"], *where, f"s{cell['seed']}"])


def records(coords: int, seed: int, axis: str | None = None):
    """The training record (a ``Record``, or a (q, f) pair) and the unseen ones by name, each
    a (displacement, force) pair."""
    other, far = seed + 7919, seed + 104729
    if coords == 1:
        train = random_test(RubberBushing.preset(axis, seed=seed), 1.0, TRAIN_S[1], seed=seed)
        seen = random_test(RubberBushing.preset(axis, seed=other), 1.0, UNSEEN_S, other)
        beyond = random_test(RubberBushing.preset(axis, seed=far), 1.5, UNSEEN_S, far)
        unseen = {"rms_ratio_n1": seen, "rms_ratio_n15": beyond}
        return train, {k: (r.displacement, r.force) for k, r in unseen.items()}
    q = random_independent(1.0, TRAIN_S[coords], PAPER_DT, seed)
    train = (q, PlanarRubber.preset(seed=seed).simulate(q))
    unseen = {}
    for name, make in (("independent", random_independent), ("correlated", random_correlated)):
        qu = make(1.0, UNSEEN_S, PAPER_DT, other)
        unseen[name] = (qu, PlanarRubber.preset(seed=other).simulate(qu))
    return train, unseen


def accuracy(model, unseen, coords: tuple[str, ...]) -> dict[str, Any]:
    """RMS ratio (free run) on each unseen record: one number, or one per coordinate."""
    out = {}
    for name, (q, f) in unseen.items():
        pred = model.simulate(q)
        out[name] = (
            {c: metrics.rms_ratio(f[:, i], pred[:, i]) for i, c in enumerate(coords)}
            if coords
            else metrics.rms_ratio(f, pred)
        )
    return out


def network_share(model, unseen, coords: tuple[str, ...]) -> dict[str, float] | None:
    """A hybrid's network part (its force less its backbone's alone, ``backbone_alone``) as an
    RMS ratio of the measured force on the unseen correlated record, per coordinate: how much of
    the model is network (None for the pure networks, all network). A certified hybrid whose
    share is ~0 is its backbone."""
    backbone = model.backbone_alone()
    if backbone is None:
        return None
    q, f = unseen["correlated"]
    part = model.simulate(q) - backbone.simulate(q)
    rms = np.sqrt(np.mean(f**2, axis=0))
    return {c: float(np.sqrt(np.mean(part[:, i] ** 2)) / rms[i]) for i, c in enumerate(coords)}


def _on_one_axis(cell, model, path, train, unseen) -> dict[str, Any]:
    """The attack's resolve stage on the member as trained (its file hashed, no card read),
    then its holds, the papers' step and the attack."""
    axis, seed = cell["axis"], int(cell["seed"])
    resolved = resolve_target(resolved_as(path, model, axis), "rubber", axis=axis)
    step = holds.steps(resolved)
    searches = cell["searchers"].split(",")
    attacks = {s: attack.attack(resolved, s, int(cell["budget"]), seed) for s in searches}
    return {
        "accuracy": accuracy(model, unseen, ()),
        "certificate": holds.certificate(model, resolved.judge.reference),
        "step": step,
        "attacks": attacks,
        "diverged": any(a["diverged"] for a in attacks.values()),
        "static_error_4mm": holds.static_error(step),
    }


def _across_axes(cell, model, path, train, unseen) -> dict[str, Any]:
    """The hold check, the single-axis check and the attack across axes, judged by the
    coupled reference."""
    from bushenv.judge import BUILTIN_REFERENCE
    from bushenv.resolved import resolve_model

    coords = TARGETS[cell["env"]].coords
    seed, budget = int(cell["seed"]), int(cell["budget"])
    reference = resolve_model(
        BUILTIN_REFERENCE, dt=model.dt, reference=True, coords=len(coords)
    ).model
    searchers = cell["searchers"].split(",")
    certificate = holds.hold_check(model, train, PAPER_DT, coords)
    check = partial(attack.single_axis, model, reference, coords)
    single = {s: check(s, budget, seed) for s in searchers}
    across = partial(attack.across_axes, model, reference, coords)
    attacks = {s: across(s, budget, seed) for s in searchers}
    return {
        "accuracy": accuracy(model, unseen, coords),
        "network_share": network_share(model, unseen, coords),
        "certificate": certificate,
        # the certified training's own verdict on the weights it kept (None: not certified)
        "certified_admitted": getattr(model, "training", {}).get("certified", {}).get("admitted"),
        "single_axis": single,
        "attacks": attacks,
        "passed_single_axis": all(v["passed"] for v in single.values()),
        "diverged": any(a["diverged"] for a in attacks.values()),
        "diverged_moving": any(a["moving_failures"] > 0 for a in attacks.values()),
    }


def run_cell(cell: dict[str, Any]) -> dict[str, Any]:
    """Train, judge, check and attack one member; the row the population study keeps."""
    import torch

    torch.set_num_threads(1)
    coords = coordinate_count(cell.get("env", "rig"))
    seed = int(cell["seed"])
    train, unseen = records(coords, seed, cell.get("axis"))
    options = {
        **DEFAULT_OPTIONS[coords],
        **RECIPE_OPTIONS[coords][cell["recipe"]],
        **cell.get("train_options", {}),
    }
    if coords > 1 and cell["model"] == "hybrid":  # a member under study: never the backbone alone
        options.setdefault("network", "always")
    fitted = fit([train], cell["model"], options, seed, progress=False, dt=PAPER_DT)
    model = fitted.model
    path = model.save(Path(cell["out"]) / "models" / f"{cell_name(cell)}.npz")
    t1 = time.perf_counter()
    stages = _on_one_axis if coords == 1 else _across_axes
    row = {
        **cell,
        "model_file": str(path.relative_to(cell["out"])),
        "train_s": fitted.seconds,
        **stages(cell, model, path, train, unseen),
    }
    row["judge_s"] = time.perf_counter() - t1
    return row
