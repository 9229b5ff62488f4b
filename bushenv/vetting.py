"""The reference is checked before it judges (``judge.build_judge`` calls ``vet_reference``).

A verdict says "the model departs from the real bushing"; it is worth only what the reference
is. Every check's verdict is *pass*, *fail* or *not checked* (``Check.passed`` True, False or
None; the detail of a "not checked" names what was missing and how to supply it). The vetting
*passed* only when every check passed; it *failed* when one failed (the reference is refused
unless ``--trust-reference``); otherwise it is *not fully checked* and the reference judges,
saying which checks it did not pass. The checks, each with a physical reason and a threshold:

1. **holds** over the judged stroke: ramp to each of ``HOLDS`` displacements in 0.25 s, hold
   ``HOLD_S``. A passive bushing only relaxes in a hold: its force never oscillates, never grows
   away from its value after the first second, and pushes back (``f x > 0``). Flagged
   (``certify.reached_holds.judge_holds``): *oscillating*, *departing*, *wrong sign* (beyond
   ``SIGN_FRACTION`` of the stroke), *not finite*, each against one threshold tied to the
   reference itself (``certify.reached_holds.ring_threshold``: the larger of 3 x its own noise
   in these holds and 1 % of its largest held force), at most the verdicts' force floor.
2. **certificate holds** (NARX references: ``nn``, ``hybrid`` or their files): the reference's
   own certificate (``bushenv certify``, reference-free: wrong sign against the deflection)
   lists the holds where it oscillates, departs or pulls. Each is reached the way a search
   reaches it -- a step at the velocity limit, and sines inside the reference's envelope then
   the hold (``certify.reached_holds.confirm_holds``) -- and judged with the same threshold. A
   confirmed one fails the check; with ``--trust-reference`` every verdict whose profile enters
   its range is marked unvetted (``Vetting.unvetted_ranges_m``).
3. **records**: the reference's RMS ratio on the records its model card names at most
   ``RECORD_LIMIT``: 30 % is beyond every fitted model of the papers (Tables 2-4) and beyond
   any model worth judging with. Not checked without a card or without its records. The
   built-in rubber passes: it is the specimen every record here is measured on.
4. **compatibility** with the model under test: on the records the model's own card names,
   the reference's RMS ratio at most ``RECORD_LIMIT`` (it is a model of the same bushing: a
   reference 3.2 times as stiff is refused). With no such records, the least-squares stiffness
   of both on one random drive within the stroke is compared: within a factor
   ``scales.STIFFNESS_MISMATCH`` (2) it passes; beyond, it is *not checked* (undecided), not a
   refusal -- the model under suspicion is then the only word on which bushing it is, and a
   broken model looks like another bushing; the model's card with its records decides.

Over several coordinates (``vet_coupled_reference``; the three in-plane ones: axial m, radial
m, rotation rad) the same checks with the same thresholds, in vectors: the holds of the whole
deflection vector (``vetting_holds.held_vectors``: each coordinate alone and the corners of the
stroke box, each coordinate against its force floor, the work ``q . f`` positive), the records
by the worst coordinate's RMS ratio, the compatibility by the diagonal of the two stiffness
matrices; and the passivity of the dynamic stiffness matrix K(jw) at rest and under preloads
(``vetting_holds.passivity_check``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.models import BushingModel
from bushenv.scales import BushingScales
from bushenv.vetting_check import (  # noqa: F401  (the thresholds and verdicts, by their names)
    CERTIFICATE_HOLDS,
    HOLDS,
    RAMP_S,
    RECORD_LIMIT,
    SIGN_FRACTION,
    VERDICTS,
    Check,
    Vetting,
)
from bushenv.vetting_holds import (
    certificate_check,
    hold_check,
    passivity_check,
    vector_hold_check,
)
from bushenv.vetting_records import (
    compatibility_check,
    file_records_check,
    records_check,
    vector_compatibility_check,
)


def vet_reference(
    reference: BushingModel,
    label: str,
    scales: BushingScales,
    card: dict | None = None,
    card_file: Any = None,
    model: BushingModel | None = None,
    model_card: dict | None = None,
    model_file: Any = None,
    envelope: tuple[float, float] | None = None,
    builtin: bool = False,
) -> Vetting:
    """The checks of the module doc on ``reference`` at ``scales``; ``envelope``: the largest
    |x| and |dx/dt| its records cover (default: the judged stroke and velocity); ``builtin``:
    the built-in rubber (the specimen itself)."""
    holds, threshold = hold_check(reference, scales)
    checks = [holds]
    env = envelope or (scales.stroke_m, scales.velocity_m_per_s)
    cert = certificate_check(reference, scales, env, threshold)
    if cert is not None:
        checks.append(cert)
    if builtin:
        checks.append(
            Check(
                "records",
                True,
                "the built-in rubber is the specimen every record here is "
                "measured on (bushenv measure): its records are its own",
            )  # fmt: skip
        )
    else:
        checks.append(records_check(reference, card, card_file, "its own card's records"))
    checks.append(compatibility_check(reference, scales, model, model_card, model_file))
    return Vetting(label, tuple(checks))


def vet_coupled_reference(
    reference: BushingModel,
    label: str,
    stroke: np.ndarray,
    floors: np.ndarray,
    reference_file: Any = None,
    model: BushingModel | None = None,
    model_file: Any = None,
) -> Vetting:
    """The checks of the module doc on a ``reference`` of C > 1 coordinates within ``stroke``
    (C,) with the judge's force ``floors`` (C,) (N, or N m for a rotation)."""
    stroke, floors = np.asarray(stroke, float), np.asarray(floors, float)
    checks = [
        vector_hold_check(reference, stroke, floors),
        file_records_check(reference, reference_file),
        passivity_check(reference, stroke),
        vector_compatibility_check(reference, model, model_file, stroke),
    ]
    return Vetting(label, tuple(checks))
