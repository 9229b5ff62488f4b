"""What a population member does at rest and under a held deflection.

One coordinate: its hold certificate over the stroke (``bushenv.certify``: folds, departures,
wrong-sign holds, the least stable attractor, the bands where it generates energy about rest)
and the papers' step (seed 000 §5.2: +-4 mm held 10 s, judged by ``bushenv.divergence``, its
held force beside the reference's). Several: the hold check of the certified training
(``identify.mimo_certified.check``, certified or not): fixed points over a 7^C grid of the
target's box, out of the records' static band, unstable, or not settling after a step.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv import excitation as ex
from bushenv.certify import CertifyOptions, certify
from bushenv.search.campaign_resolve import Resolved

STEP_M = 4e-3  # the papers' step (seed 000 §5.2)
STEP_HOLD_S = 10.0
CERTIFY = CertifyOptions(holds=101, energy_amplitudes_m=(), passivity_holds_m=(0.0,))
CERTIFICATE_KEYS = (
    "folds",
    "departing_holds",
    "wrong_sign_holds",
    "wrong_sign_ranges_m",
    "static_off_holds",
    "max_reached_spectral_radius",
    "non_passive_bands_hz_at_rest",
    "passes_holds",
)


def certificate(model, reference) -> dict[str, Any]:
    """The hold certificate's summary of a one-coordinate member."""
    s = certify(model, reference, CERTIFY).document["summary"]
    return {k: s[k] for k in CERTIFICATE_KEYS}


def hold_check(model, train, dt: float, coords: tuple[str, ...]) -> dict[str, Any]:
    """The hold check of a member over several coordinates: its fixed points' static force
    against the training record's estimate, their spectral radius, the run after a step."""
    from bushenv.identify.mimo_certified import MimoCertifiedHolds
    from bushenv.identify.static_estimate import static_estimate

    q, f = train
    n = q.shape[0] - int(0.2 * q.shape[0])  # the training part (the default val_fraction)
    estimate = static_estimate([(q[:n], f[:n])], dt, coords)
    out = MimoCertifiedHolds(1.0).check(model, estimate)
    out["failing_holds"] = len(out["failing_holds"])
    return out


def steps(resolved: Resolved) -> dict[str, Any]:
    """The papers' step both ways: verdict, departure time, held force beside the reference's."""
    dt = resolved.dt
    out = {}
    profiles = [ex.step_hold(s * STEP_M, STEP_HOLD_S, dt, pre_s=1.0) for s in (1, -1)]
    with resolved.evaluator(resolved.target_key) as ev:
        batch = ev.evaluate(profiles)
    departure = batch.verdict.criterion_first_s["self_sustained"]
    for b, name in enumerate(("+4mm", "-4mm")):
        row = batch.verdict.row(b)
        f_m, f_r = float(batch.f_model[-1, b]), float(batch.f_ref[-1, b])
        out[name] = {
            "bounded": not row["diverged"],
            "criteria": row["criteria"],
            # the free run leaves its hold (self_sustained), s after the profile's start
            "departure_s": None if np.isnan(departure[b]) else float(departure[b]),
            "held_force_n": f_m,
            "reference_held_force_n": f_r,
            "wrong_sign": bool(f_m * f_r < 0),
        }
    return out


def static_error(step: dict[str, Any]) -> float:
    """The member's held force at the papers' step against the reference's, both ways."""
    return float(
        np.mean(
            [
                abs(v["held_force_n"] - v["reference_held_force_n"])
                / abs(v["reference_held_force_n"])
                for v in step.values()
            ]
        )
    )
