"""The reference is checked before it judges (``judge.build_judge`` calls ``vet_reference``).

A verdict says "the model departs from the real bushing"; it is worth only what the reference
is. Every check's verdict is *pass*, *fail* or *not checked* (``Check.passed`` True, False or
None; the detail of a "not checked" names what was missing and how to supply it). The vetting
*passed* only when every check passed; it *failed* when one failed (the reference is refused
unless ``--trust-reference``); otherwise it is *not fully checked* and the reference judges,
saying which checks it did not pass. The checks are the same for a reference of any number of
coordinates C (C = 1: one axis, x in m; C = 3: axial m, radial m, rotation rad), each with a
physical reason and a threshold:

1. **holds** over the judged stroke: ramp in ``RAMP_S`` to each held deflection and hold
   ``HOLD_S`` -- each coordinate alone at ``HOLDS`` levels of its stroke (one axis: the 41
   holds) and, for C > 1, the corners of the stroke box (``vetting_holds.held_vectors``:
   coupling shows where coordinates combine). A passive bushing only relaxes in a hold: its
   force never oscillates, never grows away from its value after the first second, and pushes
   back: the work ``q . f`` is positive (one axis: ``f x > 0``; a coupled bushing may push
   sideways, never back into the deflection it holds). Flagged
   (``certify.reached_holds.judge_holds``): *oscillating*, *departing*, *wrong sign* (beyond
   ``SIGN_FRACTION`` of the stroke), *not finite*, each coordinate against one threshold tied
   to the reference itself (``certify.reached_holds.ring_threshold``: the larger of 3 x its own
   noise in these holds and 1 % of its largest held force), at most that coordinate's force
   floor. Where it fails: one axis, ranges of x; over C > 1, boxes about the held vectors.
2. **certificate holds** (NARX references of any C: ``nn``, ``hybrid``, ``nn-axis`` or their
   files): the reference's own certificate (``bushenv certify``, reference-free: wrong sign
   against the deflection; one axis over ``CERTIFICATE_HOLDS`` holds, over C > 1 over the held
   vectors of check 1) lists the holds where it oscillates, departs or pulls. Each is reached
   the way a search reaches it (``certify.reached_holds.confirm_holds``): a step with every
   coordinate at its own velocity limit, and sines inside the reference's envelope along each
   coordinate (and, for a hold off the coordinate axes, along its own direction) then the
   hold -- and judged per coordinate with check 1's thresholds. A confirmed one fails the
   check, naming the held vector and the coordinates that show it; with ``--trust-reference``
   every verdict whose profile dwells in its region is marked unvetted (one axis, its range,
   ``Vetting.unvetted_ranges_m``; over C > 1, a box about the held vectors,
   ``Vetting.unvetted_boxes``; ``vetting_check.enters_unvetted`` for any C). The envelope:
   ``envelope`` when given (one axis: the card's training records' largest |x| and |dx/dt|),
   else the stroke and ``velocity`` per coordinate (over C with no velocity,
   ``machine_rate``). A listing the reaching does not confirm passes, saying so.
3. **records**: the reference's RMS ratio (its worst coordinate's) on the records its model
   card names at most ``RECORD_LIMIT``: 30 % is beyond every fitted model of the papers
   (Tables 2-4) and beyond any model worth judging with. Not checked without a card or without
   its records. The built-in rubber passes: it is the specimen every record here is measured
   on.
4. **passivity**: the loss matrix of the dynamic stiffness K(jw) positive semidefinite at rest
   and under a preload along each coordinate (``certify.passivity``; one axis: Im K >= 0): a
   reference that gives energy back on some small orbit is no bushing.
5. **compatibility** with the model under test: on the records the model's own card names,
   the reference's RMS ratio at most ``RECORD_LIMIT`` (it is a model of the same bushing: a
   reference 3.2 times as stiff is refused). With no such records, the least-squares stiffness
   of both on one random drive within the stroke (``identify.linear.fitted_linear``; over C
   the diagonal of the stiffness matrix) is compared: within a factor
   ``scales.STIFFNESS_MISMATCH`` (2) on every coordinate it passes; beyond, it is *not checked*
   (undecided), not a refusal -- the model under suspicion is then the only word on which
   bushing it is, and a broken model looks like another bushing; the model's card with its
   records decides.
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
    UNVETTED_DWELL_S,
    VERDICTS,
    Check,
    Vetting,
    enters_unvetted,
    unvetted_regions,
)
from bushenv.vetting_holds import certificate_check, hold_check, passivity_check
from bushenv.vetting_records import compatibility_check, records_check


def vet_reference(
    reference: BushingModel,
    label: str,
    stroke,
    floors,
    velocity=None,
    card: dict | None = None,
    card_file: Any = None,
    model: BushingModel | None = None,
    model_card: dict | None = None,
    model_file: Any = None,
    envelope: tuple[float, float] | None = None,
    builtin: bool = False,
) -> Vetting:
    """The checks of the module doc on ``reference`` (C coordinates) within ``stroke`` with the
    verdicts' force ``floors`` (each a number for C = 1, else (C,): m or rad, N or N m);
    ``velocity``: the judged rate (one axis: the certificate's sines and the stiffness drive
    stay within it; None: the papers' machine for one axis, no limit over C; a number for
    C = 1, else (C,): m/s or rad/s). ``card``: the reference's model card (None: the card
    beside ``card_file``, a model file); ``model_card`` likewise beside ``model_file``.
    ``envelope``: the largest |q| and |dq/dt| the reference's records cover, each a number or
    (C,) (default: the stroke and velocity; over C with no velocity, ``machine_rate`` of the
    stroke); ``builtin``: the built-in rubber (the specimen itself). One-axis callers pass
    their ``BushingScales`` with ``of_scales``."""
    holds, thresholds = hold_check(reference, stroke, floors)
    checks = [holds]
    if envelope is None and reference.n_coords == 1:
        v = BushingScales().velocity_m_per_s if velocity is None else velocity
        envelope = (float(np.asarray(stroke).ravel()[0]), float(np.asarray(v).ravel()[0]))
    elif envelope is None:
        envelope = (stroke, machine_rate(stroke) if velocity is None else velocity)
    cert = certificate_check(reference, stroke, envelope, thresholds)
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
        checks.append(records_check(reference, card, card_file))
    checks.append(passivity_check(reference, stroke))
    checks.append(compatibility_check(reference, stroke, velocity, model, model_card, model_file))
    return Vetting(label, tuple(checks))


def machine_rate(stroke) -> np.ndarray:
    """The rate per coordinate of the papers' machine's rule for a stroke (m or rad): 2 pi 80 Hz
    x a fifth of it (``excitation.MAX_VELOCITY_M_PER_S`` over ``MAX_DISPLACEMENT_M``; the
    rule BushRig3-v0's rates follow, the rotation's included)."""
    from bushenv import excitation as ex

    return np.asarray(stroke, dtype=np.float64) * (ex.MAX_VELOCITY_M_PER_S / ex.MAX_DISPLACEMENT_M)


def of_scales(scales: BushingScales) -> dict[str, float]:
    """The stroke, floor and rate of one axis's ``BushingScales``, as ``vet_reference`` takes
    them: ``vet_reference(ref, label, **of_scales(scales), ...)``."""
    return {
        "stroke": scales.stroke_m,
        "floors": scales.force_floor_n,
        "velocity": scales.velocity_m_per_s,
    }
