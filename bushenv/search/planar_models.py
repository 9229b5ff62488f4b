"""What is truly three-coordinate in resolving an attack (``campaign_resolve.resolve`` is the
one stage): a three-axis model or reference named in an attack or a case (what the attack and
the corpus's replay of three-axis cases share); the limits the search drives, from the card
beside a user's file (``search_limits``, ``limits_of_card``: per coordinate, the rotation with
its own flag), as the one-axis attack takes its scales from its reference's card
(``judge.judging_scales``); and the reference vetted within those limits (``vetting``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from bushenv.scales import RECORD_MARGIN
from bushenv.search.base import SearchError
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_models import card_records
from bushenv.search.limits import (
    COORDS,
    Rig3Limits,
    limits_of_records,
    machine_limits,
)

DEFAULT_REFERENCE = "reference"
DEFAULT_CONTROL = "linear"


def resolve_planar_spec(spec: str, dt: float | None, what: str):
    """A three-axis model by ``MODELS`` name (with a preset) or ``.npz`` file; ``dt`` None:
    a file at its own rate (a fit on 500 Hz records runs at 500 Hz), a preset at the papers'."""
    from bushenv.models import load_model
    from bushenv.models.base import PAPER_DT
    from bushenv.rigs.common import resolve_model

    if dt is None and str(spec).endswith(".npz") and Path(spec).is_file():
        return load_model(spec, coords=3, wanted_by=f"the {what}")
    dt = PAPER_DT if dt is None else dt
    return resolve_model(spec, dt=dt, coords=3, what=what, env_id="BushRig3-v0")


def resolved_planar(spec: str, dt: float | None, what: str, card: bool = False):
    """``resolve_planar_spec`` as a ``ResolvedModel`` (its file and sha256, for cases); with
    ``card``, the planar card beside a file (checked against the file; ``CardError`` when it
    does not match), read here once."""
    from bushenv.models import file_hash
    from bushenv.resolved import ResolvedModel, report_key

    model = resolve_planar_spec(spec, dt, what)
    path = Path(spec) if str(spec).endswith(".npz") and Path(spec).is_file() else None
    found = read_planar_card(path) if card and path is not None else None
    return ResolvedModel(
        key=report_key(spec),
        spec=str(spec),
        model=model,
        file=path,
        sha256=None if path is None else file_hash(path),
        card=None if found is None else found.data,
        card_file=None if found is None else found.path,
        registered=path is None,
    )


def read_planar_card(path: Path):
    """The planar ``ModelCard`` beside model file ``path``, or None when there is none."""
    from bushenv.identify.card import card_paths, load_card

    if not card_paths(path)[0].is_file():
        return None
    return load_card(path)


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


def search_limits(config: CampaignConfig, subject, reference) -> Rig3Limits:
    """What the search drives (see the module doc, step 1)."""
    c = config
    limits = machine_limits()
    if reference.file is not None:  # a user's reference: its card, else the model's
        for res in (reference, subject):
            found = limits_of_card(res)
            if found is not None:
                limits = found
                break
    stroke, rate = list(limits.stroke), list(limits.rate)
    given = []
    if c.stroke_mm is not None:
        stroke[:2] = [c.stroke_mm * 1e-3] * 2
        given.append(f"--stroke-mm {c.stroke_mm:g}")
    if c.max_velocity_m_per_s is not None:
        rate[:2] = [c.max_velocity_m_per_s] * 2
        given.append(f"--max-velocity {c.max_velocity_m_per_s:g}")
    if not given and c.rotation_mrad is None:
        return limits
    source = f"{' and '.join(given)} on axial and radial" if given else ""
    if c.rotation_mrad is not None:
        stroke[2] = c.rotation_mrad * 1e-3
        source += f"{'; ' if source else ''}--rotation-mrad {c.rotation_mrad:g} on the rotation"
    else:
        source += f" (the rotation: {limits.source})"
    return replace(limits, stroke=tuple(stroke), rate=tuple(rate), source=source)


def vetting(
    reference,
    ref_spec: str,
    target,
    say: Callable[[str], None],
    model=None,
    model_file=None,
    trust: bool = False,
    error: type[Exception] = SearchError,
    stroke: np.ndarray | None = None,
):
    """The reference checked before it judges (``bushenv.vetting``) within ``stroke`` (None:
    the target's): ``error`` when it fails, unless ``trust``; (the ``Vetting``, what judged --
    the vetting, floors, stroke -- for a report)."""
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
        "force_floors": dict(zip(target.coords, floors.tolist(), strict=True)),
        "force_floors_source": floors_source,
        "stroke": dict(zip(target.coords, np.asarray(stroke).tolist(), strict=True)),
    }
