"""Model cards: what a model file was made from, with what, and how well it does on held-out data,
for a bushing of any number of coordinates C.

``MODEL.npz`` gets ``MODEL.card.json`` and ``MODEL.card.md`` beside it. The JSON holds:

- ``format`` ("bushenv-model-card"; cards of three-axis fits written before the one card carry
  "bushenv-planar-model-card" and read the same), ``version``, ``bushenv_version``,
  ``created`` (UTC);
- ``model`` (registry name), ``coords`` (the coordinates, in array order), ``model_file``,
  ``model_sha256``, ``dt_s``;
- ``source``: how it was made (``"fit"`` with ``seed``, ``wall_time_s``, ``options`` -- every
  option with its value --, ``training`` summary and ``info``, the identification's own notes;
  or ``"torch-import"`` with the torch file and the stated scaling);
- ``parameters``: the physical parameters of a physical model, by name, with their units; null
  for a network;
- ``records``: each source record (``card_records.record_entry``) with ``role`` ("train" or
  "held-out"), ``file`` (relative to the card's folder; older cards hold absolute paths, read
  the same), ``sha256`` (of the file's bytes, or null for records made in memory),
  ``data_sha256``, ``samples``, ``sample_rate_hz``, ``duration_s``, its range, and ``metrics``
  of the model's free run from rest on it (``bushenv.metrics.all_metrics``: RMS ratio and ESR
  of seed 000 eqs 8-9, max error, NRMSE, ...; per coordinate over several, where a coordinate
  held at rest with only noise measured has null ratios);
- ``notes``: what the records hold that the models cannot follow (``record_notes.start_notes``);
- ``training_range``: the training records' largest |deflection| per coordinate; held-out
  records beyond it by more than ``BEYOND`` are named (``card_text.coverage_lines``);
- ``coverage``: which held combinations of coordinates the training records showed
  (``bushenv.identify.coverage``; none exist for C = 1) and each held-out record's
  ``not_shown`` ones;
- ``holds`` (networks): their fixed points over the training range (``certify.range_holds``);
- ``backbone`` (a hybrid with held-out records): its backbone alone on each, so the card says
  what the network adds;
- ``plots``: file names of the figures beside the card.

``load_card(path, records=...)`` reads a card and checks it: the model file beside it still has
the recorded hash, and each given record file matches the card's record of the same file name.
"""

from __future__ import annotations

import datetime
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bushenv.errors import BadInput
from bushenv.identify.card_records import (
    data_sha256,
    free_run_metrics,
    record_entry,
    record_name,
    sha256_file,
)
from bushenv.identify.parameters import physical_parameters
from bushenv.persist import plain, write_json, write_text

CARD_FORMAT = "bushenv-model-card"
LEGACY_FORMATS = ("bushenv-planar-model-card",)  # three-axis cards before the one card
CARD_VERSION = 1


class CardError(BadInput):
    """A model card is unreadable or does not match its model or records (names which)."""


def card_paths(model_path: str | os.PathLike) -> tuple[Path, Path]:
    """``MODEL.card.json`` and ``MODEL.card.md`` beside ``MODEL.npz``."""
    p = Path(model_path)
    stem = p.name[: -len(p.suffix)] if p.suffix else p.name
    return p.with_name(stem + ".card.json"), p.with_name(stem + ".card.md")


def new_card(model: Any, model_path: str | os.PathLike, source: dict[str, Any]) -> dict[str, Any]:
    """The card of a model just written to ``model_path`` (records and plots added later)."""
    from bushenv import __version__

    return {
        "format": CARD_FORMAT,
        "version": CARD_VERSION,
        "bushenv_version": __version__,
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "model": model.name,
        "coords": list(model.coords),
        "model_file": Path(model_path).name,
        "model_sha256": sha256_file(model_path),
        "dt_s": model.dt,
        "sample_rate_hz": 1.0 / model.dt,
        "source": source,
        "parameters": physical_parameters(model),
        "records": [],
    }


