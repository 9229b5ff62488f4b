"""What an exported FMU carries besides the model: its validity envelope and the card's facts.

The envelope is the stroke and velocity the model was fitted on: the largest |x| and |dx/dt| of
its card's training records (as ``identify.card.record_entry`` measures them), else the papers'
test machine (12.5 mm, 1.257 m/s), else flags; plus the deflection boxes its certificate flags
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

# The three-axis test machine (envs/BushRig3-v0.toml): seed 002 Table 1's stroke and rate on
# the two translations, the assumed +-0.15 rad rotation at the same rate rule.
MAX_ROTATION_RAD = 0.15
THREE_AXIS_STROKES = (ex.MAX_DISPLACEMENT_M, ex.MAX_DISPLACEMENT_M, MAX_ROTATION_RAD)
THREE_AXIS_RATES = (
    ex.MAX_VELOCITY_M_PER_S,
    ex.MAX_VELOCITY_M_PER_S,
    ex.MAX_VELOCITY_M_PER_S / ex.MAX_DISPLACEMENT_M * MAX_ROTATION_RAD,
)


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
    """The envelope and facts of ``model`` from its card and certificate (either optional);
    ``stroke_m`` and ``velocity_m_per_s`` override the card's."""
    lines = [("model", model.name), ("sample_rate_hz", f"{1 / model.dt:.10g}")]
    lines.append(("model_sha256", model_sha256 or "none (a preset, not a file)"))
    if model.n_coords != 1:
        return _three_axis(model, lines, card_path, certificate, stroke_m, velocity_m_per_s)
    env = Envelope()
    if card_path is not None:
        env, card_lines = _from_card(card_path, model_sha256)
        lines += card_lines
    else:
        lines.append(("card", "none: no MODEL.card.json beside the model file"))
    flagged = () if certificate is None else certificate.flagged
    lines += [("certificate", "none")] if certificate is None else certificate.lines()
    source = env.source
    if stroke_m is not None or velocity_m_per_s is not None:
        source += "; overridden by --stroke-mm / --velocity-m-per-s"
    env = Envelope(
        stroke_m if stroke_m is not None else env.stroke_m,
        velocity_m_per_s if velocity_m_per_s is not None else env.velocity_m_per_s,
        flagged,
        source,
    )
    ranges = [[b.lo[0], b.hi[0]] for b in env.flagged]
    lines.append(
        (
            "envelope",
            f"|x| <= {env.stroke_m:.6g} m, |v| <= {env.velocity_m_per_s:.6g}"
            f" m/s, flagged x ranges {ranges} ({env.source})",
        )
    )
    return Facts(env, tuple(lines), certificate)


def _from_card(card_path: Path, model_sha256: str | None) -> tuple[Envelope, list]:
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
        m = r.get("metrics") or {}
        errors = ""
        if m:
            errors = (
                f"; rms_ratio={m.get('rms_ratio', float('nan')):.4g}, "
                f"esr={m.get('esr', float('nan')):.4g}, "
                f"max_error_n={m.get('max_error', float('nan')):.4g}, "
                f"nrmse={m.get('nrmse', float('nan')):.4g}"
            )
        name = Path(str(r.get("file") or r.get("name"))).name
        # numbered: a record's name is no variable name (spaces, quotes, a role's hyphen)
        lines.append((f"record_{i + 1}", f"{r['role']} {name}: sha256={digest}{errors}"))
    train = [r for r in card.records if r["role"] == "train" and "max_abs_displacement_m" in r]
    if not train:
        return Envelope(source=f"the papers' test machine ({card_path.name} has no ranges)"), lines
    stroke = max(r["max_abs_displacement_m"] for r in train)
    speed = max(r["max_abs_velocity_m_per_s"] for r in train)
    return Envelope(stroke, speed, (), f"the training records of {card_path.name}"), lines


def refuse_three_axis_overrides(card_path, stroke_m, velocity_m_per_s) -> None:
    """A three-axis FMU carries the machine's envelope: a card or envelope override is refused
    (checked before the export certifies the model, so it fails fast)."""
    given = [
        name
        for name, value in (
            ("--card", card_path),
            ("--stroke-mm", stroke_m),
            ("--velocity-m-per-s", velocity_m_per_s),
        )
        if value is not None
    ]
    if given:
        raise ModelError(
            f"{' and '.join(given)}: a three-axis FMU carries the three-axis test machine's "
            "envelope; cards and envelope overrides go into one-axis FMUs only"
        )


def _three_axis(model, lines, card_path, certificate, stroke_m, velocity_m_per_s) -> Facts:
    """A model over several coordinates carries the three-axis test machine's envelope and the
    boxes of its certificate (``bushenv.certify``); its card is not read into the FMU yet."""
    refuse_three_axis_overrides(card_path, stroke_m, velocity_m_per_s)
    source = "the three-axis test machine (BushRig3-v0's stroke and rate; no model card)"
    flagged = () if certificate is None else certificate.flagged
    env = Envelope(
        flagged=flagged, source=source, strokes=THREE_AXIS_STROKES, rates=THREE_AXIS_RATES
    )
    lines.append(("coordinates", ", ".join(model.coords)))
    lines.append(("card", "none: three-axis cards are not read into FMUs"))
    lines += [("certificate", "none")] if certificate is None else certificate.lines()
    bounds = ", ".join(
        f"|{c}| <= {s:.6g} {u}, rate <= {r:.6g} {u}/s"
        for c, u, s, r in zip(model.coords, model.units, env.strokes, env.rates, strict=True)
    )
    lines.append(("envelope", f"{bounds} ({source})"))
    return Facts(env, tuple(lines), certificate)
