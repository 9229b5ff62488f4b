"""Model cards: what a model file was made from, with what, and how well it does on held-out data.

``MODEL.npz`` gets ``MODEL.card.json`` and ``MODEL.card.md`` beside it. The JSON holds:

- ``format`` ("bushenv-model-card"), ``version``, ``bushenv_version``, ``created`` (UTC);
- ``model`` (registry name), ``model_file`` (file name), ``model_sha256``, ``dt_s``;
- ``source``: how it was made (``"fit"`` with ``seed``, ``wall_time_s``, ``options`` -- every
  option with its value --, ``training`` summary; or ``"torch-import"`` with the torch file and
  the stated scaling);
- ``parameters``: the physical parameters of a physical model, by name, with their units
  (linear and the hybrid's backbone: k and c; Bouc-Wen: its sixteen); null for the NN;
- ``records``: each source record with ``role`` ("train" or "held-out"), ``file`` (relative
  to the card's folder; cards before that hold absolute paths, read the same), ``sha256``
  (of the file's bytes, or null for records made in memory), ``data_sha256`` (of the time,
  displacement and force values as float64), ``samples``, ``sample_rate_hz``, ``duration_s``,
  and ``metrics`` of the model's free run from rest on it (``bushenv.metrics.all_metrics``:
  RMS ratio and ESR of seed 000 eqs 8-9, max error, NRMSE, ...; fractions and N);
- ``plots``: file names of the figures beside the card.

``load_card(path, records=...)`` reads a card and checks it: the model file beside it still has
the recorded hash, and each given record file matches the card's record of the same file name.
"""

from __future__ import annotations

import datetime
import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.errors import BadInput
from bushenv.identify.parameters import physical_parameters
from bushenv.metrics import all_metrics
from bushenv.persist import plain, write_json, write_text

CARD_FORMAT = "bushenv-model-card"
CARD_VERSION = 1


class CardError(BadInput):
    """A model card is unreadable or does not match its model or records (names which)."""


def card_paths(model_path: str | os.PathLike) -> tuple[Path, Path]:
    """``MODEL.card.json`` and ``MODEL.card.md`` beside ``MODEL.npz``."""
    p = Path(model_path)
    stem = p.name[: -len(p.suffix)] if p.suffix else p.name
    return p.with_name(stem + ".card.json"), p.with_name(stem + ".card.md")


def sha256_file(path: str | os.PathLike) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def data_sha256(record: Any) -> str:
    """sha256 of a record's time, displacement and force values (float64, little-endian)."""
    h = hashlib.sha256()
    for key in ("time", "displacement", "force"):
        h.update(np.ascontiguousarray(getattr(record, key), dtype="<f8").tobytes())
    return h.hexdigest()


def record_entry(
    record: Any, role: str, model: Any | None = None, card_dir: str | os.PathLike | None = None
) -> dict[str, Any]:
    """A card's description of ``record`` (and the model's metrics on it, if given); its file
    relative to ``card_dir`` when given, so a card moved with its records still finds them."""
    path = getattr(record, "path", None)
    file = os.fspath(path) if path is not None else None
    if path is not None and card_dir is not None:
        try:
            file = os.path.relpath(path, card_dir)
        except ValueError:  # another drive (Windows): no relative path exists
            file = os.path.abspath(path)
    entry = {
        "role": role,
        "name": getattr(record, "name", "") or (Path(path).stem if path else ""),
        "file": file,
        "sha256": sha256_file(path) if path is not None else None,
        "data_sha256": data_sha256(record),
        "samples": len(record.force),
        "sample_rate_hz": float(record.sample_rate_hz),
        "duration_s": float(record.duration_s),
        # the bushing's range on this record: attacks scale their search to it (bushenv.scales)
        "max_abs_displacement_m": float(np.max(np.abs(record.displacement))),
        "max_abs_velocity_m_per_s": float(
            np.max(np.abs(np.diff(record.displacement))) * record.sample_rate_hz
        ),
        "max_abs_force_n": float(np.max(np.abs(record.force))),
        # what the record says about the bushing's static behaviour (bushenv.scales)
        "quasi_static_share": quasi_static_share(record.displacement, record.sample_rate_hz),
        "longest_hold_s": longest_hold_s(record.displacement, record.sample_rate_hz),
    }
    if model is not None:
        entry["metrics"] = free_run_metrics(model, record)
    return entry


