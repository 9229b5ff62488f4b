"""Stage 1 of an attack, resolve: the model under attack, the reference, the judge, then the
hybrid, the control and the models rechecked beside them, each resolved once
(``bushenv.resolved``) into one ``Resolved``, whatever the number of coordinates C of the target.

``resolve_target`` is the stage for one model (a cell of ``bushenv campaign``, a member of the
zoo, the model ``bushenv certify`` certifies); ``resolve`` adds the roles of a whole attack
(``campaign_models.roles``). ``judge_over`` is the judge for any C: its range from the same cards
by the same rule (``judge.range_sources``, ``scales.record_range``); over one coordinate the
judge's scales (``judge.judge_of``), over several the limits per coordinate in its unit
(``campaign_limits.search_limits``) with the reference vetted within them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Any

import numpy as np

from bushenv.judge import (
    Judge,
    ScaleFlags,
    Where,
    check_reference_needed,
    criteria_of,
    judge_of,
    reference_spec_for,
)
from bushenv.models import params_sha
from bushenv.resolved import ResolvedModel, report_key, resolve_model, resolved
from bushenv.scales import BushingScales, stiffness_mismatch
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_limits import search_limits, vetted_within
from bushenv.search.campaign_models import (
    FITTED_CONTROL,
    card_displacements,
    fitted_linear,
    roles,
)
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.limits import CoordinateLimits, limits_text
from bushenv.search.targets import Target, get_target

Say = Callable[[str], None]


def _quiet(_: str) -> None:
    pass


@dataclass(frozen=True)
class Resolved:
    """What every later stage judges with: the judge, the reference and the models by report
    key (the target first), each with its role (target, hybrid, control, also)."""

    axis: str
    target: Target
    judge: Judge
    reference: ResolvedModel | None
    models: Mapping[str, ResolvedModel]
    roles: Mapping[str, str]
    keys: Mapping[str, str]  # the report key of each role (target, hybrid, control)
    notes: tuple[str, ...] = ()
    # how the control was made (label, how, spec, file), as the report records it
    control: Mapping[str, Any] | None = None
    # over several coordinates (None over one): what judged -- the force floors per coordinate
    # and the stroke the reference was vetted within -- as the report records it
    judged: Mapping[str, Any] | None = None

    @property
    def limits(self) -> CoordinateLimits | None:
        """The limits the search drives over several coordinates (the judge's scales); None
        over one, where ``judge.scales`` (a ``BushingScales``) are the bushing's limits."""
        return self.judge.scales if isinstance(self.judge.scales, CoordinateLimits) else None

    @property
    def case_axis(self) -> str:
        """The axis a corpus case of this attack records (``planar`` over several)."""
        return self.axis if self.n_coords == 1 else "planar"

    @property
    def n_coords(self) -> int:
        """The number of coordinates C of the bushing searched (the target model's)."""
        return self.models[self.target_key].model.n_coords

    @property
    def dt(self) -> float:
        return self.models[self.target_key].model.dt

    @property
    def target_key(self) -> str:
        return self.keys["target"]

    @property
    def hybrid_key(self) -> str | None:
        return self.keys.get("hybrid")

    @property
    def control_key(self) -> str | None:
        return self.keys.get("control")

    def searched_keys(self) -> list[str]:
        """The models searched (every role but ``also``: those are rechecked only)."""
        return [k for k in self.models if self.roles[k] != "also"]

    def reference_identity(self) -> dict[str, Any]:
        """What reports and cases record of the reference: the spec it was given by, its
        file's and its parameters' sha256 (all None: judged without one)."""
        ref = self.reference
        if ref is None:
            return {"spec": None, "file_sha256": None, "params_sha256": None}
        return {
            "spec": self.judge.reference_spec,
            "file_sha256": ref.sha256,
            "params_sha256": params_sha(ref.model),
        }

    def evaluator(self, key: str, threads: int = 1) -> BatchEvaluator:
        """A fresh evaluator of model ``key`` against the reference, as the judge says."""
        return BatchEvaluator(
            self.models[key].model,
            self.judge.reference,
            target=self.target,
            threads=threads,
            axis=self.axis,
            scales=self.judge.scales,
            static=self.judge.static,
        )


def _frozen(d: dict) -> Mapping:
    return MappingProxyType(dict(d))


def judge_notes(judge: Judge, target: Target, say: Say = _quiet) -> list[str]:
    """What the report says of the judge; its vetting said on ``say``."""
    notes = []
    if judge.vetting is not None:
        say(f"reference {judge.reference_spec}: vetted")
        for line in judge.vetting.lines():
            say(f"  {line}")
    if judge.reference is not None and not judge.static and target.judges_static:
        notes.append(
            "static not judged: the reference's model card shows no quasi-static content "
            "in its training records (no hold of 1 s, under 1 % of the displacement power "
            "at or below 1 Hz), so its held force is an extrapolation"
        )
    if judge.trusted_by_flag:
        notes.append(
            f"UNVETTED REFERENCE: {judge.reference_spec} failed its vetting "
            f"({judge.vetting.summary()}); --trust-reference judged with it anyway, "
            "so every verdict below may be the reference's fault"
        )
    return notes


def resolve_target(
    model: Any,
    reference: Any,
    *,
    axis: str,
    target: str | Target | Where = "rig",
    flags: ScaleFlags | None = None,
    trust_reference: bool = False,
    say: Say = _quiet,
) -> Resolved:
    """The stage for one model (a name, file, object, or resolved already, with its card)
    against ``reference`` (a name, file, object, ``"none"``, or None: see
    ``judge.reference_spec_for``): both resolved over the target's coordinates (a ``judge.Where``
    has none: the model's, any number), the judge built (``judge_over``), the reference vetted.
    Raises ``JudgeError`` as ``judge_of`` does (``SearchError`` over several coordinates)."""
    tgt = target if isinstance(target, Where) else get_target(target)
    coords = getattr(tgt, "coords", None)  # a ``Where``: the model's, however many
    flags = flags or ScaleFlags()
    wanted = f"the {tgt.name} target"
    subject = model
    if not isinstance(model, ResolvedModel):
        n = None if coords is None else max(1, len(coords))
        subject = resolve_model(model, axis, card=True, coords=n, wanted_by=f"{wanted}'s model")
    spec = reference_spec_for(subject.spec if subject.registered else None, reference)
    check_reference_needed(spec, tgt)
    ref = None
    if spec is not None:
        ref = resolve_model(spec, axis, subject.model.dt, reference=True, card=True,
                            coords=subject.model.n_coords,
                            wanted_by=f"{wanted}'s reference")  # fmt: skip
    judge, judged = judge_over(subject, ref, tgt, flags, trust_reference, say)
    return Resolved(
        axis=axis,
        target=tgt,
        judge=judge,
        reference=ref,
        models=_frozen({subject.key: subject}),
        roles=_frozen({subject.key: "target"}),
        keys=_frozen({"target": subject.key}),
        notes=tuple(judge_notes(judge, tgt, say)),
        judged=judged,
    )


def judge_over(
    subject: ResolvedModel,
    ref: ResolvedModel | None,
    target: Target | Where,
    flags: ScaleFlags,
    trust_reference: bool,
    say: Say = _quiet,
) -> tuple[Judge, dict | None]:
    """The judge of ``subject`` against ``ref`` (None: without one) over the model's C
    coordinates, and what judged for the report (None over one coordinate, where the judge's
    record says it all). The range is the one rule's either way (``judge.range_sources``); the
    kind of it is C's: one coordinate's ``BushingScales`` (force floor, limit and scale with the
    stroke, as the one-axis verdicts and their records always had) or ``CoordinateLimits``
    with a force floor per coordinate (``targets.reference_floors``)."""
    if subject.model.n_coords == 1:
        judge = judge_of(subject, ref, target=target, flags=flags, trust_reference=trust_reference)
        return judge, None
    return coordinate_judge(subject, ref, target, flags, trust_reference, say)


def coordinate_judge(
    subject: ResolvedModel,
    ref: ResolvedModel | None,
    target: Target | Where,
    flags: ScaleFlags,
    trust_reference: bool,
    say: Say = _quiet,
) -> tuple[Judge, dict | None]:
    """The judge over several coordinates: the limits searched (``search_limits``), the
    reference vetted within them, every criterion on each coordinate (``judge_coordinates``);
    and what judged, for the report (None without a reference)."""
    limits = search_limits(flags, subject, ref)
    say(f"searching within {limits_text(limits.to_json())}")
    criteria, why = criteria_of(None if ref is None else ref.model, True, target)
    why = f"{why}, on each coordinate (target_base.judge_coordinates)"
    if ref is None:
        judge = Judge(reference_spec=None, builtin=False, scales=limits, static=False,
                      criteria=criteria, why=why)  # fmt: skip
        return judge, None
    vetted, judged = vetted_within(
        ref.model, ref.spec, target, _quiet, model=subject.model, model_file=subject.file,
        trust=trust_reference, stroke=np.array(limits.stroke), rate=np.array(limits.rate),
    )  # fmt: skip
    judge = Judge(
        reference_spec=ref.spec, builtin=ref.registered, scales=limits, static=True,
        criteria=criteria, why=why, vetting=vetted,
        trusted_by_flag=bool(trust_reference and not vetted.passed), reference=ref.model,
    )  # fmt: skip
    return judge, judged


def resolve(config: CampaignConfig, say: Say = _quiet) -> Resolved:
    """The stage for a whole attack: ``resolve_target``, then every other role's model."""
    c = config
    one = resolve_target(
        c.model,
        c.reference,
        axis=c.axis,
        target=c.target,
        flags=c.flags,
        trust_reference=c.trust_reference,
        say=say,
    )
    notes = list(one.notes)
    models: dict[str, ResolvedModel] = {}
    role_of: dict[str, str] = {}
    keys: dict[str, str] = {}
    control: dict[str, Any] | None = None
    for role, spec in roles(c, one.judge, notes, coords=one.n_coords):
        key = report_key(spec)
        keys[role] = key
        known = key in models  # e.g. --model hybrid: the hybrid step is the target step
        if not known:
            models[key] = one.models[key] if role == "target" else _other(one, spec, c)
            role_of[key] = role
        if role == "control":
            control = _control_how(one, spec, models[key], given=c.control is not None)
            say(f"control: {control['label']}: {control['how']}")
        if known:
            continue
        if one.judge.static and isinstance(one.judge.scales, BushingScales):
            warning = stiffness_mismatch(models[key].model, one.judge.reference)
            if warning:  # static stiffness means something only where static is known
                notes.append(f"{key}: {warning}")
    return replace(
        one, models=_frozen(models), roles=_frozen(role_of), keys=_frozen(keys),
        notes=tuple(notes), control=None if control is None else _frozen(control),
    )  # fmt: skip


def _other(one: Resolved, spec: str, config: CampaignConfig) -> ResolvedModel:
    """A model beside the target; the fitted control is fitted (on the reference's card's
    records, else the model's, else a random drive within the limits) and saved under
    ``out``."""
    if spec == FITTED_CONTROL:
        subject = one.models[one.target_key]
        records = card_displacements(one.reference) or card_displacements(subject)
        model = fitted_linear(one.judge.reference, one.judge.scales, records)
        path = model.save(config.out / "models" / "control-linear.npz")
        return resolved(str(path), model, one.axis, key=FITTED_CONTROL)
    return resolve_model(spec, one.axis, one.dt, coords=one.n_coords,
                         wanted_by="the attack's --hybrid or --control")  # fmt: skip


def _control_how(one: Resolved, spec: str, control: ResolvedModel, given: bool) -> dict:
    """How the control was made, as the report says it."""
    if given:
        how = {"label": spec, "how": "given (--control)"}
    elif spec == FITTED_CONTROL:
        subject = one.models[one.target_key]
        q = card_displacements(one.reference) or card_displacements(subject)
        drive = "its card's training records" if q else "a random drive within the limits"
        ref = one.judge.reference_spec
        how = {"label": f"{control.spec}, a linear fit to {ref}",
               "how": f"linear, least squares on {ref}'s response to {drive}"}  # fmt: skip
    else:
        how = {"label": spec, "how": "the papers' Table-1 linear preset"}
    file = None if control.file is None else str(control.file)
    return {**how, "spec": control.spec, "file": file}
