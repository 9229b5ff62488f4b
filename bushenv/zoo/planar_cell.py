"""One member of the MIMO population (``bushenv zoo --env rig3``): train a planar network, give
it the single-axis check, then the attack across axes.

A cell is (recipe, model, seed). Its training record is the coupled planar reference measured
through its load cell on 60 s of independent random motion at n = 1 in all three coordinates,
drive and noise seeds the cell's seed (``scripts/planar_benchmark.py``'s record); two unseen
20 s records (independent and correlated, n = 1) give its accuracy per coordinate. Then, with
the same searchers and the same budget per search:

- the single-axis check: each searcher over ``one_axis`` only (the one-axis rig families in one
  coordinate at a time, the others at rest; random search draws the coordinate, CMA-ES searches
  it). A member passes when no profile fails in the coordinate it drives, on any axis: that is
  all a single-axis rig measures. A failure in a coordinate at rest is counted apart;
- its hold check (``identify.mimo_certified.check``, certified or not): fixed points over a
  7^3 grid of the rig3 box, out of the records' static band, unstable, or not settling after a step;
- the attack across axes: each searcher over the planar families (``campaign_planar``'s search);
  its failures in a coordinate the profile moves are counted apart too (a member whose only
  failures are force in a coordinate held at rest has wrong coupling, not a runaway).

``run_planar_cell`` is a pure function of the cell (module-level, so any backend can ship it).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from bushenv import metrics
from bushenv.identify import fit as fit_model
from bushenv.models.base import PAPER_DT
from bushenv.motions import random_correlated, random_independent
from bushenv.reference.planar import PlanarRubber
from bushenv.search.campaign_planar import DEFAULT_REFERENCE, planar_search, tally
from bushenv.search.limits import COORDS
from bushenv.search.planar_models import resolve_planar_spec
from bushenv.zoo.summary import shown_options

TRAIN_S, UNSEEN_S = 60.0, 20.0
# The MIMO training's two stages (``identify.mimo_train``): one step ahead only, or then
# free-run windows too (the default training); the recipes' names are the one-axis zoo's.
PLANAR_RECIPES = {"teacher-forcing": {"free_run_steps": 0}, "free-run": {}}


def planar_cell_name(cell: dict[str, Any]) -> str:
    extra = "".join(f"-{x}" for x in shown_options(cell.get("train_options", {})))
    return f"planar-{cell['recipe']}{extra}-{cell['model']}-s{cell['seed']}"


def _certificate(model, train) -> dict[str, Any]:
    """The MIMO hold check (``identify.mimo_certified.check``: fixed points over the 7^3 grid of
    the rig3 box, their static force against the training record's estimate, their spectral
    radius, the run after a step) of any member, certified or not."""
    from bushenv.identify.mimo_certified import MimoCertifiedHolds
    from bushenv.identify.static_estimate import static_estimate

    q, f = train
    n = q.shape[0] - int(0.2 * q.shape[0])  # the training part (the default val_fraction)
    estimate = static_estimate([(q[:n], f[:n])], PAPER_DT, COORDS)
    out = MimoCertifiedHolds(1.0).check(model, estimate)
    out["failing_holds"] = len(out["failing_holds"])
    return out


def planar_records(seed: int):
    """(q, f) of the training record and of the two unseen ones (independent, correlated)."""
    q = random_independent(1.0, TRAIN_S, PAPER_DT, seed)
    train = (q, PlanarRubber.preset(seed=seed).simulate(q))
    other = seed + 7919
    unseen = {}
    for name, make in (("independent", random_independent), ("correlated", random_correlated)):
        qu = make(1.0, UNSEEN_S, PAPER_DT, other)
        unseen[name] = (qu, PlanarRubber.preset(seed=other).simulate(qu))
    return train, unseen


def _accuracy(model, unseen) -> dict[str, dict[str, float]]:
    """RMS ratio per coordinate on each unseen record (free run)."""
    out = {}
    for name, (q, f) in unseen.items():
        pred = model.simulate(q)
        out[name] = {c: metrics.rms_ratio(f[:, i], pred[:, i]) for i, c in enumerate(COORDS)}
    return out


def _network_share(model, unseen) -> dict[str, float] | None:
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
    return {c: float(np.sqrt(np.mean(part[:, i] ** 2)) / rms[i]) for i, c in enumerate(COORDS)}


def driven_failed(candidate) -> bool:
    """Whether a single-axis profile failed in a coordinate it moves."""
    moving = np.flatnonzero(np.any(candidate.profile != 0, axis=0))
    rob = candidate.verdict["axis_robustness"]
    return any(rob[COORDS[i]] is not None and rob[COORDS[i]] < 0 for i in moving)


def _single_axis(model, reference, searcher: str, budget: int, seed: int) -> dict[str, Any]:
    res = planar_search(model, reference, searcher, budget, seed, family="one_axis")
    driven = [c for c in res.failures if driven_failed(c)]
    by_axis = {c: 0 for c in COORDS}
    for c in driven:  # a one_axis profile moves one coordinate
        for i in np.flatnonzero(np.any(c.profile != 0, axis=0)):
            by_axis[COORDS[i]] += 1
    return {
        "evaluations": res.evaluations,
        "driven_failures": len(driven),
        "driven_failures_by_axis": by_axis,
        "cross_axis_failures": res.n_failures - len(driven),
        "passed": not driven,
    }


def _attack(model, reference, searcher: str, budget: int, seed: int) -> dict[str, Any]:
    res = planar_search(model, reference, searcher, budget, seed)
    ff = res.first_failure
    t = tally(res.failures)
    # failures in a coordinate the profile moves: not only force in a coordinate held at rest
    moving = [c.evaluation for c in res.failures if driven_failed(c)]
    return {
        "diverged": res.diverged,
        "moving_failures": len(moving),
        "moving_evaluations_to_failure": min(moving) if moving else None,
        "evaluations": res.evaluations,
        "evaluations_to_failure": ff.evaluation if ff else None,
        "first_family": ff.family if ff else None,
        "first_axis": ff.verdict.get("axis") if ff else None,
        "first_criterion": ff.verdict["first_criterion"] if ff else None,
        "n_failures": res.n_failures,
        "in_a_coordinate_at_rest": t["in_a_coordinate_at_rest"],
        "by_family": t["by_family"],
        "by_axis": t["by_axis"],
        "worst_robustness": res.worst.robustness if res.worst else None,
    }


def run_planar_cell(cell: dict[str, Any]) -> dict[str, Any]:
    """Train, check on single axes and attack across axes one member; the row kept."""
    import torch

    torch.set_num_threads(1)
    seed, budget = int(cell["seed"]), int(cell["budget"])
    train, unseen = planar_records(seed)
    options = {**PLANAR_RECIPES[cell["recipe"]], **cell.get("train_options", {})}
    if cell["model"] == "hybrid":  # a member is a network under study: never the backbone alone
        options.setdefault("network", "always")
    fit = fit_model([train], cell["model"], options, seed, progress=False, dt=PAPER_DT)
    model = fit.model
    path = model.save(Path(cell["out"]) / "models" / f"{planar_cell_name(cell)}.npz")
    reference = resolve_planar_spec(DEFAULT_REFERENCE, model.dt, "--reference")
    t1 = time.perf_counter()
    certificate = _certificate(model, train)
    searchers = cell["searchers"].split(",")
    single = {s: _single_axis(model, reference, s, budget, seed) for s in searchers}
    attacks = {s: _attack(model, reference, s, budget, seed) for s in searchers}
    return {
        **cell,
        "model_file": str(path.relative_to(cell["out"])),
        "train_s": fit.seconds,
        "accuracy": _accuracy(model, unseen),
        "network_share": _network_share(model, unseen),
        "certificate": certificate,
        # the certified training's own verdict on the weights it kept (None: not certified)
        "certified_admitted": getattr(model, "training", {}).get("certified", {}).get("admitted"),
        "single_axis": single,
        "attacks": attacks,
        "passed_single_axis": all(v["passed"] for v in single.values()),
        "diverged": any(a["diverged"] for a in attacks.values()),
        "diverged_moving": any(a["moving_failures"] > 0 for a in attacks.values()),
        "judge_s": time.perf_counter() - t1,
    }