def quasi_static_share(x: np.ndarray, rate_hz: float, below_hz: float = 1.0) -> float:
    """Share of the displacement's power at or below ``below_hz`` (Welch estimate)."""
    from scipy import signal

    x = np.asarray(x, dtype=np.float64)
    n = min(x.size, int(rate_hz * 16))
    if n < 8:
        return 0.0
    f, p = signal.welch(x - x.mean(), fs=rate_hz, nperseg=n)
    total = float(np.sum(p))
    return float(np.sum(p[f <= below_hz]) / total) if total > 0 else 0.0


def longest_hold_s(x: np.ndarray, rate_hz: float, tolerance_m: float = 1e-9) -> float:
    """Longest run of samples at one displacement, s."""
    moving = np.abs(np.diff(np.asarray(x, dtype=np.float64))) >= tolerance_m
    longest = run = 0
    for m in moving:
        run = 0 if m else run + 1
        longest = max(longest, run)
    return longest / rate_hz


def free_run_metrics(model: Any, record: Any) -> dict[str, float]:
    """Every metric of ``bushenv.metrics`` for the model's free run from rest on ``record``."""
    model.reset(1)
    return all_metrics(record.force, model.simulate(record.displacement))


def new_card(model: Any, model_path: str | os.PathLike, source: dict[str, Any]) -> dict[str, Any]:
    """The card of a model just written to ``model_path`` (records and plots added later)."""
    from bushenv import __version__

    return {
        "format": CARD_FORMAT,
        "version": CARD_VERSION,
        "bushenv_version": __version__,
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "model": model.name,
        "model_file": Path(model_path).name,
        "model_sha256": sha256_file(model_path),
        "dt_s": model.dt,
        "sample_rate_hz": 1.0 / model.dt,
        "source": source,
        "parameters": physical_parameters(model),
        "records": [],
        "plots": [],
    }


def write_card(card: dict[str, Any], model_path: str | os.PathLike) -> tuple[Path, Path]:
    """Write the card's JSON and markdown beside the model (atomically)."""
    json_path, md_path = card_paths(model_path)
    write_json(json_path, plain(card), indent=1)
    write_text(md_path, card_markdown(card))
    return json_path, md_path


def _pct(v: float) -> str:
    return f"{100 * v:.2f}"


def card_markdown(card: dict[str, Any]) -> str:
    """The card for people: what, from which records, how well, with which options."""
    src = card["source"]
    lines = [
        f"# Model card: {card['model_file']}",
        "",
        f"- model: **{card['model']}**, {card['sample_rate_hz']:.6g} Hz "
        f"(dt = {card['dt_s']:.6g} s); sha256 `{card['model_sha256']}`",
        f"- made by: {src['kind']} with bushenv {card['bushenv_version']} on {card['created']}",
    ]
    if src["kind"] == "fit":
        lines.append(f"- seed {src['seed']}, wall time {src['wall_time_s']:.1f} s")
        if src.get("stopped"):
            early = "**stopped early** by the time limit: " if src.get("time_limited") else ""
            lines.append(f"- training ended: {early}{src['stopped']}")
        if src.get("budget_used"):
            used = ", ".join(f"{k} {v}" for k, v in src["budget_used"].items())
            lines.append(f"- budget used: {used}")
        if src.get("choice"):
            lines.append(f"- network chosen on validation: {src['choice']['summary']}")
        if src.get("note"):
            lines.append(f"- **note**: {src['note']}")
    else:
        lines.append(f"- torch file `{src['torch_file']}`, sha256 `{src['torch_sha256']}`")
    if card.get("parameters"):
        lines += ["", "## Parameters", "", "| parameter | value | unit |", "|---|---:|---|"]
        params = card["parameters"].items()
        lines += [f"| {k} | {p['value']:.6g} | {p['unit']} |" for k, p in params]
    lines += _records_table(card["records"])
    lines += ["", "## Options", "", "| option | value |", "|---|---|"]
    for k, v in src.get("options", {}).items():
        lines.append(f"| {k} | {v} |")
    for name in card["plots"]:
        lines += ["", f"![{name}]({name})"]
    return "\n".join(lines) + "\n"


