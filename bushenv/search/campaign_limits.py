"""The limits an attack over several coordinates drives and the reference vetted within them
(part of the resolve stage, ``campaign_resolve.resolve``): from the card beside a user's file
(``search_limits``, ``limits_of_card``: per coordinate, the rotation with its own flag), as the
one-axis attack takes its scales from its reference's card (``judge.judging_scales``); and the
reference vetted within those limits (``vetted_within``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from bushenv.judge import ScaleFlags
from bushenv.scales import RECORD_MARGIN
from bushenv.search.base import SearchError
from bushenv.search.campaign_models import card_records
from bushenv.search.limits import (
    COORDS,
    Rig3Limits,
    limits_of_records,
    machine_limits,
)


def limits_of_card(resolved) -> Rig3Limits | None:
    """The limits of the bushing ``resolved``'s card describes: from its training records
    (``limits_of_records``: 1.5 x their peak |q| and |dq/dt| per coordinate); when the records
    are gone, the stroke from the card's peak deflections and the machine's rates; None
    without a card (or one without training records)."""
    if resolved is None or resolved.card is None:
        return None
    name = f"the training records of {resolved.card_file}"
    records = card_records(resolved)
    if records is not None:
        return limits_of_records([r.q for r in records], records[0].dt, name)
    train = [r for r in resolved.card.get("records", []) if r.get("role") == "train"]
    peaks = [r.get("peak_deflection") for r in train]
    if not peaks or not all(isinstance(p, dict) for p in peaks):
        return None
    peak = np.array([max(float(p[c]) for p in peaks) for c in COORDS])
    machine = machine_limits()
    stroke = np.where(peak > 0, np.minimum(RECORD_MARGIN * peak, machine.stroke), machine.stroke)
    return Rig3Limits(
        tuple(stroke.tolist()),
        machine.rate,
        f"{RECORD_MARGIN:g} x the peak deflection {name} state (the records are not there: "
        "the machine's rates)",
        tuple(peak.tolist()),
    )


def search_limits(flags: ScaleFlags, subject, reference) -> Rig3Limits:
    """What the search drives: a user's reference's card (else the model's) or the machine's,
    with the flags on top (``--stroke-mm`` and ``--max-velocity`` on the translations,
    ``--rotation-mrad`` on the rotation)."""
    limits = machine_limits()
    if reference.file is not None:  # a user's reference: its card, else the model's
        for res in (reference, subject):
            found = limits_of_card(res)
            if found is not None:
                limits = found
                break
    stroke, rate = list(limits.stroke), list(limits.rate)
    given = []
    if flags.stroke_mm is not None:
        stroke[:2] = [flags.stroke_mm * 1e-3] * 2
        given.append(f"--stroke-mm {flags.stroke_mm:g}")
    if flags.max_velocity_m_per_s is not None:
        rate[:2] = [flags.max_velocity_m_per_s] * 2
        given.append(f"--max-velocity {flags.max_velocity_m_per_s:g}")
    if not given and flags.rotation_mrad is None:
        return limits
    source = f"{' and '.join(given)} on axial and radial" if given else ""
    if flags.rotation_mrad is not None:
        stroke[2] = flags.rotation_mrad * 1e-3
        source += (f"{'; ' if source else ''}--rotation-mrad {flags.rotation_mrad:g} on the "
                   "rotation")  # fmt: skip
    else:
        source += f" (the rotation: {limits.source})"
    return replace(limits, stroke=tuple(stroke), rate=tuple(rate), source=source)


def vetted_within(
    reference,
    ref_spec: str,
    target,
    say: Callable[[str], None],
    model=None,
    model_file=None,
    trust: bool = False,
    error: type[Exception] = SearchError,
    stroke: np.ndarray | None = None,
    rate: np.ndarray | None = None,
):
    """The reference (over several coordinates) checked before it judges (``bushenv.vetting``)
    within ``stroke`` (None: the search ``target``'s) and ``rate`` per coordinate (None: the
    papers' machine's rule on the stroke, ``vetting.machine_rate``): ``error`` when it fails, unless
    ``trust``; (the ``Vetting``, what judged -- the vetting, the force floors per coordinate,
    the stroke -- for a report). The attack, the zoo and ``bushenv certify`` vet with it."""
    from bushenv.search.targets import reference_floors
    from bushenv.vetting import vet_reference

    if stroke is None:
        stroke, _ = target.profile_bounds()
    floors, floors_source = reference_floors(reference)
    vetted = vet_reference(
        reference,
        ref_spec,
        stroke,
        floors,
        card_file=ref_spec if ref_spec.endswith(".npz") else None,
        model=model,
        model_file=model_file,
        velocity=None if rate is None else np.asarray(rate, dtype=np.float64),
    )
    for line in vetted.lines():
        say(f"reference {ref_spec}: {line}")
    if not vetted.passed and not trust:
        raise error(
            f"the reference {ref_spec} failed its vetting ({vetted.summary()}): it cannot judge; "
            "give another --reference, or pass --trust-reference to judge with it anyway "
            "(every verdict is then marked)"
        )
    return vetted, {
        "vetting": vetted.describe(),
        "trusted_despite_failed_vetting": bool(not vetted.passed),
        "force_floors": dict(zip(reference.coords, floors.tolist(), strict=True)),
        "force_floors_source": floors_source,
        "stroke": dict(zip(reference.coords, np.asarray(stroke).tolist(), strict=True)),
    }


def failure_reach(profiles: list[np.ndarray], limits: Rig3Limits | None) -> dict | None:
    """How far beyond the records the failures sit: per profile the largest over the
    coordinates of its peak |q| over the records' (``limits.records_peak``); its median,
    smallest and largest. None when the limits come from no records."""
    seen = None if limits is None or limits.records_peak is None else np.array(limits.records_peak)
    if seen is None or not profiles or not np.any(seen > 0):
        return None
    moved = seen > 0
    ratio = [float(np.max(np.max(np.abs(q), axis=0)[moved] / seen[moved])) for q in profiles]
    return {
        "failures": len(ratio),
        "median": round(float(np.median(ratio)), 3),
        "min": round(min(ratio), 3),
        "max": round(max(ratio), 3),
        "of": "each failure's largest peak |q| over the records' peak, per coordinate",
    }
