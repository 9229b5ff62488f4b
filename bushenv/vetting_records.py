"""The reference's error on recorded data: on the records its own card names (``records``) and
on those the model under test's card names (``compatibility``), for any number of coordinates
(the worst coordinate's RMS ratio), at most ``RECORD_LIMIT``; without such records, the
stiffness of both compared (``bushenv.vetting`` states the checks)."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.identify.card import card_paths
from bushenv.metrics import rms_ratio
from bushenv.models import BushingModel
from bushenv.scales import STIFFNESS_MISMATCH, BushingScales
from bushenv.vetting_check import RECORD_LIMIT, Check


@dataclass(frozen=True)
class _Limits:
    """A stroke and a rate per coordinate, as ``fitted_linear`` takes them."""

    stroke: np.ndarray
    rate: np.ndarray


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


def records_check(reference: BushingModel, card: dict | None, card_file: Any) -> Check:
    """Check 3: the reference's error on the records its card names (the worst coordinate's
    over several); ``card`` None: the card beside the model file ``card_file``, if any."""
    if card is None:
        card, card_file = read_card(card_file)
    if card is None:
        return Check(
            "records", None, "no model card naming the records it was fitted on: give a "
            "reference file with its card beside it (MODEL.card.json; bushenv fit writes it)",
        )  # fmt: skip
    what = "its own card's records" + _worst(reference)
    paths, missing = card_records(card, card_file)
    if not paths:
        where = "" if card_file is None else f" beside {Path(os.fspath(card_file)).parent}"
        return Check(
            "records", None, f"{what} ({', '.join(missing) or 'none named'}) are not there: "
            f"put the record files{where} or at the paths the card names",
        )  # fmt: skip
    return judged_errors("records", reference_errors(reference, paths), what, RECORD_LIMIT)


def _worst(model: BushingModel) -> str:
    return " (worst coordinate)" if model.n_coords > 1 else ""


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
    stroke,
    velocity,
    model: BushingModel | None,
    model_card: dict | None,
    model_file: Any,
) -> Check:
    """Check 5: the reference and the model under test are models of one bushing: on the
    records the model's card names (``model_card`` None: the card beside ``model_file``), else
    by the diagonal of their stiffness (``identify.linear.fitted_linear`` on one random drive
    within ``stroke`` and ``velocity`` per coordinate; None: no rate limit)."""
    if model_card is None:
        model_card, card_file = read_card(model_file)
    else:
        card_file = model_file
    paths, _ = card_records(model_card, card_file)
    if paths:
        errors = reference_errors(reference, paths)
        what = "the model's card's records" + _worst(reference)
        return judged_errors("compatibility", errors, what, RECORD_LIMIT)
    if model is None:
        return Check("compatibility", None, "no model under test to compare with (a rig judges "
                     "the model's own limits only)")  # fmt: skip
    try:
        k_ref, k_mod = _stiffness(reference, stroke, velocity), _stiffness(model, stroke, velocity)
    except Exception as exc:
        return Check("compatibility", None, f"no stiffness to compare ({type(exc).__name__}: "
                     f"{exc}); give the model's card with its records")  # fmt: skip
    if not (np.all(np.isfinite(k_ref)) and np.all(np.isfinite(k_mod))) or np.any(k_ref <= 0) or \
            np.any(k_mod <= 0):  # fmt: skip
        return Check("compatibility", None, "a stiffness is not finite or not positive; give "
                     "the model's card with its records")  # fmt: skip
    ratio = np.maximum(k_ref / k_mod, k_mod / k_ref)
    worst = int(ratio.argmax())
    units = ["N m/mrad" if u == "rad" else "N/mm" for u in reference.units]
    shown = [f"reference {kr / 1e3:.4g} {u}, model {km / 1e3:.4g} {u}"
             for kr, km, u in zip(k_ref, k_mod, units, strict=True)]  # fmt: skip
    if reference.n_coords == 1:
        text = f"dynamic stiffness on a random drive: {shown[0]}, a factor {ratio[0]:.3g}"
    else:
        text = (
            "dynamic stiffness on a random drive: "
            + "; ".join(f"{c} {s}" for c, s in zip(reference.coords, shown, strict=True))
            + f"; a factor {ratio[worst]:.3g} on the {reference.coords[worst]} coordinate"
        )
    if ratio[worst] <= STIFFNESS_MISMATCH:
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


def _stiffness(model: BushingModel, stroke, velocity) -> np.ndarray:
    """(C,) the diagonal of the stiffness of the Kelvin-Voigt least-squares fit of ``model``
    (``identify.linear.fitted_linear``) on a random drive per coordinate."""
    from bushenv.identify.linear import fitted_linear

    c = model.n_coords
    stroke = np.broadcast_to(np.asarray(stroke, dtype=np.float64), (c,))
    if c == 1:
        scales = BushingScales(stroke_m=float(stroke[0]))  # the papers' rate unless given
        if velocity is not None:
            scales = BushingScales(stroke_m=float(stroke[0]), velocity_m_per_s=float(velocity))
        return np.array([fitted_linear(model, scales).k_n_per_m])
    rate = np.broadcast_to(np.asarray(np.inf if velocity is None else velocity, float), (c,))
    return np.diag(np.atleast_2d(fitted_linear(model, _Limits(stroke, rate)).k_matrix)).copy()


def read_card(path: Any) -> tuple[dict | None, Path | None]:
    """The card beside a model file (None when there is none or it is unreadable)."""
    if path is None or not str(path).endswith(".npz"):
        return None, None
    card_file = card_paths(Path(path))[0]
    try:
        return json.loads(card_file.read_text(encoding="utf-8")), card_file
    except (OSError, ValueError):
        return None, None
