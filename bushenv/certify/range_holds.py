"""A network's fixed points on a grid of held deflection vectors over a range, without free
runs: what a model card says about holds (:func:`range_holds`), and the holds a search steps
to (:func:`suspect_holds`), for any number of coordinates C.

The holds are a ``GRID_POINTS``^C grid over +- a half-width per coordinate (rest among them);
at each, every fixed point of the network's recurrence and its stability (``fixed_points``),
and the folds crossing the grid's edges (counted). A hold whose free run can settle to more
than one force, or to none stably, is a hold the model cannot be trusted at; one whose stable
force pushes into the deflection (q . f below minus the floors' work) holds the wrong sign.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from bushenv.certify.fixed_points import FixedPoints, fixed_points, folds, grid
from bushenv.certify.network import CertifyError, narx_net

GRID_POINTS = 5  # per coordinate: 5^C holds, the zero deflection among them
KINDS = ("several_fixed_points", "no_stable_fixed_point", "pushes_into_the_deflection")


def held_grid(model: Any, spans, points: int = GRID_POINTS) -> tuple[FixedPoints, list]:
    """The fixed points of a NARX ``model`` on a grid of ``points`` values per coordinate over
    +- ``spans`` (C,), and the grid's axes; ``CertifyError`` for a model without a recurrence."""
    net = narx_net(model)
    spans = np.atleast_1d(np.asarray(spans, dtype=np.float64))
    if spans.size != net.n_coords:
        raise CertifyError(f"{spans.size} half-widths for a network of {net.n_coords} coordinates")
    axes = [np.linspace(-s, s, points) for s in spans]
    return fixed_points(net, grid(*axes)), axes


def range_holds(model: Any, peaks) -> dict[str, Any] | None:
    """The card's ``holds`` entry for a network (None for a model without a recurrence):
    ``peaks`` (C,) the training records' largest |q| (m, or rad for a rotation)."""
    t0 = time.perf_counter()
    try:
        fp, axes = held_grid(model, peaks)
    except CertifyError:
        return None
    crossings = folds(model, fp, axes, refine=False)  # counted, not located
    n = fp.count
    return {
        "range": [float(p) for p in np.atleast_1d(peaks)],
        "holds": int(len(n)),
        "fixed_points_per_hold": [int(n.min()), int(n.max())],
        "holds_with_more_than_one": int((n > 1).sum()),
        "holds_without_a_stable_one": int((fp.stable_count == 0).sum()),
        "largest_spectral_radius": float(fp.spectral_radius.max()) if n.sum() else None,
        "fold_crossings": len(crossings),
        "seconds": time.perf_counter() - t0,
    }


def describe(holds: dict[str, Any], units) -> list[str]:
    """One line of what the grid found (``units`` of the coordinates), and a warning line when
    a hold is not unique and stable."""
    shown = ", ".join(
        f"+-{v * 1e3:.3g} {'mrad' if u == 'rad' else 'mm'}"
        for v, u in zip(holds["range"], units, strict=True)
    )
    lo, hi = holds["fixed_points_per_hold"]
    line = (
        f"holds over the training range ({shown}; {holds['holds']} held vectors): {lo}-{hi} "
        f"fixed points per hold, {holds['holds_with_more_than_one']} with more than one, "
        f"{holds['holds_without_a_stable_one']} without a stable one, "
        f"{holds['fold_crossings']} fold crossings"
    )
    bad = holds["holds_with_more_than_one"] + holds["holds_without_a_stable_one"]
    if not bad:
        return [line]
    return [
        line,
        "warning: inside its own training range this network can settle to more than one force "
        "(or to none stably) at one held deflection; check it (bushenv attack, bushenv certify) "
        "or train it certified (--certified, or --structure mirror-rate over three axes)",
    ]


def suspect_holds(
    model: Any,
    spans,
    floors,
    far_fraction: float,
    points: int = GRID_POINTS,
) -> list[dict] | None:
    """The holds a search should step to: [{"q": (C,), "kinds"}] where the grid of
    :func:`held_grid` over +- ``spans`` finds several fixed points, none stable, or a stable
    force pushing into the deflection (q . f < -|q| . ``floors`` (C,), at a hold beyond
    ``far_fraction`` of the span in some coordinate); None for a model without a recurrence."""
    try:
        fp, _ = held_grid(model, spans, points)
    except CertifyError:
        return None
    spans = np.atleast_1d(np.asarray(spans, dtype=np.float64))
    q = fp.q[fp.hold]
    work = np.einsum("pi,pi->p", q, fp.force)
    far = np.max(np.abs(q) / spans, axis=1) >= far_fraction
    pushes = fp.stable & far & (work < -(np.abs(q) @ np.asarray(floors, dtype=np.float64)))
    pushing = np.bincount(fp.hold[pushes], minlength=len(fp.q)) > 0
    flags = np.stack([fp.count > 1, fp.stable_count == 0, pushing], axis=1)
    return [
        {"q": fp.q[h].tolist(), "kinds": [k for k, f in zip(KINDS, flags[h], strict=True) if f]}
        for h in np.flatnonzero(flags.any(axis=1))
    ]
