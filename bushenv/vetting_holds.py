"""The holds a reference is vetted on: a line of held displacements for one coordinate
(``hold_check``, and the NARX reference's own certificate, ``certificate_check``), held
deflection vectors for several (``vector_hold_check``) and the passivity of the dynamic
stiffness matrix (``passivity_check``); ``bushenv.vetting`` states the checks."""

from __future__ import annotations

import numpy as np

from bushenv.certify.reached_holds import (
    DEPART_FRACTION,
    HOLD_S,
    SETTLE_S,
    TAIL_S,
    confirm_holds,
    failing_holds,
    hold_entries,
    judge_holds,
    ranges_of,
    ring_threshold,
)
from bushenv.models import BushingModel
from bushenv.scales import BushingScales
from bushenv.vetting_check import CERTIFICATE_HOLDS, HOLDS, RAMP_S, SIGN_FRACTION, Check


def hold_profiles(stroke_m: float, dt: float, holds: int = HOLDS) -> tuple[np.ndarray, np.ndarray]:
    """(T, holds) ramp-and-hold displacements over -stroke..+stroke, and the held values."""
    xs = np.linspace(-stroke_m, stroke_m, holds)
    n_ramp = max(2, int(round(RAMP_S / dt)))
    n_hold = int(round(HOLD_S / dt))
    ramp = np.linspace(0.0, 1.0, n_ramp)[:, None] * xs[None, :]
    return np.vstack([ramp, np.repeat(xs[None, :], n_hold, axis=0)]), xs


def hold_check(reference: BushingModel, scales: BushingScales) -> tuple[Check, float]:
    """Check 1 of the module doc, and the threshold it judged with (N; the certificate check
    uses it too)."""
    dt = reference.dt
    x, xs = hold_profiles(scales.stroke_m, dt)
    try:
        f = reference.copy().simulate(x)
    except Exception as exc:  # a reference that cannot even run its holds
        text = f"the reference raised {type(exc).__name__}: {exc}"
        return Check("holds", False, text), scales.force_floor_n
    th = ring_threshold(f, dt)
    limit = min(th.force_n, scales.force_floor_n)
    how = th.describe()  # capped: never coarser than the verdicts' resolution
    if th.force_n > limit:
        how = f"threshold {limit:.4g} N, the force floor, below the {how}"
    flags = judge_holds(f, xs, int(round(HOLD_S / dt)), limit, dt)
    flags["wrong sign"] &= np.abs(xs) >= SIGN_FRACTION * scales.stroke_m
    step = xs[1] - xs[0]
    span = f"{len(xs)} holds of {HOLD_S:g} s over +-{scales.stroke_m * 1e3:.3g} mm"
    bad = {k: xs[flags[k]] for k in KINDS if flags[k].any()}
    if not bad:
        text = f"{span}: every hold settles, pushes back, stays finite ({how})"
        return Check("holds", True, text), limit
    parts = [
        f"{len(v)} {k} between {v.min() * 1e3:+.3g} and {v.max() * 1e3:+.3g} mm"
        for k, v in bad.items()
    ]
    where = ranges_of([float(v) for vs in bad.values() for v in vs], step)
    return Check("holds", False, f"{span}: " + ", ".join(parts) + f" ({how})", tuple(where)), limit


KINDS = ("not finite", "oscillating", "departing", "wrong sign")


