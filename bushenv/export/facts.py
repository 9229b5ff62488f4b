"""What an exported FMU carries besides the model: its validity envelope and the card's facts.

The envelope is the stroke and velocity the model was fitted on, per coordinate: the largest
|q| and |dq/dt| of its card's training records (as ``identify.card.record_entry`` measures
them), else the test machine of its coordinates (the papers' 12.5 mm, 1.257 m/s; BushRig3-v0's
over three), flags on the translations on top; plus the deflection boxes its certificate flags
(``export.certificate``: the holds that fail it). The facts are one line each (model file
hash, each record's hash, held-out errors, the certificate's verdicts and boxes), written into
modelDescription.xml as string constants and as an annotation.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from bushenv import excitation as ex
from bushenv.export.flagged import Carried, Flagged
from bushenv.identify.card import CardError, card_paths, load_card
from bushenv.models import BushingModel, ModelError, model_file
from bushenv.scales import train_range


@dataclass(frozen=True)
class Envelope:
    """Where the exported model may be driven; ``flagged``: the certificate's boxes.

    One coordinate: ``stroke_m`` and ``velocity_m_per_s``. Several: ``strokes`` and ``rates``,
    one per coordinate (m or rad; m/s or rad/s)."""

    stroke_m: float = ex.MAX_DISPLACEMENT_M
    velocity_m_per_s: float = ex.MAX_VELOCITY_M_PER_S
    flagged: tuple[Flagged, ...] = ()
    source: str = "the papers' test machine (no model card)"
    strokes: tuple[float, ...] = ()
    rates: tuple[float, ...] = ()

    def limits(self, coords: int = 1) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """(strokes, rates), one each per coordinate."""
        if coords == 1:
            return (self.stroke_m,), (self.velocity_m_per_s,)
        return self.strokes, self.rates


@dataclass(frozen=True)
class Facts:
    """The envelope, the (name, one-line value) facts and the certificate of one export."""

    envelope: Envelope
    lines: tuple[tuple[str, str], ...] = field(default_factory=tuple)
    certificate: Carried | None = None


def find_card(spec: str | os.PathLike | BushingModel, axis: str) -> Path | None:
    """The card beside the model's file, if there is one."""
    path = model_file(spec, axis)
    if path is None:
        return None
    json_path = card_paths(path)[0]
    return json_path if json_path.is_file() else None


def facts_of(
    model: BushingModel,
    model_sha256: str | None,
    card_path: Path | None = None,
    certificate: Carried | None = None,
    stroke_m: float | None = None,
    velocity_m_per_s: float | None = None,
) -> Facts:
    """The envelope and facts of ``model`` (any number of coordinates) from its card and
    certificate (either optional); ``stroke_m`` and ``velocity_m_per_s`` override the card's
    on the translations (a rotation keeps its card's or machine's range)."""
    lines = [("model", model.name), ("sample_rate_hz", f"{1 / model.dt:.10g}")]
    lines.append(("model_sha256", model_sha256 or "none (a preset, not a file)"))
    if model.n_coords > 1:
        lines.append(("coordinates", ", ".join(model.coords)))
    strokes, rates, source = machine_range(model)
    if card_path is not None:
        ranged, card_lines = _from_card(card_path, model_sha256, model)
        lines += card_lines
        if ranged is not None:
            strokes, rates, source = _card_range(ranged, rates, card_path, model)
        else:
            source = f"{source} ({card_path.name} has no ranges)"
    else:
        lines.append(("card", "none: no MODEL.card.json beside the model file"))
    if stroke_m is not None or velocity_m_per_s is not None:
        moved = [u == "m" for u in model.units]
        strokes = tuple(stroke_m if m and stroke_m is not None else s
                        for m, s in zip(moved, strokes, strict=True))  # fmt: skip
        rates = tuple(velocity_m_per_s if m and velocity_m_per_s is not None else r
                      for m, r in zip(moved, rates, strict=True))  # fmt: skip
        source += "; overridden by --stroke-mm / --velocity-m-per-s"
    flagged = () if certificate is None else certificate.flagged
    lines += [("certificate", "none")] if certificate is None else certificate.lines()
    env = Envelope(strokes[0], rates[0], flagged, source, strokes, rates)
    lines.append(("envelope", _envelope_text(model, env)))
    return Facts(env, tuple(lines), certificate)


