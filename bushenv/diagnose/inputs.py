"""What the diagnosis takes in: records checked and named, the baseline identified, and
records made ready for fitting (smoothed displacement, derivatives, baseline force), folds."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from bushenv.diagnose.candidates import effect_names, get_effect
from bushenv.diagnose.design import Prepared, smoothed_displacement
from bushenv.diagnose.effects.base import STENCILS, Signals
from bushenv.diagnose.errors import DiagnoseError
from bushenv.diagnose.fitting import Fold
from bushenv.models.base import DT_TOLERANCE
from bushenv.progress import Progress  # any callable of a line will do; fit.py types with it

MIN_SAMPLES = 64
LINEAR = "linear"


def baseline_names() -> list[str]:
    """Baselines ``diagnose`` accepts: the registered bushing models (``linear`` first)."""
    from bushenv.models import model_names

    return [LINEAR] + [n for n in model_names() if n != LINEAR]


# ----- inputs ----------------------------------------------------------------------------------
def _check_record(rec: Any, label: str) -> None:
    for attr in ("time", "displacement", "force", "dt"):
        if not hasattr(rec, attr):
            raise DiagnoseError(f"{label}: not a record (no .{attr})")
    n = np.asarray(rec.displacement).size
    if n < MIN_SAMPLES:
        raise DiagnoseError(f"{label}: {n} samples; the diagnosis needs at least {MIN_SAMPLES}")
    for attr in ("displacement", "force"):
        a = np.asarray(getattr(rec, attr), dtype=np.float64)
        if a.shape != (n,):
            raise DiagnoseError(f"{label}: {attr} has shape {a.shape}, expected ({n},)")
        if not np.all(np.isfinite(a)):
            raise DiagnoseError(f"{label}: {attr} holds NaN or inf")
    if not (np.isfinite(rec.dt) and rec.dt > 0):
        raise DiagnoseError(f"{label}: sample time {rec.dt!r} is not a positive number")
    if np.sqrt(np.mean(np.asarray(rec.force, dtype=np.float64) ** 2)) == 0:
        raise DiagnoseError(f"{label}: force is zero throughout; nothing to diagnose")
    if np.ptp(np.asarray(rec.displacement, dtype=np.float64)) == 0:
        raise DiagnoseError(f"{label}: displacement is constant; nothing identifies a baseline")


def record_name(rec: Any, default: str) -> str:
    path = getattr(rec, "path", None) or getattr(rec, "source", None)
    if path:
        from pathlib import Path

        return Path(str(path)).stem
    return getattr(rec, "name", None) or default


def names_of(recs: Sequence[Any], given: Sequence[str] | None, prefix: str) -> list[str]:
    names = list(given) if given is not None else []
    for i, rec in enumerate(recs):
        if i >= len(names):
            names.append(record_name(rec, f"{prefix}{i + 1}"))
    return names


def check_inputs(trains, tests, train_names, test_names, baseline, cross, effects) -> None:
    if baseline != LINEAR and baseline not in baseline_names():
        raise DiagnoseError(f"unknown baseline {baseline!r}; known: {', '.join(baseline_names())}")
    if not tests:
        raise DiagnoseError("no TEST record given; the gap is judged on held-out records only")
    for rec, n in zip(trains, train_names, strict=True):
        _check_record(rec, f"TRAIN {n}")
    for rec, n in zip(tests, test_names, strict=True):
        _check_record(rec, f"TEST {n}")
    if len(set(test_names)) != len(test_names):
        raise DiagnoseError(f"TEST records need distinct names (file stems), got {test_names}")
    if cross and len(set(train_names + test_names)) != len(trains) + len(tests):
        raise DiagnoseError(
            f"--cross judges every record: TRAIN and TEST names must all differ, got "
            f"{train_names} and {test_names}"
        )
    if effects is not None:
        for e in effects:
            get_effect(e)  # raises with the known names
        if not effects:
            raise DiagnoseError("no candidate effect chosen; known: " + ", ".join(effect_names()))
    if baseline == LINEAR:
        return
    if cross:
        raise DiagnoseError(
            f"cross mode refits the baseline on every fold, which only the linear baseline "
            f"does; use --baseline linear, or drop --cross to judge baseline {baseline!r} on "
            "the TESTs"
        )
    dt0 = float(trains[0].dt)
    for n, rec in zip(train_names[1:] + test_names, list(trains[1:]) + list(tests), strict=True):
        if abs(float(rec.dt) - dt0) > DT_TOLERANCE * dt0 * 1e3:
            raise DiagnoseError(
                f"{n}: sampled at {1 / rec.dt:.6g} Hz but TRAIN at {1 / dt0:.6g} Hz; baseline "
                f"{baseline!r} is a discrete-time model identified at the TRAIN rate. Resample "
                "the record or use --baseline linear (continuous-time)."
            )


def fit_nonlinear_baseline(name: str, rec: Any, seed: int, say: Progress):
    try:
        from bushenv.identify import fit_model  # the baselines' identification dispatcher
    except ImportError:
        raise DiagnoseError(
            f"baseline {name!r} needs bushenv.identify.fit_model, which is not available in "
            "this checkout; use --baseline linear"
        ) from None
    x = np.asarray(rec.displacement, dtype=np.float64)
    # its training lines go where the diagnosis's own go (nowhere with --quiet)
    f = np.asarray(rec.force, dtype=np.float64)
    return fit_model(name, x, f, float(rec.dt), seed, progress=say)


def _simulate(model: Any, x: np.ndarray) -> np.ndarray:
    out = np.asarray(model.simulate(x), dtype=np.float64)
    if not np.all(np.isfinite(out)):
        raise DiagnoseError(f"baseline {model.name!r} diverged (NaN/inf) in free run")
    return out


# ----- records ready for fitting ---------------------------------------------------------------
def _prepare(rec: Any, name: str, role: str, stencil: str, model: Any) -> Prepared:
    x = np.asarray(rec.displacement, dtype=np.float64)
    b0 = np.zeros_like(x) if model is None else _simulate(model, x)
    smooth, edge = smoothed_displacement(x, float(rec.dt))
    sig = Signals(smooth, float(rec.dt), stencil)
    force = np.asarray(rec.force, float)
    return Prepared(name, role, np.asarray(rec.time, float), sig, force, b0, edge)


def _stencil_error(preps: list[Prepared]) -> float:
    """Relative MSE of a spring, damper and mass fitted on the records."""
    a = np.concatenate([np.stack([p.signals.x, p.signals.v, p.signals.a], axis=1) for p in preps])
    y = np.concatenate([p.force - p.b0 for p in preps])
    a = a / np.sqrt(np.mean(a * a, axis=0))
    r = y - a @ np.linalg.lstsq(a, y, rcond=None)[0]
    return float(np.mean(r * r) / np.mean(y * y))


def prepare_records(trains, tests, train_names, test_names, model, cross: bool, say: Progress):
    """(train preps, test preps, stencil): the stencil fits the fitting records better."""
    fitting = list(zip(trains, train_names, strict=True))
    fitting += list(zip(tests, test_names, strict=True)) if cross else []
    errors = {}
    for stencil in STENCILS:
        errors[stencil] = _stencil_error(
            [_prepare(r, n, "fit", stencil, model) for r, n in fitting]
        )
    stencil = min(errors, key=errors.get)
    say(f"derivatives by the {stencil} stencil (better fit of spring, damper and mass)")
    tr = [_prepare(r, n, "train", stencil, model) for r, n in zip(trains, train_names, strict=True)]
    te = [_prepare(r, n, "test", stencil, model) for r, n in zip(tests, test_names, strict=True)]
    for p in tr + te:
        if p.band_edge_hz is not None:
            say(
                f"{p.name}: displacement has a noise floor above {p.band_edge_hz:.4g} Hz: "
                "differentiated low-passed below it"
            )
    return tr, te, stencil


def make_folds(tr: list[Prepared], te: list[Prepared], cross: bool) -> list[Fold]:
    if not cross:
        return [Fold(tuple(tr), tuple(te))]
    every = tr + te
    return [Fold(tuple(q for q in every if q is not p), (p,)) for p in every]
