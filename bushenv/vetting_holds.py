"""The holds a reference of any number of coordinates C is vetted on (``hold_check``: each
coordinate alone at the ``HOLDS`` levels of its stroke, and for C > 1 the corners of the stroke
box), its own certificate's holds (``certificate_check``, NARX references) and the passivity of
its dynamic stiffness (``passivity_check``); ``bushenv.vetting`` states the checks."""

from __future__ import annotations

import numpy as np

from bushenv.certify.reached_holds import (
    HOLD_S,
    boxes_of,
    confirm_holds,
    failing_holds,
    hold_entries,
    judge_holds,
    ranges_of,
    ring_threshold,
)
from bushenv.models import BushingModel
from bushenv.vetting_check import CERTIFICATE_HOLDS, HOLDS, RAMP_S, SIGN_FRACTION, Check

CORNER = 0.6  # the corners of the stroke box held, as a fraction of the stroke
PASSIVE_PRELOAD = 0.3  # the passivity's holds: at rest, and this fraction along each coordinate
PASSIVE_HZ = np.geomspace(0.2, 40.0, 12)
KINDS = ("not finite", "oscillating", "departing", "wrong sign")
SHOWN = 3  # confirmed held vectors named in a detail


def held_vectors(stroke) -> np.ndarray:
    """(H, C) held deflections: each coordinate alone at ``HOLDS`` levels over -stroke..+stroke
    (the rest held once), and for C > 1 the 2^C corners of ``CORNER`` x the stroke box
    (coupling shows where coordinates combine). One coordinate: the ``HOLDS`` levels."""
    stroke = np.atleast_1d(np.asarray(stroke, dtype=np.float64))
    c = stroke.size
    alone = [
        np.eye(c)[i] * x
        for i, s in enumerate(stroke)
        for x in np.linspace(-s, s, HOLDS)
        if i == 0 or x != 0.0
    ]
    corners = []
    if c > 1:
        signs = np.array(np.meshgrid(*[(-1, 1)] * c, indexing="ij")).reshape(c, -1).T
        corners = [s * CORNER * stroke for s in signs]
    return np.array(alone + corners) + 0.0  # no -0 shown


def hold_check(reference: BushingModel, stroke, floors) -> tuple[Check, np.ndarray]:
    """Check 1 of ``bushenv.vetting``, and the thresholds (C,) it judged with (the certificate
    check uses them too): per coordinate ``ring_threshold`` of the reference's own forces in
    these holds, at most that coordinate's force floor in ``floors``."""
    dt, c = reference.dt, reference.n_coords
    stroke = np.broadcast_to(np.asarray(stroke, dtype=np.float64), (c,))
    floors = np.broadcast_to(np.asarray(floors, dtype=np.float64), (c,))
    qs = held_vectors(stroke)
    n_ramp, n_hold = max(2, int(round(RAMP_S / dt))), int(round(HOLD_S / dt))
    ramp = np.linspace(0.0, 1.0, n_ramp)[:, None, None] * qs[None]
    q = np.concatenate([ramp, np.repeat(qs[None], n_hold, axis=0)])  # (T, H, C)
    try:
        f = reference.copy().simulate(q[..., 0] if c == 1 else q)
    except Exception as exc:  # a reference that cannot even run its holds
        text = f"the reference raised {type(exc).__name__}: {exc}"
        return Check("holds", False, text), floors.copy()
    f = f.reshape(q.shape)
    ths = [ring_threshold(f[:, :, i], dt) for i in range(c)]
    limits = np.minimum([t.force_n for t in ths], floors)
    flags = judge_holds(f, qs, n_hold, limits, dt)
    flags["wrong sign"] &= np.max(np.abs(qs) / stroke, axis=1) >= SIGN_FRACTION
    bad = {k: np.flatnonzero(flags[k]) for k in KINDS if flags[k].any()}
    span, how = _span(reference, qs, stroke), _how(reference, ths, limits)
    if not bad:
        return Check("holds", True, f"{span}: every hold settles, pushes back, stays finite "
                     f"({how})"), limits  # fmt: skip
    if c > 1:
        parts = [f"{len(v)} {k} (first at {_vector(qs[v[0]], reference)})" for k, v in bad.items()]
        flagged = qs[np.unique(np.concatenate(list(bad.values())))]
        boxes = tuple(boxes_of(flagged, 2 * stroke / (HOLDS - 1)))
        text = f"{span}: " + ", ".join(parts) + f" ({how})"
        return Check("holds", False, text, boxes=boxes), limits
    xs = qs[:, 0]
    parts = [
        f"{len(v)} {k} between {xs[v].min() * 1e3:+.3g} and {xs[v].max() * 1e3:+.3g} mm"
        for k, v in bad.items()
    ]
    where = ranges_of([float(xs[i]) for v in bad.values() for i in v], xs[1] - xs[0])
    return Check("holds", False, f"{span}: " + ", ".join(parts) + f" ({how})", tuple(where)), limits


