"""The one judging setup: which reference judges, at which scales, by which criteria.

Every command and env that makes a verdict (``attack``, ``campaign``, ``replay``, ``certify``,
``zoo``, ``measure``, ``BushRig-v0``, ``QuarterCar-v0``) builds its judge here, so the same
inputs give the same judge everywhere:

- **reference**: as given (a registered name, a model file or a model object); not given: the
  built-in ``rubber`` when the model under test is a registered name (the shipped models are
  models of it), none for a model file; ``"none"``: judged without one, by the criteria that
  need no reference -- the same meaning in every command.
- **scales** (``bushenv.scales``): the reference's static stiffness sets the force floor; the
  range (stroke and velocity, per coordinate over several) is 1.5 x the training records' peak
  |q| and |dq/dt| (``scales.record_range``, within the machine) on the first model card of
  ``range_sources`` -- the reference's; a user's reference without one, or no reference, the
  model's; a registered reference (the built-in specimen, the shipped presets) the papers'
  machine's --, flags on top. Over several coordinates the range is a
  ``search.limits.CoordinateLimits`` (``search.campaign_limits.search_limits``, the same rule).
- **criteria**: all of ``divergence.CRITERIA`` against a reference; without one, those that
  need none; ``static`` only where the target has holds and the reference's card shows static
  behaviour (``scales.static_identified``).
- **vetting** (``bushenv.vetting``): the reference is checked before it judges; every check
  passes, fails or is not checked, and the vetting passed only when every check passed. A
  reference that fails is refused (``JudgeError``, exit 2) unless ``trust_reference``; then
  every verdict is marked as judged by an unvetted reference, and those whose profile enters
  a range where it failed (``Judge.in_unvetted_range``) say so.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from bushenv.divergence import CRITERIA, NEEDS_REFERENCE
from bushenv.errors import BadInput
from bushenv.models import MODELS, BushingModel
from bushenv.resolved import ResolvedModel, resolve_model, resolved
from bushenv.scales import (
    BushingScales,
    ScaleError,
    has_range,
    scales_of_card,
    scales_of_reference,
    static_identified,
    train_range,
)

NO_REFERENCE = "none"  # the spelling of "judged without a reference" in every command
BUILTIN_REFERENCE = "rubber"


@dataclass(frozen=True)
class Where:
    """What the judge needs of where verdicts are made (a search ``Target`` has the same
    three attributes and may be passed instead)."""

    name: str
    reference_free: bool = True  # may judge with no reference (criteria that need none)
    judges_static: bool = True  # holds are of the bushing itself (``static`` applies)


RIG = Where("rig")  # prescribed displacement: the test rig, certify, the population study


class JudgeError(BadInput):
    """A judge that cannot be built: the reference failed its vetting, or cannot be loaded."""


@dataclass(frozen=True)
class ScaleFlags:
    """The bushing's limits given on the command line (None: from the reference or card)."""

    stroke_mm: float | None = None
    max_velocity_m_per_s: float | None = None
    force_floor_n: float | None = None
    force_scale_n: float | None = None
    rotation_mrad: float | None = None  # a three-axis bushing's rotation range (+-mrad)

    def given(self) -> dict[str, float]:
        values = {
            "stroke_m": None if self.stroke_mm is None else self.stroke_mm * 1e-3,
            "velocity_m_per_s": self.max_velocity_m_per_s,
            "force_floor_n": self.force_floor_n,
            "force_scale_n": self.force_scale_n,
        }
        return {k: v for k, v in values.items() if v is not None}


