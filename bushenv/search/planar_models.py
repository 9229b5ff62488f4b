"""A three-axis model or reference named in an attack or a case, resolved: what the planar
attack and the corpus's replay of planar cases share; and the planar attack's resolve stage
(``resolve_planar_attack`` -> ``Planar``): what a user's bushing gives it through the card
beside its file -- the limits the search drives (``search_limits``, ``limits_of_card``) and the
linear control fitted to the reference (``identify.linear.fitted_linear``, over C), as the
one-axis attack takes both from its reference's card (``judge.judging_scales``,
``campaign_models.roles``) -- and the reference vetted within those limits (``vetted_judge``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from bushenv.identify.linear import fitted_linear
from bushenv.progress import Progress
from bushenv.scales import RECORD_MARGIN
from bushenv.search.base import SearchError
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_models import card_displacements, card_records
from bushenv.search.limits import (
    COORDS,
    Rig3Limits,
    limits_of_records,
    limits_text,
    machine_limits,
)
from bushenv.search.targets import TARGETS

DEFAULT_REFERENCE = "reference"
DEFAULT_CONTROL = "linear"
FITTED_CONTROL = "linear-fit"  # the control's key when it is fitted to the user's reference


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


@dataclass(frozen=True)
class Planar:
    """Stage 1's result: the models by role (target, reference, control, maybe hybrid), the
    limits searched, what judged, and how the control was made."""

    models: dict
    limits: Rig3Limits
    judge: dict
    control: dict  # label, spec, file, how

    @property
    def model(self):
        return self.models["target"].model

    @property
    def reference(self):
        return self.models["reference"].model


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


def resolve_planar_attack(c: CampaignConfig, progress: Progress) -> Planar:
    """Stage 1 (see the module doc)."""
    subject = resolved_planar(c.model, None, "--model", card=True)
    dt = subject.model.dt
    reference = resolved_planar(c.reference or DEFAULT_REFERENCE, dt, "--reference", card=True)
    limits = search_limits(c, subject, reference)
    judge = vetted_judge(
        reference.model,
        reference.spec,
        TARGETS[c.target],
        progress,
        model=subject.model,
        model_file=subject.file,
        trust=c.trust_reference,
        stroke=np.array(limits.stroke),
    )
    models = {"target": subject, "reference": reference}
    if c.control:
        models["control"] = resolved_planar(c.control, dt, "--control")
        control = {"label": c.control, "how": "given (--control)"}
    elif reference.file is not None:
        q = card_displacements(reference) or card_displacements(subject)
        fit = fitted_linear(reference.model, limits, q)
        path = fit.save(Path(c.out) / "models" / "control-linear.npz")
        models["control"] = replace(resolved_planar(str(path), dt, "--control"), key=FITTED_CONTROL)
        drive = "its card's training records" if q else "a random drive within the limits"
        control = {
            "label": f"{path}, a linear fit to {reference.spec}",
            "how": f"linear, least squares on {reference.spec}'s response to {drive}",
        }
    else:
        models["control"] = resolved_planar(DEFAULT_CONTROL, dt, "--control")
        control = {"label": DEFAULT_CONTROL, "how": "the planar Table-1 linear preset"}
    control.update(spec=models["control"].spec, file=_path(models["control"].file))
    if c.hybrid and c.hybrid != "none":
        models["hybrid"] = resolved_planar(c.hybrid, dt, "--hybrid")
    for line in (
        f"searching within {limits_text(limits.to_json())}",
        f"control: {control['label']}: {control['how']}",
    ):
        progress.say(line)
    return Planar(models, limits, judge, control)


def _path(p) -> str | None:
    return None if p is None else str(p)


def vetted_judge(
    reference,
    ref_spec: str,
    target,
    progress: Progress,
    model=None,
    model_file=None,
    trust: bool = False,
    error: type[Exception] = SearchError,
    stroke: np.ndarray | None = None,
) -> dict:
    """The reference checked before it judges (``bushenv.vetting``) within ``stroke`` (None:
    the target's): ``error`` when it fails, unless ``trust``; what judged (the vetting,
    floors, stroke) for a report."""
    from bushenv.search.targets import reference_floors
    from bushenv.vetting import vet_reference

    if stroke is None:
        stroke, _ = target.profile_bounds()
    floors, floors_source = reference_floors(reference)
    vetting = vet_reference(
        reference,
        ref_spec,
        stroke,
        floors,
        card_file=ref_spec if ref_spec.endswith(".npz") else None,
        model=model,
        model_file=model_file,
    )
    for line in vetting.lines():
        progress.say(f"reference {ref_spec}: {line}")
    if not vetting.passed and not trust:
        raise error(
            f"the reference {ref_spec} failed its vetting ({vetting.summary()}): it cannot judge; "
            "give another --reference, or pass --trust-reference to judge with it anyway "
            "(every verdict is then marked)"
        )
    return {
        "vetting": vetting.describe(),
        "trusted_despite_failed_vetting": bool(not vetting.passed),
        "force_floors": dict(zip(target.coords, floors.tolist(), strict=True)),
        "force_floors_source": floors_source,
        "stroke": dict(zip(target.coords, np.asarray(stroke).tolist(), strict=True)),
    }
