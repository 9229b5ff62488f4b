"""The reference is checked before it judges (``judge.build_judge`` calls ``vet_reference``).

A verdict says "the model departs from the real bushing"; it is worth only what the reference
is. Three checks, each with a physical reason and a threshold stated here:

1. **holds** over the judged stroke: ramp to each of ``HOLDS`` displacements in 0.25 s, hold
   ``HOLD_S``. A passive bushing only relaxes in a hold: its force never oscillates, never grows
   away from its value after the first second, and pushes back (``f x > 0``). Flagged:
   *oscillating* (the force, less a straight line, still moves by more than the floor over the
   last ``TAIL_S``), *departing* (it grows by more than ``DEPART_FRACTION`` of its held value,
   at least the floor, or changes sign), *wrong sign* (beyond ``SIGN_FRACTION`` of the stroke
   it pulls by more than the floor), *not finite*.
2. **records**: the reference's RMS ratio on the records its model card names (when it has a
   card and they are there) at most ``RECORD_LIMIT``: 30 % is beyond every fitted model of the
   papers (Tables 2-4) and beyond any model worth judging with.
3. **compatibility** with the model under test: on the records the model's own card names,
   the reference's RMS ratio at most ``RECORD_LIMIT`` (it is a model of the same bushing: a
   reference 3.2 times as stiff is refused). With no such records, the least-squares stiffness
   of both on one random drive within the stroke is compared: within a factor
   ``scales.STIFFNESS_MISMATCH`` (2) it passes; beyond, it is a warning, not a refusal -- the
   model under suspicion is then the only word on which bushing it is, and a broken model
   looks like another bushing.

Each check is ``passed`` True, False, or None (not run, or undecided: the detail says why).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.metrics import rms_ratio
from bushenv.models import BushingModel
from bushenv.scales import STIFFNESS_MISMATCH, BushingScales

HOLDS = 41
RAMP_S = 0.25
HOLD_S = 4.0
SETTLE_S = 1.0
TAIL_S = 2.0
DEPART_FRACTION = 0.25
SIGN_FRACTION = 0.1
RECORD_LIMIT = 0.30


@dataclass(frozen=True)
class Check:
    name: str
    passed: bool | None
    detail: str

    def describe(self) -> dict[str, Any]:
        return {"check": self.name, "passed": self.passed, "detail": self.detail}


@dataclass(frozen=True)
class Vetting:
    reference: str
    checks: tuple[Check, ...]

    @property
    def passed(self) -> bool:
        return all(c.passed is not False for c in self.checks)

    def summary(self) -> str:
        bad = [f"{c.name}: {c.detail}" for c in self.checks if c.passed is False]
        return "; ".join(bad) if bad else "passed"

    def describe(self) -> dict[str, Any]:
        return {
            "reference": self.reference,
            "passed": self.passed,
            "checks": [c.describe() for c in self.checks],
        }

    def lines(self) -> list[str]:
        mark = {True: "ok", False: "FAILED", None: "undecided"}
        return [f"{c.name}: {mark[c.passed]} ({c.detail})" for c in self.checks]


def vet_reference(
    reference: BushingModel,
    label: str,
    scales: BushingScales,
    card: dict | None = None,
    card_file: Any = None,
    model: BushingModel | None = None,
    model_card: dict | None = None,
    model_file: Any = None,
) -> Vetting:
    """The three checks of the module doc on ``reference`` at ``scales``."""
    checks = [
        hold_check(reference, scales),
        records_check(reference, card, card_file, "its own card's records"),
        compatibility_check(reference, scales, model, model_card, model_file),
    ]
    return Vetting(label, tuple(checks))


def hold_profiles(stroke_m: float, dt: float, holds: int = HOLDS) -> tuple[np.ndarray, np.ndarray]:
    """(T, holds) ramp-and-hold displacements over -stroke..+stroke, and the held values."""
    xs = np.linspace(-stroke_m, stroke_m, holds)
    n_ramp = max(2, int(round(RAMP_S / dt)))
    n_hold = int(round(HOLD_S / dt))
    ramp = np.linspace(0.0, 1.0, n_ramp)[:, None] * xs[None, :]
    return np.vstack([ramp, np.repeat(xs[None, :], n_hold, axis=0)]), xs


def hold_check(reference: BushingModel, scales: BushingScales) -> Check:
    """Check 1 of the module doc."""
    dt = reference.dt
    x, xs = hold_profiles(scales.stroke_m, dt)
    try:
        f = reference.copy().simulate(x)
    except Exception as exc:  # a reference that cannot even run its holds
        return Check("holds", False, f"the reference raised {type(exc).__name__}: {exc}")
    n_ramp = x.shape[0] - int(round(HOLD_S / dt))
    settle = n_ramp + int(round(SETTLE_S / dt))
    tail = f[-int(round(TAIL_S / dt)) :]
    floor = scales.force_floor_n
    found: dict[str, list[float]] = {"not finite": [], "oscillating": [], "departing": [],
                                     "wrong sign": []}  # fmt: skip
    t = np.arange(tail.shape[0])
    for j, xj in enumerate(xs):
        col = f[:, j]
        if not np.all(np.isfinite(col)):
            found["not finite"].append(xj)
            continue
        line = np.polyval(np.polyfit(t, tail[:, j], 1), t)
        if np.ptp(tail[:, j] - line) > floor:
            found["oscillating"].append(xj)
        f0, f1 = col[settle], col[-1]
        grows = abs(f1) - abs(f0) > max(floor, DEPART_FRACTION * abs(f0))
        flips = abs(f0) > floor and abs(f1) > floor and np.sign(f0) != np.sign(f1)
        if grows or flips:
            found["departing"].append(xj)
        if abs(xj) >= SIGN_FRACTION * scales.stroke_m and f1 * xj < 0 and abs(f1) > floor:
            found["wrong sign"].append(xj)
    bad = {k: v for k, v in found.items() if v}
    span = f"{len(xs)} holds of {HOLD_S:g} s over +-{scales.stroke_m * 1e3:.3g} mm"
    if not bad:
        return Check("holds", True, f"{span}: every hold settles, pushes back, stays finite")
    parts = [
        f"{len(v)} {k} between {min(v) * 1e3:+.3g} and {max(v) * 1e3:+.3g} mm"
        for k, v in bad.items()
    ]
    return Check("holds", False, f"{span}: " + ", ".join(parts) + f" (floor {floor:.4g} N)")


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


def _record_errors(reference: BushingModel, paths: list[Path]) -> list[tuple[str, float]]:
    from bushenv.records import load_csv

    def error(rec) -> float:
        f = reference.copy().simulate(rec.displacement)
        return float(rms_ratio(rec.force, f)) if np.all(np.isfinite(f)) else np.inf

    return record_errors(paths, reference.dt, load_csv, error)


def records_check(reference: BushingModel, card: dict | None, card_file: Any, what: str) -> Check:
    """Check 2: the reference's error on the records its card names."""
    if card is None:
        return Check("records", None, "no model card: nothing to check it against")
    paths, missing = card_records(card, card_file)
    if not paths:
        return Check("records", None, f"{what} are not there ({', '.join(missing) or 'none'})")
    errors = _record_errors(reference, paths)
    return judged_errors("records", errors, what, RECORD_LIMIT)


def judged_errors(name: str, errors: list[tuple[str, float]], what: str, limit: float) -> Check:
    text = ", ".join(f"{n} {e:.1%}" if np.isfinite(e) else f"{n} not comparable" for n, e in errors)
    usable = [e for _, e in errors if not np.isnan(e)]
    if not usable:
        return Check(name, None, f"{what}: another sample rate ({text})")
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
        errors = _record_errors(reference, paths)
        return judged_errors("compatibility", errors, "the model's card's records", RECORD_LIMIT)
    if model is None:
        return Check("compatibility", None, "no model under test to compare with")
    from bushenv.identify.linear import fitted_linear

    try:
        k_ref = fitted_linear(reference, scales).k_n_per_m
        k_mod = fitted_linear(model, scales).k_n_per_m
    except Exception as exc:
        return Check("compatibility", None, f"no stiffness to compare ({type(exc).__name__})")
    if not (np.isfinite(k_ref) and np.isfinite(k_mod) and k_ref > 0 and k_mod > 0):
        return Check("compatibility", None, "a stiffness is not finite or not positive")
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
        f"WARNING: {text} (beyond {STIFFNESS_MISMATCH:g}: another bushing, or a broken model; "
        "a model card with its records decides)",
    )
