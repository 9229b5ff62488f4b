"""The planar reference is checked before it judges, as the one-axis one is (``bushenv.vetting``).

The one-axis checks and passivity, in three coordinates (axial m, radial m, rotation rad):

1. **holds** of the whole deflection vector: ramp in ``RAMP_S`` to each held vector, hold
   ``HOLD_S``; the vectors are every coordinate alone at ``LEVELS`` of its stroke and the eight
   corners of ``CORNER`` x the stroke box (coupling shows where coordinates combine). A
   passive bushing only relaxes in a hold: in no coordinate does the force oscillate (tail less a
   straight line moves by more than that coordinate's floor), depart (grow by more than
   ``DEPART_FRACTION`` of its held value, at least the floor, or change sign), and the work
   ``q . f`` (N m, the stored energy's sign) is positive beyond ``SIGN_FRACTION`` of the stroke:
   a coupled bushing may push sideways, never back into the deflection it holds.
2. **records**: on the records its own card names (a planar card), the worst coordinate's RMS
   ratio at most ``bushenv.vetting.RECORD_LIMIT``.
3. **passivity** (``passivity.py``): at ``PASSIVE_HOLDS`` (rest, a radial and a rotational
   preload) and ``PASSIVE_HZ``, the loss matrix of the dynamic stiffness K(jw) positive
   semidefinite: a reference that gives energy back on some small orbit is no bushing.
4. **compatibility** with the model under test: on the records the model's card names, the
   reference's worst RMS ratio at most that limit; with none, the diagonal of the two 3x3
   stiffness matrices least-squares fitted on one random drive within the stroke, each within a
   factor ``STIFFNESS_MISMATCH`` -- beyond, a warning (the model is then the only word on which
   bushing it is, and a broken model looks like another bushing).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.identify.card import card_paths
from bushenv.metrics import rms_ratio
from bushenv.models.planar_base import COORDS, PlanarModel
from bushenv.scales import STIFFNESS_MISMATCH
from bushenv.vetting import (
    DEPART_FRACTION,
    HOLD_S,
    RAMP_S,
    RECORD_LIMIT,
    SETTLE_S,
    SIGN_FRACTION,
    TAIL_S,
    Check,
    Vetting,
    card_records,
    judged_errors,
    record_errors,
)

LEVELS = (-1.0, -0.6, -0.3, -0.1, 0.1, 0.3, 0.6, 1.0)
CORNER = 0.6
DRIVE_S = 20.0  # the random drive of the stiffness comparison
UNITS = ("mm", "mm", "mrad")
PASSIVE_HOLDS = ((0.0, 0.0, 0.0), (0.0, 0.3, 0.0), (0.0, 0.0, 0.3))  # fractions of the stroke
PASSIVE_HZ = np.geomspace(0.2, 40.0, 12)


def held_vectors(stroke: np.ndarray) -> np.ndarray:
    """(H, 3) held deflection vectors: each coordinate alone at ``LEVELS``, and the corners."""
    alone = [np.eye(3)[i] * lv for i in range(3) for lv in LEVELS]
    corners = [np.array([a, b, c]) * CORNER for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]
    return np.array(alone + corners) * np.asarray(stroke, float)[None, :]


def _run(model: PlanarModel, q: np.ndarray) -> np.ndarray:
    return model.copy().simulate(q)


def hold_check(reference: PlanarModel, stroke: np.ndarray, floors: np.ndarray) -> Check:
    """Check 1 of the module doc."""
    dt = reference.dt
    qs = held_vectors(stroke)
    n_ramp, n_hold = max(2, int(round(RAMP_S / dt))), int(round(HOLD_S / dt))
    ramp = np.linspace(0.0, 1.0, n_ramp)[:, None, None] * qs[None]
    q = np.concatenate([ramp, np.repeat(qs[None], n_hold, axis=0)])  # (T, H, 3)
    try:
        f = _run(reference, q)
    except Exception as exc:  # a reference that cannot even run its holds
        return Check("holds", False, f"the reference raised {type(exc).__name__}: {exc}")
    settle = n_ramp + int(round(SETTLE_S / dt))
    tail = f[-int(round(TAIL_S / dt)) :]
    t = np.arange(tail.shape[0])
    found: dict[str, list[int]] = {"not finite": [], "oscillating": [], "departing": [],
                                   "pushing into the deflection": []}  # fmt: skip
    for j, qj in enumerate(qs):
        col = f[:, j, :]
        if not np.all(np.isfinite(col)):
            found["not finite"].append(j)
            continue
        for i in range(3):
            line = np.polyval(np.polyfit(t, tail[:, j, i], 1), t)
            if np.ptp(tail[:, j, i] - line) > floors[i]:
                found["oscillating"].append(j)
                break
        f0, f1 = col[settle], col[-1]
        grows = np.abs(f1) - np.abs(f0) > np.maximum(floors, DEPART_FRACTION * np.abs(f0))
        flips = (np.abs(f0) > floors) & (np.abs(f1) > floors) & (np.sign(f0) != np.sign(f1))
        if np.any(grows | flips):
            found["departing"].append(j)
        far = np.max(np.abs(qj) / stroke) >= SIGN_FRACTION
        floor_work = float(np.sum(floors * np.abs(qj)))
        if far and float(np.dot(qj, f1)) < -floor_work:
            found["pushing into the deflection"].append(j)
    span = (
        f"{len(qs)} holds of {HOLD_S:g} s over +-("
        + ", ".join(f"{1e3 * s:.3g} {u}" for s, u in zip(stroke, UNITS, strict=True))
        + ")"
    )
    bad = {k: v for k, v in found.items() if v}
    if not bad:
        return Check("holds", True, f"{span}: every hold settles, pushes back, stays finite")
    parts = [f"{len(v)} {k} (first at {_vector(qs[v[0]])})" for k, v in bad.items()]
    return Check("holds", False, f"{span}: " + ", ".join(parts))


def passivity_check(reference: PlanarModel, stroke: np.ndarray) -> Check:
    """Check 3 of the module doc."""
    from bushenv.planar.passivity import passivity

    q0 = np.array(PASSIVE_HOLDS) * stroke[None, :]
    hz = PASSIVE_HZ[PASSIVE_HZ < 0.45 / reference.dt]
    try:
        rep = passivity(reference, q0, hz)
    except Exception as exc:
        return Check("passivity", None, f"not measured ({type(exc).__name__}: {exc})")
    span = f"{len(q0)} holds x {len(hz)} frequencies {hz[0]:.2g}-{hz[-1]:.3g} Hz ({rep.method})"
    if rep.passive:
        return Check("passivity", True, f"{span}: least loss eigenvalue {rep.min_eig:.4g} J")
    row, bands = rep.active_bands()[0]
    where = ", ".join(f"{a:.3g}-{b:.3g} Hz" for a, b in bands)
    return Check(
        "passivity",
        False,
        f"{span}: it gives energy back at the hold {_vector(rep.q[row])}, {where} (least loss "
        f"eigenvalue {rep.min_eig:.4g} J)",
    )


def _vector(q: np.ndarray) -> str:
    return "(" + ", ".join(f"{1e3 * v:+.3g} {u}" for v, u in zip(q, UNITS, strict=True)) + ")"


def _read_card(path: Any) -> tuple[dict | None, Path | None]:
    """The planar card beside a model file (None when there is none or it is unreadable)."""
    if path is None or not str(path).endswith(".npz"):
        return None, None
    card_file = card_paths(Path(path))[0]
    try:
        return json.loads(card_file.read_text(encoding="utf-8")), card_file
    except (OSError, ValueError):
        return None, None


def _record_errors(reference: PlanarModel, paths: list[Path]) -> list[tuple[str, float]]:
    from bushenv.planar.records import load_planar_csv, only_noise

    def worst(rec) -> float:  # the worst coordinate's RMS ratio
        f = _run(reference, rec.q)
        if not np.all(np.isfinite(f)):
            return float("inf")
        judged = np.flatnonzero(~only_noise(rec.q, rec.f))
        return max((float(rms_ratio(rec.f[:, i], f[:, i])) for i in judged), default=0.0)

    return record_errors(paths, reference.dt, load_planar_csv, worst)


def records_check(reference: PlanarModel, reference_file: Any) -> Check:
    """Check 2: the reference's worst-coordinate error on the records its card names."""
    card, card_file = _read_card(reference_file)
    if card is None:
        return Check("records", None, "no model card: nothing to check it against")
    paths, missing = card_records(card, card_file)
    if not paths:
        return Check("records", None, f"its card's records are not there ({', '.join(missing)})")
    return judged_errors("records", _record_errors(reference, paths), "its card's records (worst "
                   "coordinate)", RECORD_LIMIT)  # fmt: skip


