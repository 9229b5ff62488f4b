"""What ``bushenv certify`` judges with: the holds' span and the reference, resolved once, for a
model of any number of coordinates C by the attack's resolve stage
(``search.campaign_resolve.resolve_target`` at the rig, ``judge.RIG``: reference-free, static
judged).

The span per coordinate is the judge's range (``Judge.span``): 1.5 x the training records' peak
|q| on the first model card of ``judge.range_sources`` (the reference's; a user's reference
without one, or no reference, the model's), within the machine of those coordinates; the
machine's for a registered reference (the shipped models); ``--stroke-mm`` on the translations
and ``--rotation-mrad`` on the rotations on top. A model file whose span would be the machine's
by default is refused: that span is the shipped models' only. The reference is a model of as
many coordinates (a registered name or a file), vetted within the span (``--trust-reference``
certifies against one that failed).
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bushenv.certify.network import CertifyError
from bushenv.certify.options import span_text
from bushenv.judge import RIG, ScaleFlags
from bushenv.models import MODELS
from bushenv.resolved import resolved
from bushenv.search.campaign_resolve import resolve_target

FLAGS = {"m": "--stroke-mm", "rad": "--rotation-mrad"}  # the span's flag per unit


@dataclass(frozen=True)
class Setup:
    """The span per coordinate (m or rad) and where it comes from, the reference (None: none)
    with its spec and its summary line, the judging setup's record, the plots' title."""

    span: tuple[float, ...]
    span_source: str
    span_text: str
    reference: Any
    reference_spec: str | None
    reference_line: str
    judge: dict | None
    title: str


def setup(args: argparse.Namespace, model) -> Setup:
    """The span and the reference of ``args`` for ``model`` (see the module doc)."""
    subject = resolved(args.model, model, args.axis, card=True)
    flags = ScaleFlags(stroke_mm=args.stroke_mm, rotation_mrad=args.rotation_mrad)
    one = resolve_target(subject, args.reference, axis=args.axis, target=RIG, flags=flags,
                         trust_reference=args.trust_reference)  # fmt: skip
    judge = one.judge
    source = judge.scales.source
    given = {"m": args.stroke_mm, "rad": args.rotation_mrad}
    missing = [FLAGS[u] for u in dict.fromkeys(model.units) if given[u] is None]
    if missing and args.model not in MODELS and "card" not in source:
        ref = one.reference
        why = (
            f"the registered reference {ref.spec} has no model card and leaves the holds' span "
            "to the machine"
            if ref is not None and ref.registered
            else "no model card (the reference's or the model's) to take the holds' span from"
        )
        raise CertifyError(
            f"{args.model}: {why}, and the machine's span is the shipped models' only; give "
            f"{' and '.join(missing)} (the deflections the bushing is used at)"
        )
    line = (judge.reference_spec or "none") + (
        "" if judge.vetting is None else f", vetting {judge.vetting.headline()}"
    )
    span = judge.span
    return Setup(
        span,
        source,
        span_text(model.coords, model.units, span),
        judge.reference,
        judge.reference_spec,
        line,
        {**judge.describe(), **(one.judged or {})},
        title(Path(args.model).name, args.axis, model.coords),
    )


def title(name: str, axis: str, coords) -> str:
    """The plots' title: the model's name, with the axis (``--axis``) a one-coordinate model
    stands for (the coordinates of several are on the plots' own axes)."""
    return name if len(coords) > 1 else f"{name} ({axis})"
