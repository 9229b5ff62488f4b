"""What ``bushenv certify`` judges with: the holds' span and the reference, resolved once.

One coordinate: the one judging setup (``bushenv.judge``: the reference resolved and vetted,
the stroke the model card's, the machine's for the shipped models, ``--stroke-mm`` on top).
Several coordinates: the span per coordinate 1.5 x the card's training range (the one-axis
stroke rule), ``--stroke-mm`` for translations and ``--rotation-mrad`` for rotations on top;
the reference a model of as many coordinates (a registered name or a file), vetted over the
span (``vetting.vet_reference``; ``--trust-reference`` certifies against one that
failed), the judging setup being one coordinate's.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.certify.network import CertifyError
from bushenv.models import MODELS, get_model


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


def _shown(model, span) -> str:
    return ", ".join(
        f"{c} +-{v * 1e3:.4g} {'mrad' if u == 'rad' else 'mm'}"
        for c, u, v in zip(model.coords, model.units, span, strict=True)
    )


def setup(args: argparse.Namespace, model) -> Setup:
    """The span and the reference of ``args`` for ``model`` (see the module doc)."""
    if model.n_coords == 1:
        return _judged(args, model)
    return _several(args, model)


def _judged(args: argparse.Namespace, model) -> Setup:
    from bushenv.judge import ScaleFlags, build_judge

    judge = build_judge(
        args.model,
        args.reference,
        axis=args.axis,
        dt=model.dt,
        flags=ScaleFlags(stroke_mm=args.stroke_mm),
        trust_reference=args.trust_reference,
        model_object=model,
    )
    if args.stroke_mm is None and args.model not in MODELS and "card" not in judge.scales.source:
        raise CertifyError(
            f"{args.model}: no model card to take the stroke from (and the papers' +-12.5 mm "
            "is the shipped models' only); give --stroke-mm S, the stroke the model is for"
        )
    line = (judge.reference_spec or "none") + (
        "" if judge.vetting is None else f", vetting {judge.vetting.headline()}"
    )
    stroke = judge.scales.stroke_m
    return Setup(
        (stroke,),
        judge.scales.source,
        f"+-{stroke * 1e3:.4g} mm",
        judge.reference,
        judge.reference_spec,
        line,
        judge.describe(),
        f"{Path(args.model).name} ({args.axis})",
    )


def _span(args: argparse.Namespace, model) -> tuple[tuple[float, ...], str]:
    """The holds' half-width per coordinate: 1.5 x the card's training range, else
    --stroke-mm for translations and --rotation-mrad for rotations."""
    from bushenv.identify.card import card_paths

    given = {"m": args.stroke_mm, "rad": args.rotation_mrad}
    if all(given[u] is not None for u in model.units):
        return tuple(given[u] * 1e-3 for u in model.units), "--stroke-mm/--rotation-mrad"
    card = card_paths(args.model)[0]
    if Path(args.model).suffix == ".npz" and card.is_file():
        span = json.loads(card.read_text()).get("training_range")
        if span:
            out = [
                1.5 * span[c] if given[u] is None else given[u] * 1e-3
                for c, u in zip(model.coords, model.units, strict=True)
            ]
            return tuple(out), f"1.5 x the training range of {card.name}"
    missing = " and ".join(
        f for f, u in (("--stroke-mm", "m"), ("--rotation-mrad", "rad")) if given[u] is None
    )
    raise CertifyError(
        f"{args.model}: no model card with a training range beside it to take the holds' span "
        f"from; give {missing} (the deflections the bushing is used at)"
    )


def _several(args: argparse.Namespace, model) -> Setup:
    from bushenv.search.campaign_limits import vetted_within

    span, source = _span(args, model)
    spec = None if args.reference in (None, "none") else str(args.reference)
    if spec is None:
        return Setup(span, source, _shown(model, span), None, None, "none", None, _title(args))
    reference = get_model(
        spec, axis=args.axis, dt=model.dt, coords=model.n_coords,
        wanted_by="bushenv certify --reference",
    )  # fmt: skip
    model_file = args.model if str(args.model).endswith(".npz") else None
    vetting, judged = vetted_within(
        reference, spec, None, lambda _: None, model=model, model_file=model_file,
        trust=args.trust_reference, error=CertifyError, stroke=np.array(span),
    )  # fmt: skip
    judge = {"reference": spec, "vetting_verdict": vetting.verdict, **judged}
    line = f"{spec}, vetting {vetting.headline()}"
    return Setup(span, source, _shown(model, span), reference, spec, line, judge, _title(args))


def _title(args: argparse.Namespace) -> str:
    return Path(args.model).name
