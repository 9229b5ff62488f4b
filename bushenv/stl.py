"""A small vectorised Signal Temporal Logic (STL) monitor over (T, B) arrays.

Robustness semantics (Donze & Maler 2010, discrete time): every operator maps robustness
signals of shape (T, B) -- one column per profile, one row per sample -- to a new robustness
signal of the same shape. Positive means satisfied, negative violated; the magnitude is how far
from the boundary. A formula's verdict for a whole trace is its robustness at t = 0.

| operator                  | robustness at t                                                  |
|---------------------------|------------------------------------------------------------------|
| ``predicate(g)``          | ``g(t)`` (write ``c - |F|`` for ``|F| <= c``)                    |
| ``neg(r)``                | ``-r(t)``                                                        |
| ``conj(r1, r2, ...)``     | ``min_i r_i(t)``                                                 |
| ``disj(r1, r2, ...)``     | ``max_i r_i(t)``                                                 |
| ``implies(a, b)``         | ``max(-a(t), b(t))``                                             |
| ``always(r, a, b)``       | ``min_{t' in [t+a, t+b]} r(t')``                                |
| ``eventually(r, a, b)``   | ``max_{t' in [t+a, t+b]} r(t')``                                |
| ``until(p, q, a, b)``     | ``max_{t' in [t+a,t+b]} min(q(t'), min_{t'' in [t,t']} p(t''))`` |

Windows are in samples; ``b=None`` means "to the end of the trace". A finite trace ends: samples
past the end take the value ``pad``. ``always`` pads with +inf (nothing beyond the trace can
violate it) and ``eventually`` with -inf (nothing beyond the trace can satisfy it), unless told
otherwise. ``boolean(mask)`` lifts a True/False condition to +inf/-inf so it composes with
real-valued robustness (``implies(boolean(in_hold), r)`` checks ``r`` only inside holds).

Sliding minima and maxima use ``scipy.ndimage`` (O(T B) whatever the window), so a monitor over
a population of 256 profiles of 2,500 samples takes milliseconds.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import maximum_filter1d, minimum_filter1d

from bushenv.errors import BadInput


class STLError(BadInput):
    """A malformed formula argument (window bounds, shapes)."""


def _as2d(r: np.ndarray) -> np.ndarray:
    r = np.asarray(r, dtype=np.float64)
    if r.ndim == 1:
        r = r[:, None]
    if r.ndim != 2:
        raise STLError(f"robustness signals are (T,) or (T, B) arrays, got shape {r.shape}")
    return r


def predicate(g: np.ndarray) -> np.ndarray:
    """The robustness of ``g >= 0`` is ``g`` itself."""
    return _as2d(g)


def boolean(mask: np.ndarray) -> np.ndarray:
    """A crisp condition: +inf where True, -inf where False."""
    m = np.asarray(mask, dtype=bool)
    m = m[:, None] if m.ndim == 1 else m
    return np.where(m, np.inf, -np.inf)


def neg(r: np.ndarray) -> np.ndarray:
    return -_as2d(r)


def conj(*rs: np.ndarray) -> np.ndarray:
    if not rs:
        raise STLError("conj needs at least one operand")
    out = _as2d(rs[0]).copy()
    for r in rs[1:]:
        np.minimum(out, _as2d(r), out=out)
    return out


def disj(*rs: np.ndarray) -> np.ndarray:
    if not rs:
        raise STLError("disj needs at least one operand")
    out = _as2d(rs[0]).copy()
    for r in rs[1:]:
        np.maximum(out, _as2d(r), out=out)
    return out


def implies(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return disj(neg(a), b)


def _window(r: np.ndarray, a: int, b: int | None, pad: float, reduce: str) -> np.ndarray:
    r = _as2d(r)
    T = r.shape[0]
    if a < 0 or (b is not None and b < a):
        raise STLError(f"window [{a}, {b}] must satisfy 0 <= a <= b")
    # shift by a: s(t) = r(t + a), padded beyond the end
    if a:
        s = np.full_like(r, pad)
        if a < T:
            s[: T - a] = r[a:]
    else:
        s = r
    if b is None:  # to the end of the trace: reverse cumulative min/max
        acc = np.minimum.accumulate if reduce == "min" else np.maximum.accumulate
        out = acc(s[::-1], axis=0)[::-1]
        # the padded tail (if any) is part of the window
        if a:
            fn = np.minimum if reduce == "min" else np.maximum
            out = fn(out, pad)
        return np.ascontiguousarray(out)
    width = b - a + 1
    if width == 1:
        return np.array(s, copy=True)
    filt = minimum_filter1d if reduce == "min" else maximum_filter1d
    return filt(s, size=width, axis=0, origin=-(width // 2), mode="constant", cval=pad)


def always(r: np.ndarray, a: int = 0, b: int | None = None, pad: float = np.inf) -> np.ndarray:
    """G[a,b] r: the worst value in the window ahead."""
    return _window(r, int(a), None if b is None else int(b), pad, "min")


def eventually(r: np.ndarray, a: int = 0, b: int | None = None, pad: float = -np.inf) -> np.ndarray:
    """F[a,b] r: the best value in the window ahead."""
    return _window(r, int(a), None if b is None else int(b), pad, "max")


def until(
    p: np.ndarray, q: np.ndarray, a: int = 0, b: int | None = None, pad: float = -np.inf
) -> np.ndarray:
    """p U[a,b] q: q becomes true somewhere in the window and p holds from now until then.

    Computed by one pass over the window offsets (O(T B window)); fine for the short windows
    STL properties here use. ``b=None`` runs to the end of the trace.
    """
    p = _as2d(p)
    q = _as2d(q)
    if p.shape != q.shape:
        raise STLError(f"until: operands have shapes {p.shape} and {q.shape}")
    T = p.shape[0]
    a = int(a)
    b = T - 1 if b is None else int(b)
    if a < 0 or b < a:
        raise STLError(f"window [{a}, {b}] must satisfy 0 <= a <= b")
    run_min = np.full_like(p, np.inf)
    out = np.full_like(p, -np.inf)
    for k in range(0, b + 1):
        pk = np.full_like(p, pad)
        qk = np.full_like(q, pad)
        if k < T:
            pk[: T - k] = p[k:]
            qk[: T - k] = q[k:]
        np.minimum(run_min, pk, out=run_min)
        if k >= a:
            np.maximum(out, np.minimum(qk, run_min), out=out)
    return out


def at_start(r: np.ndarray) -> np.ndarray:
    """The verdict of a formula for each trace: its robustness at t = 0, shape (B,)."""
    return _as2d(r)[0].copy()
