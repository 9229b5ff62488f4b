"""A fitted planar network's fixed points over its own training range: what its card says about
holds, so a fit that can settle to two forces at one held deflection says so when it is made.

The holds are a ``GRID_POINTS``^3 grid over +- the training records' largest deflection per
coordinate; at each, every fixed point of the network's recurrence and its stability
(``fixed_points``), and the fold-surface crossings on the grid's edges (counted). A hold
whose free run can settle to more than one force, or to none stably, is a hold the model
cannot be trusted at, inside the range it was fitted on (docs/planar.md, "Passivity").
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from bushenv.models.planar_narx import PlanarNarx
from bushenv.planar.fixed_points import fixed_points, fold_crossings, grid

GRID_POINTS = 5  # per coordinate: 125 holds, the zero deflection among them


def range_holds(model: Any, peaks: np.ndarray) -> dict[str, Any] | None:
    """The card's ``holds`` entry for a network (None for a model without a recurrence):
    ``peaks`` (3,) the training records' largest |q| (m, m, rad)."""
    if not isinstance(model, PlanarNarx):
        return None
    t0 = time.perf_counter()
    axes = [np.linspace(-p, p, GRID_POINTS) for p in np.asarray(peaks, dtype=np.float64)]
    fp = fixed_points(model, grid(*axes))
    folds = fold_crossings(model, *axes, fp=fp, refine=False)  # counted, not located
    n = fp.count
    return {
        "range": [float(p) for p in peaks],
        "holds": int(len(n)),
        "fixed_points_per_hold": [int(n.min()), int(n.max())],
        "holds_with_more_than_one": int((n > 1).sum()),
        "holds_without_a_stable_one": int((fp.stable_count == 0).sum()),
        "largest_spectral_radius": float(fp.spectral_radius.max()) if n.sum() else None,
        "fold_crossings": len(folds),
        "seconds": time.perf_counter() - t0,
    }


def describe(holds: dict[str, Any]) -> list[str]:
    """One line of what the grid found, and a warning line when a hold is not unique and
    stable."""
    a, r, t = holds["range"]
    lo, hi = holds["fixed_points_per_hold"]
    line = (
        f"holds over the training range (+-{a * 1e3:.3g} mm, +-{r * 1e3:.3g} mm, "
        f"+-{t * 1e3:.3g} mrad; {holds['holds']} held vectors): {lo}-{hi} fixed points per hold, "
        f"{holds['holds_with_more_than_one']} with more than one, "
        f"{holds['holds_without_a_stable_one']} without a stable one, "
        f"{holds['fold_crossings']} fold crossings"
    )
    bad = holds["holds_with_more_than_one"] + holds["holds_without_a_stable_one"]
    if not bad:
        return [line]
    return [
        line,
        "warning: inside its own training range this network can settle to more than one force "
        "(or to none stably) at one held deflection; check it (bushenv attack --env rig3) or "
        "train it certified (--certified on --structure mirror-rate)",
    ]