def certificate_check(
    reference: BushingModel,
    scales: BushingScales,
    envelope: tuple[float, float],
    threshold: float,
) -> Check | None:
    """Check 2 of the module doc; None for a reference that is not a NARX network."""
    from bushenv.certify.network import CertifyError

    try:
        entries = hold_entries(reference, None, scales.stroke_m, CERTIFICATE_HOLDS)
    except CertifyError:
        return None
    listed = failing_holds(entries)
    span = f"its certificate, {CERTIFICATE_HOLDS} holds over +-{scales.stroke_m * 1e3:.3g} mm,"
    if not listed:
        return Check("certificate holds", True, f"{span} lists none oscillating, departing or "
                     "wrong-sign")  # fmt: skip
    kinds = sorted({k for h in listed for k in h["kinds"]})
    xl = [h["x_m"] for h in listed]
    said = (
        f"{span} lists {len(listed)} ({', '.join(kinds)}) between {min(xl) * 1e3:+.3g} and "
        f"{max(xl) * 1e3:+.3g} mm"
    )
    confirmed, n = confirm_holds(reference, listed, envelope, threshold)
    reach = (
        f"{n} profiles reaching them after a step or sines inside its envelope (|x| <= "
        f"{envelope[0] * 1e3:.3g} mm, |dx/dt| <= {envelope[1]:.3g} m/s); threshold "
        f"{threshold:.4g} N"
    )
    if not confirmed:
        return Check("certificate holds", True, f"{said}; none confirmed by {reach}")
    worst = max(confirmed, key=lambda c: c.ripple_n)
    found = sorted({k for c in confirmed for k in c.kinds})
    xc = [c.x_m for c in confirmed]
    text = (
        f"{said}; {len(confirmed)} confirmed ({', '.join(found)}) between "
        f"{min(xc) * 1e3:+.3g} and {max(xc) * 1e3:+.3g} mm by {reach}; worst "
        f"{worst.ripple_n:.4g} N p-p at {worst.x_m * 1e3:+.3g} mm after {worst.after}"
    )
    # the listed runs holding a confirmed hold (not every listed hold is simulated)
    step = 2 * scales.stroke_m / (CERTIFICATE_HOLDS - 1)
    runs = [(a, b) for a, b in ranges_of(xl, step) if any(a <= x <= b for x in xc)]
    return Check("certificate holds", False, text, tuple(runs))


LEVELS = (-1.0, -0.6, -0.3, -0.1, 0.1, 0.3, 0.6, 1.0)
CORNER = 0.6
PASSIVE_HOLDS = ((0.0, 0.0, 0.0), (0.0, 0.3, 0.0), (0.0, 0.0, 0.3))  # fractions of the stroke
PASSIVE_HZ = np.geomspace(0.2, 40.0, 12)


def held_vectors(stroke: np.ndarray) -> np.ndarray:
    """(H, C) held deflection vectors: each coordinate alone at ``LEVELS`` of its stroke, and
    the 2^C corners of ``CORNER`` x the stroke box (coupling shows where coordinates
    combine)."""
    stroke = np.asarray(stroke, float)
    c = stroke.size
    alone = [np.eye(c)[i] * lv for i in range(c) for lv in LEVELS]
    signs = np.array(np.meshgrid(*[(-1, 1)] * c, indexing="ij")).reshape(c, -1).T
    return np.array(alone + [s * CORNER for s in signs]) * stroke[None, :]


def _run(model: BushingModel, q: np.ndarray) -> np.ndarray:
    return model.copy().simulate(q)


def vector_hold_check(reference: BushingModel, stroke: np.ndarray, floors: np.ndarray) -> Check:
    """Holds of the whole deflection vector (C > 1): the one-coordinate check's rules per
    coordinate (``bushenv.vetting``, check 1) over ``held_vectors``, each coordinate against its
    force floor; the work ``q . f`` (N m) positive beyond ``SIGN_FRACTION`` of the stroke: a
    coupled bushing may push sideways, never back into the deflection it holds."""
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
        for i in range(qs.shape[1]):
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
        + ", ".join(f"{1e3 * s:.3g} {u}" for s, u in zip(stroke, _units(reference), strict=True))
        + ")"
    )
    bad = {k: v for k, v in found.items() if v}
    if not bad:
        return Check("holds", True, f"{span}: every hold settles, pushes back, stays finite")
    parts = [f"{len(v)} {k} (first at {_vector(qs[v[0]], reference)})" for k, v in bad.items()]
    return Check("holds", False, f"{span}: " + ", ".join(parts))


def passivity_check(reference: BushingModel, stroke: np.ndarray) -> Check:
    """At ``PASSIVE_HOLDS`` and ``PASSIVE_HZ``, the loss matrix of the dynamic stiffness
    K(jw) positive semidefinite (``certify.passivity``): a reference that gives energy back on
    some small orbit is no bushing."""
    from bushenv.certify.passivity import passivity

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
        f"{span}: it gives energy back at the hold {_vector(rep.q[row], reference)}, {where} "
        "(least loss "
        f"eigenvalue {rep.min_eig:.4g} J)",
    )


def _units(model: BushingModel) -> tuple[str, ...]:
    """What a held vector is shown in: mm for a coordinate in m, mrad for one in rad."""
    return tuple("mrad" if u == "rad" else "mm" for u in model.units)


def _vector(q: np.ndarray, model: BushingModel) -> str:
    shown = zip(q, _units(model), strict=True)
    return "(" + ", ".join(f"{1e3 * v:+.3g} {u}" for v, u in shown) + ")"
