"""The reference's error on recorded data: on the records its own card names (``records``) and
on those the model under test's card names (``compatibility``), for any number of coordinates
(the worst coordinate's RMS ratio), at most ``RECORD_LIMIT``; without such records, the
stiffness of both compared (``bushenv.vetting`` states the checks)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.identify.card import card_paths
from bushenv.metrics import rms_ratio
from bushenv.models import BushingModel
from bushenv.scales import STIFFNESS_MISMATCH, BushingScales
from bushenv.vetting_check import RECORD_LIMIT, Check

DRIVE_S = 20.0  # the random drive of the vector stiffness comparison


def card_records(card: dict | None, card_file: Any) -> tuple[list[Path], list[str]]:
    """The record files a card names that exist (relative paths against the card's folder),
    and the names of those that do not."""
    if not card:
        return [], []
    base = Path(os.fspath(card_file)).parent if card_file is not None else Path(".")
    found, missing = [], []
    for r in card.get("records", []):
        name = r.get("file") or r.get("name")
        if not name:
            continue
        p = Path(name)
        for cand in (p, base / p) if not p.is_absolute() else (p,):
            if cand.is_file():
                found.append(cand)
                break
        else:
            missing.append(str(name))
    return found, missing


def record_errors(paths: list[Path], dt: float, load, error) -> list[tuple[str, float]]:
    """(file name, ``error(record)``) per record file (``load`` reads one); NaN for a record at
    another sample time than ``dt`` (not comparable)."""
    out = []
    for p in paths:
        rec = load(p)
        if abs(rec.dt - dt) > 1e-6 * dt:
            out.append((p.name, float("nan")))
            continue
        out.append((p.name, float(error(rec))))
    return out


def reference_errors(reference: BushingModel, paths: list[Path]) -> list[tuple[str, float]]:
    """(file name, the reference's worst RMS ratio over the record's coordinates) per record
    file; a coordinate held at rest with only its sensor's noise is not judged
    (``record_notes.only_noise``: a ratio to noise judges nothing)."""
    from bushenv.record_files import load_record
    from bushenv.record_notes import only_noise

    def error(rec) -> float:
        f = reference.copy().simulate(rec.displacement).reshape(rec.f.shape)
        if not np.all(np.isfinite(f)):
            return np.inf
        judged = np.flatnonzero(~only_noise(rec.q, rec.f)) if rec.n_coords > 1 else [0]
        return max((float(rms_ratio(rec.f[:, i], f[:, i])) for i in judged), default=0.0)

    return record_errors(paths, reference.dt, lambda p: load_record(p, reference.n_coords), error)


def records_check(reference: BushingModel, card: dict | None, card_file: Any, what: str) -> Check:
    """Check 2: the reference's error on the records its card names."""
    if card is None:
        return Check(
            "records", None, "no model card naming the records it was fitted on: give a "
            "reference file with its card beside it (MODEL.card.json; bushenv fit writes it)",
        )  # fmt: skip
    paths, missing = card_records(card, card_file)
    if not paths:
        where = "" if card_file is None else f" beside {Path(os.fspath(card_file)).parent}"
        return Check(
            "records", None, f"{what} ({', '.join(missing) or 'none named'}) are not there: "
            f"put the record files{where} or at the paths the card names",
        )  # fmt: skip
    errors = reference_errors(reference, paths)
    return judged_errors("records", errors, what, RECORD_LIMIT)


def judged_errors(name: str, errors: list[tuple[str, float]], what: str, limit: float) -> Check:
    text = ", ".join(f"{n} {e:.1%}" if np.isfinite(e) else f"{n} not comparable" for n, e in errors)
    usable = [e for _, e in errors if not np.isnan(e)]
    if not usable:
        return Check(
            name, None, f"{what}: at another sample rate than the reference ({text}); give "
            "records at its rate",
        )  # fmt: skip
    worst = max(usable)
    ok = bool(worst <= limit)
    verdict = "within" if ok else "beyond"
    return Check(name, ok, f"RMS ratio on {what}: {text}, {verdict} {limit:.0%}")


def compatibility_check(
    reference: BushingModel,
    scales: BushingScales,
    model: BushingModel | None,
    model_card: dict | None,
    model_file: Any,
) -> Check:
    """Check 3: the reference and the model under test are models of one bushing."""
    paths, _ = card_records(model_card, model_file)
    if paths:
        errors = reference_errors(reference, paths)
        return judged_errors("compatibility", errors, "the model's card's records", RECORD_LIMIT)
    if model is None:
        return Check("compatibility", None, "no model under test to compare with (a rig judges "
                     "the model's own limits only)")  # fmt: skip
    from bushenv.identify.linear import fitted_linear

    try:
        k_ref = fitted_linear(reference, scales).k_n_per_m
        k_mod = fitted_linear(model, scales).k_n_per_m
    except Exception as exc:
        return Check("compatibility", None, f"no stiffness to compare ({type(exc).__name__}: "
                     f"{exc}); give the model's card with its records")  # fmt: skip
    if not (np.isfinite(k_ref) and np.isfinite(k_mod) and k_ref > 0 and k_mod > 0):
        return Check("compatibility", None, "a stiffness is not finite or not positive; give "
                     "the model's card with its records")  # fmt: skip
    ratio = max(k_ref / k_mod, k_mod / k_ref)
    text = (
        f"dynamic stiffness on a random drive: reference {k_ref / 1e3:.4g} N/mm, model "
        f"{k_mod / 1e3:.4g} N/mm, a factor {ratio:.3g}"
    )
    if ratio <= STIFFNESS_MISMATCH:
        return Check("compatibility", True, f"{text} (within {STIFFNESS_MISMATCH:g}: one bushing)")
    # without records the model is the only word on which bushing it is, and the model is
    # what is under suspicion: another bushing, or a broken model -- records would decide
    return Check(
        "compatibility",
        None,
        f"undecided: {text}, beyond {STIFFNESS_MISMATCH:g}: another bushing, or a broken "
        "model; give the model under test with its card and records (bushenv fit writes "
        "MODEL.card.json beside it) and the reference is compared on those records",
    )


def read_card(path: Any) -> tuple[dict | None, Path | None]:
    """The card beside a model file (None when there is none or it is unreadable)."""
    if path is None or not str(path).endswith(".npz"):
        return None, None
    card_file = card_paths(Path(path))[0]
    try:
        return json.loads(card_file.read_text(encoding="utf-8")), card_file
    except (OSError, ValueError):
        return None, None


def file_records_check(reference: BushingModel, reference_file: Any) -> Check:
    """Check 2 for a reference given as a file: the worst coordinate's error on the records
    the card beside it names."""
    card, card_file = read_card(reference_file)
    if card is None:
        return Check("records", None, "no model card: nothing to check it against")
    paths, missing = card_records(card, card_file)
    if not paths:
        return Check("records", None, f"its card's records are not there ({', '.join(missing)})")
    return judged_errors("records", reference_errors(reference, paths), "its card's records (worst "
                   "coordinate)", RECORD_LIMIT)  # fmt: skip


def _stiffness(model: BushingModel, stroke: np.ndarray) -> np.ndarray:
    """Diagonal of the C x C K of ``f = K q + C v + b`` least-squares fitted on a random drive."""
    dt = model.dt
    n = int(round(DRIVE_S / dt))
    rng = np.random.default_rng(0)
    t = np.arange(n) * dt
    c = len(stroke)
    q = np.zeros((n, c))
    for i in range(c):  # a few incommensurate sines per coordinate, 0.3-3 Hz, half the stroke
        hz = rng.uniform(0.3, 3.0, size=4)
        ph = rng.uniform(0, 2 * np.pi, size=4)
        q[:, i] = 0.5 * stroke[i] * np.sin(2 * np.pi * hz[:, None] * t + ph[:, None]).sum(0) / 2
    q *= np.minimum(1.0, t / 1.0)[:, None]  # from rest
    f = model.copy().simulate(q)
    v = np.gradient(q, dt, axis=0)
    a = np.column_stack([q, v, np.ones(n)])
    w, *_ = np.linalg.lstsq(a, f, rcond=None)
    return np.diag(w[:c].T)


def vector_compatibility_check(
    reference: BushingModel, model: BushingModel | None, model_file: Any, stroke: np.ndarray
) -> Check:
    """Check 4 over several coordinates: on the model's card's records the worst coordinate's
    RMS ratio; without them, the diagonal of the two stiffness matrices least-squares fitted on
    one random drive within ``stroke``, each within ``STIFFNESS_MISMATCH``."""
    card, card_file = read_card(model_file)
    paths, _ = card_records(card, card_file)
    if paths:
        return judged_errors("compatibility", reference_errors(reference, paths),
                       "the model's card's records (worst coordinate)", RECORD_LIMIT)  # fmt: skip
    if model is None:
        return Check("compatibility", None, "no model under test to compare with")
    try:
        k_ref, k_mod = _stiffness(reference, stroke), _stiffness(model, stroke)
    except Exception as exc:
        return Check("compatibility", None, f"no stiffness to compare ({type(exc).__name__})")
    if not (np.all(np.isfinite(k_ref)) and np.all(np.isfinite(k_mod))) or np.any(k_ref <= 0) or \
            np.any(k_mod <= 0):  # fmt: skip
        return Check("compatibility", None, "a stiffness is not finite or not positive")
    ratio = np.maximum(k_ref / k_mod, k_mod / k_ref)
    units = ["N m/mrad" if u == "rad" else "N/mm" for u in reference.units]
    text = "dynamic stiffness on a random drive, reference / model: " + ", ".join(
        f"{c} {kr / 1e3:.4g} / {km / 1e3:.4g} {u}"
        for c, kr, km, u in zip(reference.coords, k_ref, k_mod, units, strict=True)
    )
    worst = float(ratio.max())
    if worst <= STIFFNESS_MISMATCH:
        return Check("compatibility", True, f"{text} (within {STIFFNESS_MISMATCH:g}: one bushing)")
    return Check(
        "compatibility",
        None,
        f"WARNING: {text}: a factor {worst:.3g} on the "
        f"{reference.coords[int(ratio.argmax())]} axis (beyond "
        f"{STIFFNESS_MISMATCH:g}: another bushing, or a broken model; a model card with its "
        "records decides)",
    )