def _span(reference: BushingModel, qs: np.ndarray, stroke: np.ndarray) -> str:
    if reference.n_coords == 1:
        return f"{len(qs)} holds of {HOLD_S:g} s over +-{stroke[0] * 1e3:.3g} mm"
    shown = ", ".join(f"{1e3 * s:.3g} {u}" for s, u in zip(stroke, _units(reference), strict=True))
    return f"{len(qs)} holds of {HOLD_S:g} s over +-({shown})"


def _how(reference: BushingModel, ths: list, limits: np.ndarray) -> str:
    """The thresholds and where they come from (capped: never coarser than the floor)."""
    if reference.n_coords == 1:
        how = ths[0].describe()
        if ths[0].force_n > limits[0]:
            how = f"threshold {limits[0]:.4g} N, the force floor, below the {how}"
        return how
    each = ", ".join(
        f"{name} {lim:.4g} {u}" + (" (its floor)" if t.force_n > lim else "")
        for name, lim, u, t in zip(
            reference.coords, limits, reference.force_units, ths, strict=True
        )
    )
    return (f"thresholds {each}: per coordinate the larger of 3 x its noise and 1% of its force "
            "scale in these holds, at most its force floor")  # fmt: skip


def certificate_check(
    reference: BushingModel, stroke, envelope: tuple, thresholds: np.ndarray
) -> Check | None:
    """Check 2 of ``bushenv.vetting``; None for a reference that is not a NARX network.
    ``envelope``: the largest |q| and |dq/dt| the reaching stays within (each a number or
    (C,)); ``thresholds`` (C,): check 1's, per coordinate."""
    from bushenv.certify.network import CertifyError

    c = reference.n_coords
    stroke = np.broadcast_to(np.asarray(stroke, dtype=np.float64), (c,))
    try:
        if c == 1:
            entries = hold_entries(reference, None, float(stroke[0]), CERTIFICATE_HOLDS)
        else:
            entries = hold_entries(reference, None, q=held_vectors(stroke))
    except CertifyError:
        return None
    listed = failing_holds(entries)
    if c == 1:
        return _confirmed(reference, listed, float(stroke[0]), envelope, float(thresholds[0]))
    return _confirmed_vectors(reference, listed, len(entries), stroke, envelope, thresholds)