@dataclass(frozen=True)
class Judge:
    """What judges a verdict; ``describe()`` is what reports and corpus cases record."""

    reference_spec: str | None
    builtin: bool
    scales: BushingScales
    static: bool
    criteria: tuple[str, ...]
    why: str
    vetting: Any = None  # bushenv.vetting.Vetting, or None (no reference, or not vetted)
    trusted_by_flag: bool = False
    # where the reference is known to hold: its card's training records' largest |x| and
    # |dx/dt| (m, m/s), else the scales' stroke and velocity; and where that comes from
    envelope: tuple[float, float, str] | None = None
    reference: BushingModel | None = field(default=None, compare=False, repr=False)

    def in_envelope(self, profile, dt: float) -> bool | None:
        """Whether ``profile`` (deflection, m) stays where the reference is known to hold;
        None without a reference."""
        if self.reference is None or self.envelope is None:
            return None
        import numpy as np

        x = np.asarray(profile, dtype=np.float64)
        x_max, v_max, _ = self.envelope
        rate = float(np.max(np.abs(np.diff(x)))) / dt if x.size > 1 else 0.0
        return bool(np.max(np.abs(x)) <= x_max * (1 + 1e-9) and rate <= v_max * (1 + 1e-9))

    @property
    def span(self) -> tuple[float, ...]:
        """The largest |q| per coordinate the judge's range allows (m or rad): one coordinate's
        ``BushingScales.stroke_m``, each of several coordinates' ``CoordinateLimits.stroke``."""
        stroke = getattr(self.scales, "stroke", None)
        return (self.scales.stroke_m,) if stroke is None else tuple(stroke)

    @property
    def unvetted_ranges_m(self) -> tuple[tuple[float, float], ...]:
        """Displacement ranges (lo, hi), m, where the reference failed its vetting (it rings,
        departs or pulls there); empty when it passed or was not vetted."""
        return () if self.vetting is None else self.vetting.unvetted_ranges_m

    @property
    def has_unvetted_regions(self) -> bool:
        """Whether the reference failed its vetting somewhere (ranges over one coordinate,
        boxes of held vectors over several), so verdicts there are marked unvetted."""
        return self.vetting is not None and bool(
            self.vetting.unvetted_ranges_m or self.vetting.unvetted_boxes
        )

    def in_unvetted_range(self, profile, dt: float) -> bool | None:
        """Whether ``profile`` ((T,) deflection, m, or (T, C) over C coordinates, at ``dt``)
        dwells, ``vetting_check.UNVETTED_DWELL_S`` in all, where the reference failed its
        vetting (it rings, departs or pulls when held there, so a verdict on the profile is
        unvetted): one
        coordinate, its ranges widened by one hold grid step (the vetting saw the holds, not
        between them); several, its boxes (``vetting_check.enters_unvetted``). None without a
        reference."""
        if self.reference is None:
            return None
        from bushenv.vetting_check import enters_unvetted

        stroke = getattr(self.scales, "stroke_m", None) or getattr(self.scales, "stroke", None)
        return enters_unvetted(self.vetting, profile, dt, stroke)

    @property
    def unvetted(self) -> bool:
        """A reference judges that did not pass its vetting (or was not vetted)."""
        return self.reference is not None and (self.vetting is None or not self.vetting.passed)

    def describe(self) -> dict[str, Any]:
        return {
            "reference": self.reference_spec,
            "builtin_reference": self.builtin,
            "scales": self.scales.to_json(),
            "static": self.static,
            "criteria": list(self.criteria),
            "why": self.why,
            "vetting": None if self.vetting is None else self.vetting.describe(),
            "vetting_verdict": None if self.vetting is None else self.vetting.verdict,
            "unvetted_ranges_m": [list(r) for r in self.unvetted_ranges_m],
            "trusted_by_flag": self.trusted_by_flag,
            "unvetted": self.unvetted,
            "envelope": None
            if self.envelope is None
            else {
                "max_abs_displacement_m": self.envelope[0],
                "max_abs_velocity_m_per_s": self.envelope[1],
                "source": self.envelope[2],
            },
        }


def reference_spec_for(model: Any, reference: Any) -> Any:
    """The reference a verdict on ``model`` is judged against (see the module doc)."""
    if reference is None:
        registered = isinstance(model, str) and model in MODELS
        return BUILTIN_REFERENCE if registered else None
    if isinstance(reference, str) and reference.strip().lower() == NO_REFERENCE:
        return None
    return reference


def check_reference_needed(spec: Any, target: Any) -> None:
    """Refuse to judge without a reference where ``target`` cannot (``JudgeError``)."""
    if spec is None and not target.reference_free:
        raise JudgeError(
            f"the {target.name} target judges against a reference and none was given: pass "
            f"--reference NAME|FILE (a model of your bushing, or {BUILTIN_REFERENCE}, the "
            "built-in)"
        )


def range_sources(model: Any, reference: Any) -> tuple:
    """Whose model card gives the judged range, first choice first (``bushenv.resolved``
    values): the reference's; a user's reference (a file) without a usable card leaves it to the
    model's, and so does no reference; a registered reference (the built-in specimen, the
    shipped presets, models of the papers' bushing) has no card and leaves the machine's. The
    one rule for any number of coordinates."""
    if reference is None:
        return () if model is None else (model,)
    if reference.registered or model is None:
        return (reference,)
    return (reference, model)


def judging_scales(
    reference: BushingModel | None,
    builtin: bool,
    card: dict | None,
    flags: ScaleFlags = ScaleFlags(),
) -> BushingScales:
    """The reference's scales, its card's records' range, and the flags on top of both."""
    scales = scales_of_reference(reference, builtin)
    if card is not None:
        scales = scales_of_card(scales, card)
    given = flags.given()
    if not given:
        return scales
    return replace(scales, **given, source=scales.source + f"; flags: {sorted(given)}")


