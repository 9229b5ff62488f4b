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

from bushenv.judge import ScaleFlags, range_sources
from bushenv.scales import RECORD_MARGIN, record_range, train_range
from bushenv.search.base import SearchError
from bushenv.search.campaign_models import card_records
from bushenv.search.limits import (
    CoordinateLimits,
    limits_of_records,
    machine_limits,
    machine_of,
)
from bushenv.vetting import machine_rate


def limits_of_card(resolved) -> CoordinateLimits | None:
    """The limits of the bushing ``resolved``'s card describes, over its model's coordinates:
    from its training records (``limits_of_records``: 1.5 x their peak |q| and |dq/dt| per
    coordinate); when the records are gone, the card's peak deflections and rates (cards
    written before state no rates: the machine's, ``machine_of``; none: ``vetting.machine_rate``,
    the papers' rule on the stroke); None without a card (or one without training records)."""
    if resolved is None or resolved.card is None:
        return None
    coords, units = tuple(resolved.model.coords), tuple(resolved.model.units)
    name = f"the training records of {resolved.card_file}"
    records = card_records(resolved)
    if records is not None:
        return limits_of_records([r.q for r in records], records[0].dt, name, coords, units)
    train = [r for r in resolved.card.get("records", []) if r.get("role") == "train"]
    if not train or not all(isinstance(r.get("peak_deflection"), dict) for r in train):
        return None
    peaks, speeds = train_range(train, coords)
    peak = np.array(peaks)
    if speeds is not None:  # cards state |dq/dt| since 2026-11-29
        speed = np.array(speeds)
        machine = machine_limits() if machine_of(coords) is not None else None
        top_s, top_r = (np.inf, np.inf) if machine is None else (machine.stroke, machine.rate)
        stroke, rate = record_range(peak, speed, np.array(top_s), np.array(top_r))
        return CoordinateLimits(
            tuple(stroke.tolist()), tuple(rate.tolist()),
            f"{RECORD_MARGIN:g} x the peak deflection and rate {name} state (the records are "
            "not there)", tuple(peak.tolist()), coords, units,
        )  # fmt: skip
    if machine_of(coords) is None:
        if not np.all(peak > 0):
            return None
        stroke = record_range(peak, 0.0)[0]
        rate, whose = machine_rate(stroke), "rule"
    else:
        machine = machine_limits()
        top = np.array(machine.stroke)
        stroke = np.where(peak > 0, record_range(peak, 0.0, top)[0], top)
        rate, whose = np.array(machine.rate), "rates"
    return CoordinateLimits(
        tuple(stroke.tolist()),
        tuple(rate.tolist()),
        f"{RECORD_MARGIN:g} x the peak deflection {name} state (the records are not there: "
        f"the machine's {whose})",
        tuple(peak.tolist()),
        coords,
        units,
    )


def _listed(names: list[str]) -> str:
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


def search_limits(flags: ScaleFlags, subject, reference) -> CoordinateLimits:
    """What the search drives over the model's coordinates: the range of the first card of
    ``judge.range_sources`` (the reference's; a user's reference without one, or none, the
    model's) or the machine's (``machine_of``), with the flags on top (``--stroke-mm`` and
    ``--max-velocity`` on the translations, ``--rotation-mrad`` on the rotations).
    ``SearchError`` when a coordinate has none of these."""
    coords, units = tuple(subject.model.coords), tuple(subject.model.units)
    limits = machine_limits() if machine_of(coords) is not None else None
    for res in range_sources(subject, reference):
        found = limits_of_card(res)
        if found is not None:
            limits = found
            break
    flag = {"m": (flags.stroke_mm, flags.max_velocity_m_per_s), "rad": (flags.rotation_mrad, None)}
    named = {"m": [c for c, u in zip(coords, units, strict=True) if u == "m"],
             "rad": [c for c, u in zip(coords, units, strict=True) if u == "rad"]}  # fmt: skip
    if limits is None:
        missing = [f for f, u in (("--stroke-mm", "m"), ("--rotation-mrad", "rad"))
                   if named[u] and flag[u][0] is None]  # fmt: skip
        if missing:
            raise SearchError(
                f"{subject.spec}: no model card with training records to take the range of "
                f"{', '.join(coords)} from, and no machine over them; give {' and '.join(missing)} "
                "(the deflections the bushing is used at)"
            )
        stroke = [flag[u][0] * 1e-3 for u in units]
        v = flags.max_velocity_m_per_s
        rate = [machine_rate(s) if u == "rad" or v is None else v
                for s, u in zip(stroke, units, strict=True)]  # fmt: skip
        given = " and ".join(f for f, u in (("--stroke-mm", "m"), ("--rotation-mrad", "rad"))
                             if named[u])  # fmt: skip
        return CoordinateLimits(tuple(stroke), tuple(float(r) for r in rate),
                                f"{given} (the rates the papers' machine's rule)", None,
                                coords, units)  # fmt: skip
    stroke, rate = list(limits.stroke), list(limits.rate)
    parts = []
    for u in ("m", "rad"):
        s, v = flag[u]
        if not named[u] or (s is None and v is None):
            continue
        idx = [i for i, x in enumerate(units) if x == u]
        given = []
        if s is not None:
            given.append(f"--{'stroke-mm' if u == 'm' else 'rotation-mrad'} {s:g}")
            for i in idx:
                stroke[i] = s * 1e-3
        if v is not None:
            given.append(f"--max-velocity {v:g}")
            for i in idx:
                rate[i] = v
        where = _listed(named[u]) if u == "m" else "the " + _listed(named[u])
        parts.append((u, f"{' and '.join(given)} on {where}"))
    if not parts:
        return limits
    source = "; ".join(text for _, text in parts)
    if [u for u, _ in parts] == ["m"] and named["rad"]:
        source += f" (the {_listed(named['rad'])}: {limits.source})"
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


def failure_reach(profiles: list[np.ndarray], limits: CoordinateLimits | None) -> dict | None:
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