def write_card(card: dict[str, Any], model_path: str | os.PathLike) -> tuple[Path, Path]:
    """Write the card's JSON and markdown beside the model (atomically)."""
    from bushenv.identify.card_text import card_markdown

    json_path, md_path = card_paths(model_path)
    write_json(json_path, plain(card), indent=1)
    write_text(md_path, card_markdown(plain(card)))
    return json_path, md_path


@dataclass
class ModelCard:
    """A card read from disk (``data`` is its JSON) and where it is."""

    path: Path
    data: dict[str, Any]
    checked_records: list[str] = field(default_factory=list)

    @property
    def model_path(self) -> Path:
        return self.path.with_name(self.data["model_file"])

    @property
    def records(self) -> list[dict[str, Any]]:
        return self.data["records"]

    def record_path(self, entry: dict[str, Any]) -> Path | None:
        """Where a card record's file is: relative paths from the card's folder (absolute
        ones, as older cards hold, as they are); None for a record made in memory."""
        if not entry.get("file"):
            return None
        p = Path(entry["file"])
        return p if p.is_absolute() else self.path.parent / p

    def held_out(self) -> list[dict[str, Any]]:
        return [r for r in self.records if r["role"] == "held-out"]

    def verify_model(self) -> None:
        """The model file beside the card is the one the card describes."""
        path = self.model_path
        if not path.is_file():
            raise CardError(f"{self.path}: its model file {path} is missing")
        if sha256_file(path) != self.data["model_sha256"]:
            raise CardError(
                f"{self.path}: model file {path} does not match the card (sha256 differs): "
                "it was replaced or changed after the card was written"
            )

    def verify_records(self, records: list) -> None:
        """Each given record (a path or a Record) matches the card's record of its file name."""
        for rec in records:
            self.checked_records.append(self._verify_one(rec))

    def _verify_one(self, rec: Any) -> str:
        if isinstance(rec, str | os.PathLike):
            name, digest, key = Path(rec).name, sha256_file(rec), "sha256"
        else:
            name = Path(rec.path).name if getattr(rec, "path", None) else rec.name
            digest, key = data_sha256(rec), "data_sha256"
        mine = [r for r in self.records if _entry_name(r) == name]
        if not mine:
            known = ", ".join(_entry_name(r) for r in self.records) or "none"
            raise CardError(
                f"{self.path}: record {name} is not one of the card's records ({known})"
            )
        if not any(r.get(key) == digest for r in mine):
            raise CardError(
                f"{self.path}: record {name} does not match the card: sha256 "
                f"{digest[:16]}... here, {(mine[0].get(key) or 'none')[:16]}... in the card "
                "(the file changed, or it is another record of the same name)"
            )
        return name


def _entry_name(entry: dict[str, Any]) -> str:
    return Path(entry["file"]).name if entry.get("file") else entry["name"]


def load_card(
    path: str | os.PathLike,
    records: list | None = None,
    check_model: bool = True,
    formats: tuple[str, ...] = (CARD_FORMAT, *LEGACY_FORMATS),
) -> ModelCard:
    """Read the card of a model (``MODEL.card.json``, or ``MODEL.npz`` for the card beside it).

    Checks that the model file still has the card's hash (``check_model``) and that each of
    ``records`` (paths or ``Record`` objects) matches the card's record of the same file name;
    raises ``CardError`` naming the record or file that does not. ``formats``: the format
    tags accepted (by default the card's and the three-axis cards' written before it).
    """
    p = Path(path)
    if p.suffix == ".npz":
        p = card_paths(p)[0]
    if not p.is_file():
        raise CardError(f"{p}: no such model card")
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise CardError(f"{p}: not a model card (unreadable JSON: {exc})") from None
    if not isinstance(data, dict) or data.get("format") not in formats:
        raise CardError(f"{p}: not a model card (format tag missing)")
    if data.get("version") != CARD_VERSION:
        raise CardError(f"{p}: card version {data.get('version')!r}, this bushenv reads 1")
    card = ModelCard(p, data)
    if check_model:
        card.verify_model()
    card.verify_records(list(records or []))
    return card


