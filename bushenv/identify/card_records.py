"""A model card's description of one record: where it is, its hashes, its range, and the model's
free-run metrics on it, per coordinate for a bushing of several (``bushenv.identify.card``)."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.metrics import all_metrics
from bushenv.record_notes import only_noise

RATIOS = ("rms_ratio", "esr", "max_error_ratio", "nrmse", "fit_index")  # all_metrics' ratios


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


def record_name(record: Any) -> str:
    """A record's short name: its file's stem, else its own name (a record made in memory)."""
    path = getattr(record, "path", None)
    return Path(path).stem if path is not None else getattr(record, "name", "")


def coordinate_metrics(
    coords: tuple[str, ...], f_exp: np.ndarray, f_pre: np.ndarray, q: np.ndarray | None = None
) -> dict[str, dict[str, float | None]]:
    """Per coordinate, every metric of ``bushenv.metrics`` ((T, C) arrays); non-finite ratios
    None, and none for a coordinate whose measured force is zero throughout or that ``q`` holds
    at rest with only noise measured (``record_notes.only_noise``): there the largest error
    in N (N m) says how much force the model invents."""
    out = {}
    noise = np.zeros(len(coords), dtype=bool) if q is None else only_noise(q, f_exp)
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, c in enumerate(coords):
            if not np.any(f_exp[:, i]) or noise[i]:  # no ratio to nothing or to noise
                err = float(np.max(np.abs(f_pre[:, i])))
                out[c] = {k: None for k in RATIOS} | {"max_error": err, "peak_error": err}
                continue
            m = all_metrics(f_exp[:, i], f_pre[:, i])
            out[c] = {k: (float(v) if np.isfinite(v) else None) for k, v in m.items()}
    return out


def free_run_metrics(model: Any, record: Any) -> dict[str, Any]:
    """The model's free run from rest on ``record``: every metric of ``bushenv.metrics`` (one
    coordinate), or ``coordinate_metrics`` (several)."""
    model.reset(1)
    if record.n_coords == 1:
        return all_metrics(record.force, model.simulate(record.displacement))
    return coordinate_metrics(record.coords, record.f, model.simulate(record.q), record.q)


def record_entry(
    record: Any, role: str, model: Any | None = None, card_dir: str | os.PathLike | None = None
) -> dict[str, Any]:
    """A card's description of ``record`` (and the model's metrics on it, if given); its file
    relative to ``card_dir`` when given, so a card moved with its records still finds them.

    Over one coordinate the range is ``max_abs_displacement_m``, ``max_abs_velocity_m_per_s``,
    ``max_abs_force_n`` and what it says about static behaviour (``quasi_static_share``,
    ``longest_hold_s``; attacks scale their search to these, ``bushenv.scales``); over several,
    ``peak_deflection``, ``peak_rate`` (|dq/dt|) and ``max_abs`` (force) per coordinate."""
    path = getattr(record, "path", None)
    file = os.fspath(path) if path is not None else None
    if path is not None and card_dir is not None:
        try:
            file = os.path.relpath(path, card_dir)
        except ValueError:  # another drive (Windows): no relative path exists
            file = os.path.abspath(path)
    entry = {
        "role": role,
        "name": record_name(record),
        "file": file,
        "sha256": sha256_file(path) if path is not None and Path(path).is_file() else None,
        "data_sha256": data_sha256(record),
        "samples": len(record.time),
        "sample_rate_hz": float(record.sample_rate_hz),
        "duration_s": float(record.duration_s),
    }
    if record.n_coords == 1:
        rate = record.sample_rate_hz
        entry |= {
            "max_abs_displacement_m": float(np.max(np.abs(record.displacement))),
            "max_abs_velocity_m_per_s": float(np.max(np.abs(np.diff(record.displacement))) * rate),
            "max_abs_force_n": float(np.max(np.abs(record.force))),
            "quasi_static_share": quasi_static_share(record.displacement, rate),
            "longest_hold_s": longest_hold_s(record.displacement, rate),
        }
    else:
        peaks_f, peaks_q = np.abs(record.f).max(axis=0), np.abs(record.q).max(axis=0)
        entry["max_abs"] = {c: float(v) for c, v in zip(record.coords, peaks_f, strict=True)}
        entry["peak_deflection"] = {
            c: float(v) for c, v in zip(record.coords, peaks_q, strict=True)
        }
        rates = np.abs(np.diff(record.q, axis=0)).max(axis=0) * record.sample_rate_hz
        entry["peak_rate"] = {c: float(v) for c, v in zip(record.coords, rates, strict=True)}
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
