"""Stage 1 of an attack, resolve: the model under attack, the reference, the judge, then the
hybrid, the control and the models rechecked beside them, each resolved once
(``bushenv.resolved``) into one ``Resolved``.

``resolve_target`` is the stage for one model (a cell of ``bushenv campaign``, a member of the
zoo); ``resolve`` adds the roles of a whole attack (``campaign_models.roles``), for a target of
any number of coordinates: over several, the limits the search drives are scaled to the user's
card (``planar_models.search_limits``), the reference is vetted within them, and the control is
the user's own (``--control``), a linear fit to the user's reference, or the Table-1 preset.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from bushenv.judge import (
    Judge,
    ScaleFlags,
    check_reference_needed,
    judge_of,
    reference_spec_for,
)
from bushenv.models import params_sha
from bushenv.resolved import ResolvedModel, report_key, resolve_model, resolved
from bushenv.scales import stiffness_mismatch
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_models import (
    FITTED_CONTROL,
    card_displacements,
    fitted_linear,
    roles,
)
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.limits import Rig3Limits, limits_text
from bushenv.search.planar_models import (
    DEFAULT_CONTROL,
    DEFAULT_REFERENCE,
    resolved_planar,
    search_limits,
    vetting,
)
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
    # over several coordinates (None over one, where ``judge.scales`` are the limits): the
    # limits the search drives, what judged (the vetting, the force floors, the stroke) and how
    # the control was made (label, how, spec, file), as the report records them
    limits: Rig3Limits | None = None
    judged: dict | None = None
    control: dict | None = None

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
    target: str | Target = "rig",
    flags: ScaleFlags | None = None,
    trust_reference: bool = False,
    say: Say = _quiet,
) -> Resolved:
    """The stage for one model (a name, file, object, or resolved already, with its card)
    against ``reference`` (a name, file, object, ``"none"``, or None: see
    ``judge.reference_spec_for``): both resolved, the reference vetted. Raises
    ``JudgeError`` as ``judge_of`` does."""
    tgt = get_target(target)
    subject = model if isinstance(model, ResolvedModel) else resolve_model(model, axis, card=True)
    spec = reference_spec_for(subject.spec if subject.registered else None, reference)
    check_reference_needed(spec, tgt)
    ref = None
    if spec is not None:
        ref = resolve_model(spec, axis, subject.model.dt, reference=True, card=True)
    judge = judge_of(
        subject, ref, target=tgt, flags=flags or ScaleFlags(), trust_reference=trust_reference
    )
    return Resolved(
        axis=axis,
        target=tgt,
        judge=judge,
        reference=ref,
        models=_frozen({subject.key: subject}),
        roles=_frozen({subject.key: "target"}),
        keys=_frozen({"target": subject.key}),
        notes=tuple(judge_notes(judge, tgt, say)),
    )


def resolve(config: CampaignConfig, say: Say = _quiet) -> Resolved:
    """The stage for a whole attack: ``resolve_target``, then every other role's model."""
    c = config
    if get_target(c.target).coords:
        return _resolve_coordinates(c, say)
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
    for role, spec in roles(c, one.judge, notes):
        key = report_key(spec)
        keys[role] = key
        if key in models:  # e.g. --model hybrid: the hybrid step is the target step
            continue
        models[key] = one.models[key] if role == "target" else _other(one, spec, c)
        role_of[key] = role
        if one.judge.static:  # static stiffness means something only where static is known
            warning = stiffness_mismatch(models[key].model, one.judge.reference)
            if warning:
                notes.append(f"{key}: {warning}")
    return replace(
        one, models=_frozen(models), roles=_frozen(role_of), keys=_frozen(keys), notes=tuple(notes)
    )


def _other(one: Resolved, spec: str, config: CampaignConfig) -> ResolvedModel:
    """A model beside the target; the fitted control is fitted and saved under ``out``."""
    if spec == FITTED_CONTROL:
        records = card_displacements(one.reference)
        model = fitted_linear(one.judge.reference, one.judge.scales, records)
        path = model.save(config.out / "models" / "control-linear.npz")
        return resolved(str(path), model, one.axis, key=FITTED_CONTROL)
    return resolve_model(spec, one.axis, one.dt)


def _resolve_coordinates(c: CampaignConfig, say: Say) -> Resolved:
    """``resolve`` over several coordinates (see the module doc)."""
    tgt = get_target(c.target)
    subject = resolved_planar(c.model, None, "--model", card=True)
    dt = subject.model.dt
    ref = resolved_planar(c.reference or DEFAULT_REFERENCE, dt, "--reference", card=True)
    limits = search_limits(c, subject, ref)
    vetted, judged = vetting(
        ref.model, ref.spec, tgt, say, model=subject.model, model_file=subject.file,
        trust=c.trust_reference, stroke=np.array(limits.stroke),
    )  # fmt: skip
    if c.control:
        control = resolved_planar(c.control, dt, "--control")
        how = {"label": c.control, "how": "given (--control)"}
    elif ref.file is not None:
        q = card_displacements(ref) or card_displacements(subject)
        fit = fitted_linear(ref.model, limits, q)
        path = fit.save(Path(c.out) / "models" / "control-linear.npz")
        control = replace(resolved_planar(str(path), dt, "--control"), key=FITTED_CONTROL)
        drive = "its card's training records" if q else "a random drive within the limits"
        how = {
            "label": f"{path}, a linear fit to {ref.spec}",
            "how": f"linear, least squares on {ref.spec}'s response to {drive}",
        }
    else:
        control = resolved_planar(DEFAULT_CONTROL, dt, "--control")
        how = {"label": DEFAULT_CONTROL, "how": "the planar Table-1 linear preset"}
    how.update(spec=control.spec, file=None if control.file is None else str(control.file))
    by_role = {"target": subject, "control": control}
    if c.hybrid and c.hybrid != "none":
        by_role["hybrid"] = resolved_planar(c.hybrid, dt, "--hybrid")
    models: dict[str, ResolvedModel] = {}
    for m in by_role.values():
        models.setdefault(m.key, m)
    judge = Judge(
        reference_spec=ref.spec, builtin=ref.registered, scales=limits, static=True,
        criteria=(), why="per coordinate, as the target judges (target_base.judge_coordinates)",
        vetting=vetted, trusted_by_flag=bool(c.trust_reference and not vetted.passed),
        reference=ref.model,
    )  # fmt: skip
    for line in (
        f"searching within {limits_text(limits.to_json())}",
        f"control: {how['label']}: {how['how']}",
    ):
        say(line)
    return Resolved(
        axis=c.axis, target=tgt, judge=judge, reference=ref, models=_frozen(models),
        roles=_frozen({m.key: r for r, m in reversed(by_role.items())}),
        keys=_frozen({r: m.key for r, m in by_role.items()}),
        notes=tuple(judge_notes(judge, tgt)), limits=limits, judged=judged, control=how,
    )  # fmt: skip
