"""Model cards of planar fits: what a 3-axis model was made from and how well it does, per axis.

``MODEL.npz`` gets ``MODEL.card.json`` and ``MODEL.card.md`` beside it (the one-axis names,
``bushenv.identify.card.card_paths``), under the format tag ``bushenv-planar-model-card``:

- ``model`` (a ``PLANAR_MODELS`` name), ``model_file``, ``model_sha256``, ``dt_s``;
- ``source``: ``kind`` "fit", ``seed``, ``wall_time_s``, ``options`` (every option and its
  value), ``info`` (the identification's own summary: evaluations, a stop by the clock, notes);
- ``records``: each record with ``role`` ("train" or "held-out"), ``file`` (relative to the
  card), ``sha256`` of its bytes, ``samples``, ``sample_rate_hz``, ``duration_s``, and
  ``metrics`` per axis (``axial``, ``radial``, ``rotation``) of the model's free run from rest:
  ``bushenv.metrics.all_metrics`` (RMS ratio and ESR of seed 000 eqs 8-9, MAX as max error
  over max |f| as in Table 3, max error in N or N m; fractions). An axis whose measured force
  is zero throughout, or held at rest with only its sensor's noise measured
  (``records.only_noise``), has null ratios there (its max error is the force the model
  invents);
- ``notes``: what the records hold that the models cannot follow (a start away from rest, a
  force offset at rest, ``bushenv.planar.records.start_notes``);
- ``holds`` (networks): their fixed points over the training range (``range_holds``);
- ``backbone`` (hybrids, with held-out records): the backbone alone (``backbone_alone``), its
  per-axis metrics on each held-out record, so the card says what the network adds;
- ``training_range``: the training records' largest |deflection| per coordinate, m / rad;
  each record's ``peak_deflection`` beside it; held-out records beyond it by more than
  ``BEYOND`` are named (``coverage_lines``): their figures judge extrapolation;
- ``coverage``: which combinations of coordinates the training records showed the model
  (``bushenv.identify.coverage``: one coordinate held while another moves, by sign) and which
  they never did; each held-out record's ``not_shown`` combinations beside it, named by
  ``coverage_lines``: their figures judge a use the model was not shown;
- ``plots``: the figures beside the model file (``plots.fit_figures3``; none with
  ``--no-plots``).
"""

from __future__ import annotations

import datetime
import os
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.identify.card import card_paths, sha256_file
from bushenv.identify.options import as_dict
from bushenv.metrics import all_metrics
from bushenv.models.planar_base import COORDS, FORCE_UNITS
from bushenv.persist import plain, write_json, write_text
from bushenv.planar.records import only_noise

CARD_FORMAT = "bushenv-planar-model-card"
CARD_VERSION = 1
RATIOS = ("rms_ratio", "esr", "max_error_ratio", "nrmse", "fit_index")  # all_metrics' ratios
WORSE_BY = 0.05  # a network worse than its backbone alone by more than this share is warned of
BEYOND = 0.05  # a held-out record past the training deflection by more than this share is named


def axis_metrics(
    f_exp: np.ndarray, f_pre: np.ndarray, q: np.ndarray | None = None
) -> dict[str, dict[str, float | None]]:
    """Per axis, every metric of ``bushenv.metrics`` ((T, 3) arrays); non-finite ratios None,
    and none for a coordinate ``q`` holds at rest with only noise measured (``only_noise``):
    there the largest error in N (N m) is what says how much force the model invents."""
    out = {}
    noise = np.zeros(3, dtype=bool) if q is None else only_noise(q, f_exp)
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, c in enumerate(COORDS):
            if not np.any(f_exp[:, i]) or noise[i]:  # no ratio to nothing or to noise
                err = float(np.max(np.abs(f_pre[:, i])))
                out[c] = {k: None for k in RATIOS} | {"max_error": err, "peak_error": err}
                continue
            m = all_metrics(f_exp[:, i], f_pre[:, i])
            out[c] = {k: (float(v) if np.isfinite(v) else None) for k, v in m.items()}
    return out


def _stem(record: Any) -> str:
    """A record's short name: its file's stem, else its own name (a record made in memory)."""
    return Path(record.path).stem if record.path is not None else Path(record.name).stem