def _records_table(records: list[dict[str, Any]]) -> list[str]:
    if not records:
        return ["", "No records: the model was not identified here."]
    out = [
        "",
        "## Records",
        "",
        "Free run from rest on each record. RMS ratio and ESR: seed 000 eqs 8-9; NRMSE: RMS "
        "error over the standard deviation of the measured force.",
        "",
        "| role | record | rate Hz | duration s | RMS ratio % | ESR % | max error N | "
        "NRMSE % | sha256 |",
        "|---|---|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in records:
        m = r.get("metrics") or {}
        cells = [
            _pct(m["rms_ratio"]) if m else "",
            _pct(m["esr"]) if m else "",
            f"{m['max_error']:.1f}" if m else "",
            _pct(m["nrmse"]) if m else "",
        ]
        digest = (r["sha256"] or r["data_sha256"])[:16]
        out.append(
            f"| {r['role']} | {r['file'] or r['name']} | {r['sample_rate_hz']:.6g} | "
            f"{r['duration_s']:.2f} | {' | '.join(cells)} | `{digest}` |"
        )
    return out


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
    formats: tuple[str, ...] = (CARD_FORMAT,),
) -> ModelCard:
    """Read the card of a model (``MODEL.card.json``, or ``MODEL.npz`` for the card beside it).

    Checks that the model file still has the card's hash (``check_model``) and that each of
    ``records`` (paths or ``Record`` objects) matches the card's record of the same file name;
    raises ``CardError`` naming the record or file that does not. ``formats``: the format
    tags accepted (a planar card, ``bushenv.planar.card``, has the same model and record keys).
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
) -> dict[str, Any]:
    """Write a ``FitResult``'s figures, model file and card (JSON + markdown), in that order
    (a failure leaves no model file without its card).

    ``held_out``: records never seen in training; the card gives the model's metrics on each
    and a figure pair per record (without held-out records, the first training record is
    plotted, marked as seen in training). Returns the card.
    """
    from bushenv.identify.options import as_dict

    model_path = Path(model_path)
    model = result.model
    held_out = list(held_out or [])
    figures = _figures(model, model_path, result.records, held_out) if plots else []
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
    }
    card = new_card(model, model_path, source)
    here = model_path.parent
    card["records"] = [record_entry(r, "train", model, here) for r in result.records]
    card["records"] += [record_entry(r, "held-out", model, here) for r in held_out]
    card["plots"] = figures
    write_card(card, model_path)
    return card


def _figures(model: Any, model_path: Path, train: list, held_out: list) -> list[str]:
    """The figure pair of each held-out record (or of the first training record)."""
    from bushenv.identify.plots import record_figures, safe_name

    shown = [(r, "held-out") for r in held_out] or [(train[0], "seen in training")]
    stem = model_path.name[: -len(model_path.suffix)] if model_path.suffix else model_path.name
    names = []
    for i, (rec, role) in enumerate(shown):
        model.reset(1)
        f_model = model.simulate(rec.displacement)
        prefix = model_path.with_name(f"{stem}.{i + 1}-{safe_name(rec.name or 'record')}")
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