def save_fit(
    result: Any,
    model_path: str | os.PathLike,
    held_out: list | None = None,
    plots: bool = True,
    notes: list[str] | None = None,
) -> dict[str, Any]:
    """Write a fit's figures, model file and card (JSON + markdown), in that order (a failure
    leaves no model file without its card); returns the card. The one card writer for a fit
    of any number of coordinates (``bushenv fit`` calls it; C comes from the model).

    ``result``: a ``bushenv.identify.FitResult`` (its ``model``, ``records`` -- the training
    records, ``Record`` objects --, ``options``, ``seed``, ``seconds``, ``info``).
    ``held_out``: records never seen in training; the card gives the model's metrics on each
    and a figure pair per record (without held-out records, the first training record is
    plotted, marked as seen in training). ``notes``: what the user should know about the
    records (``bushenv.record_notes.start_notes``).
    """
    from bushenv.certify.range_holds import range_holds
    from bushenv.identify.coverage import coverage, not_shown, spans
    from bushenv.identify.options import as_dict

    model_path = Path(model_path)
    model = result.model
    train, held_out = list(result.records), list(held_out or [])
    figures = _figures(model, model_path, train, held_out) if plots else []
    model.save(model_path)
    training = getattr(model, "training", {}) or {}
    source = {
        "kind": "fit",
        "seed": result.seed,
        "wall_time_s": result.seconds,
        "options": as_dict(result.options),
        "stopped": training.get("stopped"),
        "time_limited": bool(training.get("time_limited", False)),
        "budget_used": training.get("budget_used"),
        "choice": training.get("choice"),
        "note": training.get("note"),
        "training": {k: training[k] for k in _TRAINING_SUMMARY if k in training},
        "info": dict(getattr(result, "info", None) or {}),
    }
    card = new_card(model, model_path, source)
    here = model_path.parent
    card["records"] = [record_entry(r, "train", model, here) for r in train]
    card["records"] += [record_entry(r, "held-out", model, here) for r in held_out]
    card["notes"] = list(notes or [])
    span = spans([r.q for r in train])
    card["training_range"] = {c: float(s) for c, s in zip(model.coords, span, strict=True)}
    card["coverage"] = coverage([r.q for r in train], model.dt, model.coords)
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
                {"name": record_name(r), "metrics": free_run_metrics(backbone.copy(), r)}
                for r in held_out
            ],
        }
    if plots:
        card["plots"] = figures
    write_card(card, model_path)
    return plain(card)


def _figures(model: Any, model_path: Path, train: list, held_out: list) -> list[str]:
    """The figure pair of each held-out record (or of the first training record)."""
    from bushenv.identify.plots import record_figures, safe_name

    shown = [(r, "held-out") for r in held_out] or [(train[0], "seen in training")]
    stem = model_path.name[: -len(model_path.suffix)] if model_path.suffix else model_path.name
    names = []
    for i, (rec, role) in enumerate(shown):
        model.reset(1)
        f_model = model.simulate(rec.displacement)
        prefix = model_path.with_name(f"{stem}.{i + 1}-{safe_name(record_name(rec) or 'record')}")
        names += [p.name for p in record_figures(rec, f_model, model.name, prefix, role)]
    return names


# What of a model's training log goes on its card (the rest is per-iteration detail).
_TRAINING_SUMMARY = (
    "recipe",
    "input_basis",
    "best_validation_rms_ratio",
    "validation_after_teacher",
    "best_teacher_validation_mse",
    "stage_stops",
    "skipped_windows",
    "loss_terms",
    "generations",
    "cost_n",
    "rms_ratio",
    "evaluations",
    "k_n_per_m",
    "c_ns_per_m",
    "linear_validation_rms_ratio",
    "seconds",
)
