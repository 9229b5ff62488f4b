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

import numpy as np

from bushenv.certify import CertifyError, CertifyOptions, certify
from bushenv.search.base import Searcher

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

    def _search(self, evaluator, budget, rng, recorder, seed, progress) -> None:
        if not self.holds:
            return
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