def _confirmed_vectors(reference, listed, n_held, stroke, envelope, thresholds) -> Check:
    """The certificate check over C > 1: its listed held vectors reached as a search would."""
    span = f"its certificate, over the {n_held} held vectors of the holds check,"
    if not listed:
        return Check("certificate holds", True, f"{span} lists none oscillating, "
                     "departing or wrong-sign")  # fmt: skip
    c = reference.n_coords
    env = [np.broadcast_to(np.asarray(e, dtype=np.float64), (c,)) for e in envelope]
    kinds = sorted({k for h in listed for k in h["kinds"]})
    said = (
        f"{span} lists {len(listed)} ({', '.join(kinds)}), first at "
        f"{_vector(np.asarray(listed[0]['q']), reference)}"
    )
    confirmed, n = confirm_holds(reference, listed, env, thresholds)
    rates = zip(env[1], reference.units, strict=True)
    reach = (
        f"{n} profiles reaching them after a step or sines along each coordinate and along "
        f"each hold's direction inside its envelope (|q| <= {_vector(env[0], reference, '')}, "
        f"|dq/dt| <= ({', '.join(f'{v:.3g} {u}/s' for v, u in rates)})); "
        + _thresholds(reference, thresholds)
    )
    if not confirmed:
        return Check("certificate holds", True, f"{said}; none confirmed by {reach}")
    found = sorted({k for h in confirmed for k in h.kinds})
    names = [reference.coords[i] for i in sorted({i for h in confirmed for i in h.coords})]
    shown = "; ".join(
        f"{_vector(np.asarray(h.q), reference)} {'/'.join(h.kinds)} on "
        f"{', '.join(reference.coords[i] for i in h.coords)}"
        for h in confirmed[:SHOWN]
    )
    more = f"; and {len(confirmed) - SHOWN} more" if len(confirmed) > SHOWN else ""
    overall = f" ({', '.join(found)}; on {', '.join(names)})" if more else ""
    text = f"{said}; {len(confirmed)} confirmed{overall}: {shown}{more}; by {reach}"
    ringing = [h for h in confirmed if set(h.kinds) & {"oscillating", "not finite"}]
    if ringing:  # a ripple says something of a ring only
        worst = max(ringing, key=lambda h: h.ripple_n)
        w, at = worst.worst_coord, _vector(np.asarray(worst.q), reference)
        text += (
            f"; worst {worst.ripple_n:.4g} {reference.force_units[w]} p-p on "
            f"{reference.coords[w]} at {at} after {worst.after}"
        )
    else:
        text += f"; first after {confirmed[0].after}"
    # the chains of listed vectors holding a confirmed one (not every listed hold is simulated)
    step = 2 * stroke / (HOLDS - 1)
    qs = np.array([h["q"] for h in listed], dtype=np.float64)
    boxes = [b for b in boxes_of(qs, step) if any(_inside(h.q, b) for h in confirmed)]
    return Check("certificate holds", False, text, boxes=tuple(boxes))


def _inside(q, box) -> bool:
    return all(a <= v <= b for v, (a, b) in zip(q, box, strict=True))


def _thresholds(reference: BushingModel, thresholds) -> str:
    each = zip(reference.coords, thresholds, reference.force_units, strict=True)
    return "thresholds " + ", ".join(f"{n} {t:.4g} {u}" for n, t, u in each) + " (check 1's)"


def _confirmed(reference, listed, stroke_m, envelope, threshold) -> Check:
    """The one-coordinate certificate check: its listed holds reached as a search would."""
    span = f"its certificate, {CERTIFICATE_HOLDS} holds over +-{stroke_m * 1e3:.3g} mm,"
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
    step = 2 * stroke_m / (CERTIFICATE_HOLDS - 1)
    runs = [(a, b) for a, b in ranges_of(xl, step) if any(a <= x <= b for x in xc)]
    return Check("certificate holds", False, text, tuple(runs))


def passivity_check(reference: BushingModel, stroke) -> Check:
    """At rest and at ``PASSIVE_PRELOAD`` of the stroke along each coordinate, over
    ``PASSIVE_HZ``, the loss matrix of the dynamic stiffness K(jw) positive semidefinite
    (``certify.passivity``; one coordinate: Im K >= 0): a reference that gives energy back on
    some small orbit is no bushing."""
    from bushenv.certify.passivity import passivity

    c = reference.n_coords
    stroke = np.broadcast_to(np.asarray(stroke, dtype=np.float64), (c,))
    q0 = np.vstack([np.zeros(c), PASSIVE_PRELOAD * np.diag(stroke)])
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
        f"(least loss eigenvalue {rep.min_eig:.4g} J)",
    )


def _units(model: BushingModel) -> tuple[str, ...]:
    """What a held vector is shown in: mm for a coordinate in m, mrad for one in rad."""
    return tuple("mrad" if u == "rad" else "mm" for u in model.units)


def _vector(q: np.ndarray, model: BushingModel, sign: str = "+") -> str:
    shown = zip(np.atleast_1d(q), _units(model), strict=True)
    return "(" + ", ".join(f"{1e3 * v:{sign}.3g} {u}" for v, u in shown) + ")"
