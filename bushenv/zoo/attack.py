"""The searches a population member is given, with the same searchers and the same budget.

One coordinate: each searcher of the attack (``campaign_search.run_search``) against the
reference rubber. Several: first the single-axis check, each searcher over ``one_axis`` only
(the one-axis rig families in one coordinate at a time, the others at rest; random search draws
the coordinate, CMA-ES searches it): a member passes when no profile fails in the coordinate it
drives, on any axis, which is all a single-axis rig measures (a failure in a coordinate at rest
is counted apart); then the attack across axes, each searcher over the families over all
coordinates (``campaign_search.family_search``), its failures in a coordinate the profile moves
counted apart too (a member whose only failures are force in a coordinate held at rest has
wrong coupling, not a runaway).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.search.campaign_resolve import Resolved
from bushenv.search.campaign_search import family_search, run_search, tally


def attack(resolved: Resolved, searcher: str, budget: int, seed: int) -> dict[str, Any]:
    """One search of the attack's on a one-coordinate member."""
    res = run_search(resolved, resolved.target_key, searcher, budget, seed)
    ff = res.first_failure
    return {
        "diverged": res.diverged,
        "evaluations_to_failure": ff.evaluation if ff else None,
        "first_criterion": ff.verdict["first_criterion"] if ff else None,
        "first_family": ff.family if ff else None,
        "criteria": sorted({c for f in res.failures for c in f.verdict["criteria"]}),
        "families": sorted({f.family for f in res.failures}),
        "n_failures": res.n_failures,
        "worst_robustness": res.worst.robustness if res.worst else None,
    }


def _moving(candidate) -> np.ndarray:
    """The coordinates a profile moves."""
    return np.flatnonzero(np.any(candidate.profile != 0, axis=0))


def driven_failed(candidate, coords: tuple[str, ...]) -> bool:
    """Whether a profile over ``coords`` failed in a coordinate it moves."""
    rob = candidate.verdict["axis_robustness"]
    return any(rob[coords[i]] is not None and rob[coords[i]] < 0 for i in _moving(candidate))


def single_axis(model, reference, coords, searcher: str, budget: int, seed: int) -> dict:
    """The single-axis check of a member over several coordinates (module docstring)."""
    res = family_search(model, reference, searcher, budget, seed, family="one_axis")
    driven = [c for c in res.failures if driven_failed(c, coords)]
    by_axis = dict.fromkeys(coords, 0)
    for c in driven:  # a one_axis profile moves one coordinate
        for i in _moving(c):
            by_axis[coords[i]] += 1
    return {
        "evaluations": res.evaluations,
        "driven_failures": len(driven),
        "driven_failures_by_axis": by_axis,
        "cross_axis_failures": res.n_failures - len(driven),
        "passed": not driven,
    }


def across_axes(model, reference, coords, searcher: str, budget: int, seed: int) -> dict:
    """The attack across axes of a member over several coordinates (module docstring)."""
    res = family_search(model, reference, searcher, budget, seed)
    ff = res.first_failure
    t = tally(res.failures, coords)
    # failures in a coordinate the profile moves: not only force in a coordinate held at rest
    moving = [c.evaluation for c in res.failures if driven_failed(c, coords)]
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
