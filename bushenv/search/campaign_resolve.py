"""Stage 1 of an attack, resolve: the model under attack, the reference, the judge, then the
hybrid, the control and the models rechecked beside them, each resolved once
(``bushenv.resolved``) into one ``Resolved``.

``resolve_target`` is the stage for one model (a cell of ``bushenv campaign``, a member of the
zoo); ``resolve`` adds the roles of a whole attack (``campaign_models.roles``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Any

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
