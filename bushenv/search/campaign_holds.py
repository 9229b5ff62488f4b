"""The attack's hold stage: every hold the certificate lists as failing is simulated and judged.

``bushenv certify`` finds, without search, the holds where a NARX model's own-output recurrence
oscillates, departs or holds a wrong-sign force. A search with a finite budget may never step
to exactly those displacements (seed 0 of the default attack missed a -7.2 mm step that its
certificate listed). This stage makes the two agree: for each listed hold a profile steps to it
as fast as the bushing's velocity limit allows and holds ``HOLD_PROFILE_S`` (the papers' 4 mm
step was held 10 s, seed 000 §5.2); the judge confirms (a divergence) or refutes it. Confirmed
holds join the target's failures, so they are rechecked on the hybrid and the control, shrunk
and kept like any search's.

A model that is not a NARX network (no certificate) skips the stage; it is a stage, not a
searcher, so its budget is the number of listed holds (at most ``MAX_HOLDS``, spread over the
stroke).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv.certify import CertifyError, CertifyOptions, certify
from bushenv.progress import Progress
from bushenv.search.base import SearchContext, Searcher
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_resolve import Resolved
from bushenv.search.campaign_search import Searched, search_one

NAME = "cert-holds"
HOLD_PROFILE_S = 10.0
MAX_HOLDS = 64
KINDS = ("oscillates", "departs", "wrong_sign")


def listed_holds(model, reference, stroke_m: float) -> list[dict] | None:
    """The certificate's failing holds: [{"x_m", "kinds"}], or None for a non-NARX model."""
    try:
        cert = certify(model, reference, CertifyOptions(stroke_m=stroke_m))
    except CertifyError:
        return None
    out = []
    for h in cert.document["holds"]:
        kinds = [k for k in KINDS if h.get(k)]
        if kinds:
            out.append({"x_m": float(h["x_m"]), "kinds": kinds})
    if len(out) > MAX_HOLDS:
        keep = np.unique(np.linspace(0, len(out) - 1, MAX_HOLDS).round().astype(int))
        out = [out[i] for i in keep]
    return out


def step_and_hold(x_m: float, velocity_m_per_s: float, dt: float) -> np.ndarray:
    """From rest to ``x_m`` at the velocity limit, then held ``HOLD_PROFILE_S``."""
    n_ramp = max(1, int(np.ceil(abs(x_m) / (velocity_m_per_s * dt))))
    ramp = np.linspace(0.0, x_m, n_ramp + 1)
    return np.concatenate([ramp, np.full(int(round(HOLD_PROFILE_S / dt)), x_m)])


class CertificateHolds(Searcher):
    """The stage as a searcher over a fixed list of profiles (``run`` ignores ``budget``)."""

    name = NAME

    def __init__(self, holds: list[dict]) -> None:
        self.holds = holds
        self.verdicts: list[dict] = []

    def search(self, ctx: SearchContext) -> None:
        if not self.holds:
            return
        evaluator, recorder, progress = ctx.evaluator, ctx.recorder, ctx.progress
        dt, vmax = evaluator.dt, evaluator.scales.velocity_m_per_s
        profiles = [step_and_hold(h["x_m"], vmax, dt) for h in self.holds]
        batch = evaluator.evaluate(profiles)
        recorder.record(batch, ["step_hold"] * len(profiles), [None] * len(profiles))
        v = batch.verdict
        for b, h in enumerate(self.holds):
            self.verdicts.append(
                {
                    "x_mm": round(h["x_m"] * 1e3, 4),
                    "listed_as": h["kinds"],
                    "confirmed": bool(v.diverged[b]),
                    "criterion": v.first_criterion[b] if v.diverged[b] else None,
                }
            )
        progress(
            f"{sum(x['confirmed'] for x in self.verdicts)} of {len(self.holds)} listed holds "
            "confirmed by the judge"
        )


@dataclass(frozen=True)
class HoldStage:
    """The stage's outcome: the search summary filed under ``NAME`` beside the target's
    searches (None: no search ran) and the report's ``hold_stage`` entry (None: resumed)."""

    summary: Mapping[str, Any] | None = None
    entry: Mapping[str, Any] | None = None

    def searched(self, resolved: Resolved, out) -> Searched:
        """The stage's search as a ``Searched`` (to merge with the target's searches)."""
        runs = {resolved.target_key: {NAME: self.summary}} if self.summary else {}
        return Searched(out, runs)


def hold_stage(
    resolved: Resolved,
    config: CampaignConfig,
    threads: int,
    progress: Progress,
    searched: Searched,
) -> HoldStage:
    """Simulate every hold the target's certificate lists as failing (a resumed report that
    holds the stage's search is left as it is)."""
    key = resolved.target_key
    if NAME in searched.of(key):
        progress.say(f"[{key}] {NAME}: done earlier (resumed)")
        return HoldStage()
    model = resolved.models[key].model
    holds = listed_holds(model, resolved.judge.reference, resolved.judge.scales.stroke_m)
    if holds is None:
        return HoldStage(entry={"run": False, "why": "not a NARX network (no certificate)"})
    if not holds:
        progress.say(f"[{key}] {NAME}: the certificate lists none")
        return HoldStage(entry={"run": True, "listed": 0, "confirmed": 0, "holds": []})
    stage = CertificateHolds(holds)
    summary = search_one(resolved, key, NAME, config, threads, progress, stage, len(holds))
    entry = {
        "run": True,
        "listed": len(holds),
        "confirmed": sum(v["confirmed"] for v in stage.verdicts),
        "holds": stage.verdicts,
    }
    return HoldStage(summary, entry)