def record_entry(record: Any, role: str, model: Any, card_dir: Path) -> dict[str, Any]:
    """A card's description of a three-axis ``Record`` and the model's per-axis metrics on it;
    ``file`` is its path relative to the card (None for a record made in memory)."""
    path = Path(record.path) if record.path is not None else None
    entry = {
        "role": role,
        "name": _stem(record),
        "file": os.path.relpath(path, card_dir) if path else None,
        "sha256": sha256_file(path) if path and path.is_file() else None,
        "samples": int(record.time.size),
        "sample_rate_hz": 1.0 / record.dt,
        "duration_s": float(record.time[-1] - record.time[0] + record.dt),
        "max_abs": {c: float(np.abs(record.f[:, i]).max()) for i, c in enumerate(COORDS)},
        "peak_deflection": {c: float(np.abs(record.q[:, i]).max()) for i, c in enumerate(COORDS)},
    }
    entry["metrics"] = axis_metrics(record.f, model.simulate(record.q), record.q)
    return entry


def save_planar_fit(
    result: Any,
    model_path: Path,
    train: list,
    held_out: list,
    notes: list[str] | None = None,
    plots: bool = True,
) -> dict[str, Any]:
    """Write the model file, its figures (``plots.fit_figures3``) and its card (JSON +
    markdown); returns the card. ``notes``: what the user should know about the records
    (``records.start_notes``)."""
    from bushenv import __version__

    model = result.model
    model.save(model_path)
    here = model_path.parent
    card = {
        "format": CARD_FORMAT,
        "version": CARD_VERSION,
        "bushenv_version": __version__,
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "model": model.name,
        "model_file": model_path.name,
        "model_sha256": sha256_file(model_path),
        "dt_s": model.dt,
        "sample_rate_hz": 1.0 / model.dt,
        "source": {
            "kind": "fit",
            "seed": result.seed,
            "wall_time_s": result.seconds,
            "options": as_dict(result.options),
            "info": result.info,
        },
        "records": [record_entry(r, "train", model, here) for r in train]
        + [record_entry(r, "held-out", model, here) for r in held_out],
        "notes": list(notes or []),
    }
    from bushenv.identify.coverage import coverage, not_shown
    from bushenv.planar.range_holds import range_holds

    span = np.max([np.abs(r.q).max(axis=0) for r in train], axis=0)
    card["training_range"] = {c: float(span[i]) for i, c in enumerate(COORDS)}
    card["coverage"] = coverage([r.q for r in train], model.dt, COORDS)
    for entry, r in zip(card["records"][len(train) :], held_out, strict=True):
        entry["not_shown"] = not_shown(card["coverage"], r.q, r.dt)
    holds = range_holds(model, span)
    if holds is not None:
        card["holds"] = holds
    backbone = model.backbone_alone()
    if backbone is not None and held_out:  # what the network adds where it was not trained
        card["backbone"] = {
            "model": backbone.name,
            "records": [
                {
                    "name": _stem(r),
                    "metrics": axis_metrics(r.f, backbone.copy().simulate(r.q), r.q),
                }
                for r in held_out
            ],
        }
    if plots:
        from bushenv.planar.plots import fit_figures3

        card["plots"] = fit_figures3(model, model_path, train, held_out)
    card = plain(card)
    json_path, md_path = card_paths(model_path)
    write_json(json_path, card, indent=1)
    write_text(md_path, card_markdown(card))
    return card


def backbone_lines(card: dict[str, Any]) -> list[str]:
    """The model and its backbone alone on the held-out records, worst RMS (MAX) per axis,
    and the axes where the network makes the worst RMS ratio worse by more than ``WORSE_BY``."""
    held = [r for r in card["records"] if r["role"] == "held-out"]
    mine, theirs = (
        _worst(r["metrics"] for r in held),
        _worst(r["metrics"] for r in card["backbone"]["records"]),
    )
    line = (
        f"held-out records, worst RMS ratio (MAX) % axial / radial / rotation: {card['model']} "
        f"{_cells(mine)}; its backbone alone ({card['backbone']['model']}) {_cells(theirs)}"
    )
    worse = [
        c
        for c in COORDS
        if None not in (mine[c][0], theirs[c][0]) and mine[c][0] > (1 + WORSE_BY) * theirs[c][0]
    ]
    if not worse:
        return [line]
    return [
        line,
        f"warning: on records it never saw the network makes the {', '.join(worse)} worse "
        f"than its backbone alone: the backbone ({card['backbone']['model']}) may be the "
        "better model there",
    ]