def machine_range(model: BushingModel) -> tuple[tuple, tuple, str]:
    """(strokes, rates, source): the test machine of the model's coordinates -- the papers'
    for one, BushRig3-v0 for its three (``search.limits.machine_of``)."""
    if model.n_coords == 1:
        return (
            (ex.MAX_DISPLACEMENT_M,),
            (ex.MAX_VELOCITY_M_PER_S,),
            "the papers' test machine (no model card)",
        )
    from bushenv.search.limits import machine_of, rig3_limits

    if machine_of(model.coords) is None:
        raise ModelError(
            f"no test machine over {', '.join(model.coords)} to take an FMU's envelope from; "
            "give the model's card (--card) with its training records' ranges"
        )
    stroke, rate = rig3_limits()
    return (
        tuple(stroke.tolist()),
        tuple(rate.tolist()),
        "the three-axis test machine (BushRig3-v0's stroke and rate; no model card)",
    )


def _card_range(ranged, machine_rates, card_path, model) -> tuple[tuple, tuple, str]:
    """The card's training records' largest |q| per coordinate, and their |dq/dt| where the
    card states it (cards written before did not over several: then the machine's)."""
    peaks, speeds = ranged
    source = f"the training records of {card_path.name}"
    if speeds is None:
        return peaks, machine_rates, source + " (the rates the machine's: the card has none)"
    return peaks, speeds, source


def _envelope_text(model: BushingModel, env: Envelope) -> str:
    if model.n_coords == 1:
        ranges = [[b.lo[0], b.hi[0]] for b in env.flagged]
        return (
            f"|x| <= {env.stroke_m:.6g} m, |v| <= {env.velocity_m_per_s:.6g}"
            f" m/s, flagged x ranges {ranges} ({env.source})"
        )
    bounds = ", ".join(
        f"|{c}| <= {s:.6g} {u}, rate <= {r:.6g} {u}/s"
        for c, u, s, r in zip(model.coords, model.units, env.strokes, env.rates, strict=True)
    )
    return f"{bounds} ({env.source})"


def _from_card(card_path: Path, model_sha256: str | None, model: BushingModel):
    """((peaks, speeds or None) per coordinate, or None when the card states no ranges; the
    card's lines)."""
    try:
        card = load_card(card_path, check_model=True)
    except CardError as exc:
        raise ModelError(str(exc)) from None
    data = card.data
    if model_sha256 is not None and data.get("model_sha256") != model_sha256:
        raise ModelError(
            f"{card_path}: this card describes {data.get('model_file')}, not the model being "
            "exported (sha256 differs); pass that model's own card"
        )
    lines = [
        ("card", f"{card_path.name}, made by {data['source'].get('kind')} on {data.get('created')}")
    ]
    for i, r in enumerate(card.records):
        digest = r.get("sha256") or r.get("data_sha256")
        errors = _errors(r.get("metrics") or {})
        name = Path(str(r.get("file") or r.get("name"))).name
        # numbered: a record's name is no variable name (spaces, quotes, a role's hyphen)
        lines.append((f"record_{i + 1}", f"{r['role']} {name}: sha256={digest}{errors}"))
    return train_range(card.records, model.coords), lines


def _errors(m: dict) -> str:
    """A record's held-out errors: the one coordinate's, or each coordinate's RMS ratio and
    largest error over several (``card_records.coordinate_metrics``; None: no ratio)."""
    if not m:
        return ""
    if not all(isinstance(v, dict) for v in m.values()):
        return (
            f"; rms_ratio={m.get('rms_ratio', float('nan')):.4g}, "
            f"esr={m.get('esr', float('nan')):.4g}, "
            f"max_error_n={m.get('max_error', float('nan')):.4g}, "
            f"nrmse={m.get('nrmse', float('nan')):.4g}"
        )

    def ratio(v):
        return "none" if v is None else f"{v:.4g}"

    return "; " + ", ".join(
        f"{c}: rms_ratio={ratio(v.get('rms_ratio'))}, max_error={ratio(v.get('max_error'))}"
        for c, v in m.items()
    )