def _stiffness(model: PlanarModel, stroke: np.ndarray) -> np.ndarray:
    """Diagonal of the 3x3 K of ``f = K q + C v + b`` least-squares fitted on a random drive."""
    dt = model.dt
    n = int(round(DRIVE_S / dt))
    rng = np.random.default_rng(0)
    t = np.arange(n) * dt
    q = np.zeros((n, 3))
    for i in range(3):  # a few incommensurate sines per coordinate, 0.3-3 Hz, half the stroke
        hz = rng.uniform(0.3, 3.0, size=4)
        ph = rng.uniform(0, 2 * np.pi, size=4)
        q[:, i] = 0.5 * stroke[i] * np.sin(2 * np.pi * hz[:, None] * t + ph[:, None]).sum(0) / 2
    q *= np.minimum(1.0, t / 1.0)[:, None]  # from rest
    f = _run(model, q)
    v = np.gradient(q, dt, axis=0)
    a = np.column_stack([q, v, np.ones(n)])
    w, *_ = np.linalg.lstsq(a, f, rcond=None)
    return np.diag(w[:3].T)


def compatibility_check(
    reference: PlanarModel, model: PlanarModel | None, model_file: Any, stroke: np.ndarray
) -> Check:
    """Check 4: the reference and the model under test are models of one bushing."""
    card, card_file = _read_card(model_file)
    paths, _ = card_records(card, card_file)
    if paths:
        return judged_errors("compatibility", _record_errors(reference, paths),
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
    units = ("N/mm", "N/mm", "N m/mrad")
    text = "dynamic stiffness on a random drive, reference / model: " + ", ".join(
        f"{c} {kr / 1e3:.4g} / {km / 1e3:.4g} {u}"
        for c, kr, km, u in zip(COORDS, k_ref, k_mod, units, strict=True)
    )
    worst = float(ratio.max())
    if worst <= STIFFNESS_MISMATCH:
        return Check("compatibility", True, f"{text} (within {STIFFNESS_MISMATCH:g}: one bushing)")
    return Check(
        "compatibility",
        None,
        f"WARNING: {text}: a factor {worst:.3g} on the {COORDS[int(ratio.argmax())]} axis (beyond "
        f"{STIFFNESS_MISMATCH:g}: another bushing, or a broken model; a model card with its "
        "records decides)",
    )


def vet_planar_reference(
    reference: PlanarModel,
    label: str,
    stroke: np.ndarray,
    floors: np.ndarray,
    reference_file: Any = None,
    model: PlanarModel | None = None,
    model_file: Any = None,
) -> Vetting:
    """The three checks of the module doc on the planar ``reference`` within ``stroke`` (3,)
    with the judge's force ``floors`` (3,) (N, N, N m)."""
    stroke, floors = np.asarray(stroke, float), np.asarray(floors, float)
    checks = [
        hold_check(reference, stroke, floors),
        records_check(reference, reference_file),
        passivity_check(reference, stroke),
        compatibility_check(reference, model, model_file, stroke),
    ]
    return Vetting(label, tuple(checks))