def coverage_lines(card: dict[str, Any]) -> list[str]:
    """What the training records showed (held combinations), and the held-out records that go
    beyond it: beyond the largest deflection in some coordinate by more than ``BEYOND``, or
    holding a combination training never held: their figures judge extrapolation, not the
    fit's range."""
    from bushenv.identify.coverage import coverage_summary

    span = card.get("training_range")
    if not span:
        return []
    out = coverage_summary(card["coverage"]) if "coverage" in card else []
    for r in card["records"]:
        if r.get("not_shown"):
            out.append(
                f"not shown: {r['file'] or r['name']} holds {'; '.join(sorted(r['not_shown']))}, "
                "which the training records never held: its figures judge a use the model was "
                "not shown"
            )
    for r in card["records"]:
        if r["role"] != "held-out" or "peak_deflection" not in r:
            continue
        ratios = {c: r["peak_deflection"][c] / span[c] for c in COORDS if span[c] > 0}
        beyond = {c: x for c, x in ratios.items() if x > 1 + BEYOND}
        beyond |= {c: None for c in COORDS if span[c] == 0 and r["peak_deflection"][c] > 0}
        if beyond:
            shown = ", ".join(
                f"{c} {x:.2f}x" if x is not None else f"{c} (never moved in training)"
                for c, x in beyond.items()
            )
            out.append(
                f"extrapolation: {r['file'] or r['name']} goes beyond the training records' "
                f"largest deflection ({shown}): its figures judge the model outside the range it "
                "was identified on, where a fit's error grows fast (docs/planar.md)"
            )
    return out


def _worst(metrics) -> dict[str, list[float | None]]:
    """Per axis [worst RMS ratio, worst MAX] over per-record ``axis_metrics``."""
    out: dict[str, list[float | None]] = {c: [None, None] for c in COORDS}
    for m in metrics:
        for c in COORDS:
            for k, key in enumerate(("rms_ratio", "max_error_ratio")):
                v = m[c][key]
                if v is not None and (out[c][k] is None or v > out[c][k]):
                    out[c][k] = v
    return out


def _cells(worst: dict[str, list[float | None]]) -> str:
    return " / ".join(f"{_pct(worst[c][0])} ({_pct(worst[c][1])})" for c in COORDS)


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:.2f}"


def card_markdown(card: dict[str, Any]) -> str:
    """The card for people: per record and axis, RMS ratio, ESR, MAX and max error."""
    src = card["source"]
    lines = [
        f"# Model card: {card['model_file']} (3-axis)",
        "",
        f"- model: **{card['model']}** (planar), {card['sample_rate_hz']:.6g} Hz; sha256 "
        f"`{card['model_sha256']}`",
        f"- made by: fit with bushenv {card['bushenv_version']} on {card['created']}; seed "
        f"{src['seed']}, wall time {src['wall_time_s']:.1f} s",
    ]
    lines += [f"- {k}: {v}" for k, v in src["info"].items()]
    lines += [f"- note: {n}" for n in card.get("notes", [])]
    lines += [
        "",
        "## Free run from rest, per axis",
        "",
        "| record | role | axis | RMS ratio % | ESR % | MAX % | max error |",
        "|---|---|---|---:|---:|---:|---:|",
    ]
    for r in card["records"]:
        for c, unit in zip(COORDS, FORCE_UNITS, strict=True):
            m = r["metrics"][c]
            lines.append(
                f"| {r['file'] or r['name']} | {r['role']} | {c} | {_pct(m['rms_ratio'])} | "
                f"{_pct(m['esr'])} | {_pct(m['max_error_ratio'])} | {m['max_error']:.4g} {unit} |"
            )
    if coverage_lines(card):
        lines += ["", "## Held-out records beyond the training range", ""]
        lines += [f"- {line}" for line in coverage_lines(card)]
    if card.get("holds"):
        from bushenv.planar.range_holds import describe

        lines += ["", "## Holds over the training range", ""] + describe(card["holds"])
    if card.get("backbone"):
        lines += ["", "## The network against its backbone alone", ""] + backbone_lines(card)
    if card.get("plots"):
        lines += ["", "## Figures", ""] + [f"![{p}]({p})" for p in card["plots"]]
    lines += ["", "## Options", "", "| option | value |", "|---|---|"]
    lines += [f"| {k} | {v} |" for k, v in src["options"].items()]
    return "\n".join(lines) + "\n"


__all__ = ["CARD_FORMAT", "axis_metrics", "card_markdown", "card_paths", "save_planar_fit"]
