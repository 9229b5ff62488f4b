"""The planar attack's hold stage: every held deflection vector a planar network's fixed points
mark as suspect is simulated and judged, as ``campaign_holds`` does with the one-axis
certificate's holds.

Over a ``GRID_POINTS``^3 grid of held vectors within the searched limits (+- the stroke per
coordinate), every fixed point of the network's recurrence and its stability
(``certify.range_holds.suspect_holds``, any number of coordinates). A hold is listed when the
free run can settle to more than one force (``several_fixed_points``), to none stably
(``no_stable_fixed_point``), or holds a stable force that pushes into the deflection
(``pushes_into_the_deflection``: q . f below minus the floors' work, at a vector beyond
``vetting.SIGN_FRACTION`` of the stroke, the planar vetting's rule). For each listed hold a
profile ramps every coordinate from rest to it within its rate and holds
``campaign_holds.HOLD_PROFILE_S``; the judge confirms (a divergence) or refutes it, and
confirmed holds join the failures (rechecked, shrunk, kept).

A model that is not a planar network (no recurrence to hold) skips the stage; its budget is
the number of listed holds (at most ``campaign_holds.MAX_HOLDS``, spread over the grid).
"""

from __future__ import annotations

import numpy as np

from bushenv.search.base import SearchContext, Searcher
from bushenv.search.campaign_holds import HOLD_PROFILE_S, MAX_HOLDS, NAME
from bushenv.search.limits import Rig3Limits

GRID_POINTS = 5  # per coordinate: 125 held vectors, rest among them
KINDS = ("several_fixed_points", "no_stable_fixed_point", "pushes_into_the_deflection")
FAMILY = "step_hold3"

__all__ = ["NAME", "PlanarHolds", "listed_holds3", "step_and_hold3"]


def listed_holds3(model, limits: Rig3Limits, floors: np.ndarray) -> list[dict] | None:
    """The suspect holds of the module doc: [{"q": (3,) m, m, rad, "kinds"}]; None for a
    model that is not a planar network."""
    from bushenv.certify.range_holds import suspect_holds
    from bushenv.vetting import SIGN_FRACTION

    out = suspect_holds(model, limits.stroke, floors, SIGN_FRACTION, GRID_POINTS)
    if out is None:
        return None
    if len(out) > MAX_HOLDS:
        keep = np.unique(np.linspace(0, len(out) - 1, MAX_HOLDS).round().astype(int))
        out = [out[i] for i in keep]
    return out


def step_and_hold3(q, limits: Rig3Limits, dt: float) -> np.ndarray:
    """(T, 3) from rest to ``q``, every coordinate within its rate (all arriving together),
    then held ``HOLD_PROFILE_S``."""
    q = np.asarray(q, dtype=np.float64)
    n_ramp = max(1, int(np.ceil(np.max(np.abs(q) / (np.asarray(limits.rate) * dt)))))
    ramp = np.linspace(0.0, 1.0, n_ramp + 1)[:, None] * q[None, :]
    return np.concatenate([ramp, np.repeat(q[None, :], int(round(HOLD_PROFILE_S / dt)), axis=0)])


class PlanarHolds(Searcher):
    """The stage as a searcher over a fixed list of holds (``run`` ignores ``budget``);
    ``verdicts`` one row per hold once it ran."""

    name = NAME

    def __init__(self, holds: list[dict], limits: Rig3Limits) -> None:
        self.holds, self.limits = holds, limits
        self.verdicts: list[dict] = []

    def search(self, ctx: SearchContext) -> None:
        if not self.holds:
            return
        ev = ctx.evaluator
        profiles = [step_and_hold3(h["q"], self.limits, ev.dt) for h in self.holds]
        batch = ev.evaluate(profiles)
        ctx.recorder.record(batch, [FAMILY] * len(profiles), [None] * len(profiles))
        v = batch.verdict
        for b, h in enumerate(self.holds):
            row = v.row(b)
            held = [round(1e3 * x, 4) for x in h["q"]]
            self.verdicts.append({"q_mm_mm_mrad": held, "listed_as": h["kinds"],
                                  "confirmed": bool(row["diverged"]),
                                  "axis": row.get("axis") if row["diverged"] else None,
                                  "criterion": row["first_criterion"] if row["diverged"]
                                  else None})  # fmt: skip
        confirmed = sum(x["confirmed"] for x in self.verdicts)
        ctx.progress(f"{confirmed} of {len(self.holds)} listed holds confirmed by the judge")

    def entry(self) -> dict:
        """The report's ``hold_stage`` entry."""
        return {"run": True, "listed": len(self.holds), "grid_points": GRID_POINTS,
                "confirmed": sum(v["confirmed"] for v in self.verdicts),
                "holds": self.verdicts}  # fmt: skip