def criteria_of(
    reference: BushingModel | None, static: bool, target: Any
) -> tuple[tuple[str, ...], str]:
    """The criteria a verdict runs, and why some do not."""
    if reference is None:
        run = [c for c in CRITERIA if c not in NEEDS_REFERENCE]
        why = (
            "no reference: only the criteria that need none ran "
            f"({', '.join(NEEDS_REFERENCE)} compare with a reference's force); pass "
            "--reference NAME|FILE for all"
        )
    else:
        run, why = list(CRITERIA), "all, against the reference"
    if "static" in run and not getattr(target, "judges_static", True):
        run.remove("static")
        why += (f"; static is judged on the one-axis rig only (the {target.name} compares no "
                "held force with a static curve of its reference)")  # fmt: skip
    elif "static" in run and not static:
        run.remove("static")
        why += (
            "; static not judged: the reference's model card shows no quasi-static content in "
            "its training records (no hold of 1 s, under 1 % of the displacement power at or "
            "below 1 Hz), so its held force is an extrapolation"
        )
    return tuple(run), why


def build_judge(
    model: Any,
    reference: Any = None,
    *,
    axis: str,
    dt: float,
    target: Any = RIG,
    flags: ScaleFlags = ScaleFlags(),
    trust_reference: bool = False,
    vet: bool = True,
    model_object: BushingModel | None = None,
) -> Judge:
    """The judge of verdicts on ``model`` (a name, file or object) against ``reference``:
    both resolved here (``bushenv.resolved``), then ``judge_of``.

    ``model_object`` is the resolved model under test (its responses enter the compatibility
    check of the vetting); without it the model's card still counts, its responses do not."""
    spec = reference_spec_for(model, reference)
    check_reference_needed(spec, target)
    ref = None if spec is None else resolve_model(spec, axis, dt, reference=True, card=True)
    subject = None
    if model_object is not None:
        given = model_object if model is None else model
        subject = resolved(given, model_object, axis, card=True)
    elif model is not None:
        subject = resolve_model(model, axis, card=True)
    return judge_of(
        subject, ref, target=target, flags=flags, trust_reference=trust_reference, vet=vet,
        compare=model_object is not None,
    )  # fmt: skip


def judge_of(
    model: ResolvedModel | None,
    reference: ResolvedModel | None,
    *,
    target: Any = RIG,
    flags: ScaleFlags = ScaleFlags(),
    trust_reference: bool = False,
    vet: bool = True,
    compare: bool = True,
) -> Judge:
    """The judge of verdicts on ``model`` against ``reference``, both resolved already.

    ``target``: where the verdicts are made (``Where``, or a search ``Target``). ``compare``:
    the model's responses enter the compatibility check of the vetting (its card always
    does). Raises ``JudgeError`` when the reference fails its vetting and ``trust_reference``
    is not set."""
    tgt = target  # a ``Where`` or a search ``Target``
    check_reference_needed(reference, tgt)
    ref = None if reference is None else reference.model
    builtin = reference is not None and reference.registered and reference.spec == BUILTIN_REFERENCE
    ref_card = None if reference is None else reference.card
    model_card = None if model is None else model.card
    cards = [r.card for r in range_sources(model, reference) if has_range(r.card)]
    card = cards[0] if cards else None
    scale_problem = None
    try:
        scales = judging_scales(ref, builtin, card, flags)
    except ScaleError as exc:  # a reference that pulls or is not finite sets no floor
        scale_problem = f"{exc}; a bushing pushes back (a positive, finite static stiffness)"
        scales = judging_scales(None, builtin, card, flags)
    static = ref is not None and (ref_card is None or static_identified(ref_card))
    criteria, why = criteria_of(ref, static, tgt)
    label = None if reference is None else reference.spec
    envelope = None if ref is None else envelope_of(ref_card, scales)
    vetting = None
    if ref is not None and vet:
        from bushenv.vetting import of_scales, vet_reference

        vetting = vet_reference(
            ref, label, **of_scales(scales), card=ref_card, card_file=reference.file,
            model=model.model if model is not None and compare else None,
            model_card=model_card, model_file=None if model is None else model.file,
            envelope=envelope[:2], builtin=builtin,
        )  # fmt: skip
        if scale_problem is not None:
            from bushenv.vetting import Check, Vetting

            vetting = Vetting(vetting.reference, (Check("scales", False, scale_problem),
                                                  *vetting.checks))  # fmt: skip
        if not vetting.passed and not trust_reference:
            raise JudgeError(
                f"the reference {label} failed its vetting: {vetting.summary()}; a verdict "
                "against it could be the reference's fault. Pass a reference of this bushing "
                "that passes, or --trust-reference to judge with it anyway (every verdict is "
                "then marked as judged by an unvetted reference)"
            )
    return Judge(
        reference_spec=label,
        builtin=builtin,
        scales=scales,
        static=static and "static" in criteria,
        criteria=criteria,
        why=why,
        vetting=vetting,
        trusted_by_flag=bool(trust_reference and vetting is not None and not vetting.passed),
        envelope=envelope,
        reference=ref,
    )


def envelope_of(card: dict | None, scales: BushingScales) -> tuple[float, float, str]:
    """The reference's envelope (see ``Judge.envelope``)."""
    if has_range(card):
        (peak,), (speed,) = train_range(card["records"], ())
        return peak, speed, "the reference's card's training records"
    return scales.stroke_m, scales.velocity_m_per_s, "the judged stroke and velocity"
