"""Linear (Kelvin-Voigt) identification: least squares of F on [x, v] (seed 000 §4.1)."""

from __future__ import annotations

import numpy as np

from bushenv.models.base import PAPER_DT, velocity_of
from bushenv.models.linear import LinearBushing


class IdentificationError(ValueError):
    """Identification data or options are unusable; the message names the argument."""


def check_record(x, f, dt: float, v=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate a (T,) displacement/force record; return float64 x, f and v (central diff.)."""
    x = np.asarray(x, dtype=np.float64)
    f = np.asarray(f, dtype=np.float64)
    if x.ndim != 1 or f.shape != x.shape:
        raise IdentificationError(
            f"x and f must be 1-D of equal length, got shapes {x.shape} and {f.shape}"
        )
    if x.size < 10:
        raise IdentificationError(f"record too short: {x.size} samples")
    if not (np.isfinite(dt) and dt > 0):
        raise IdentificationError(f"dt must be a positive number of seconds, got {dt!r}")
    for name, a in (("x", x), ("f", f)):
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            raise IdentificationError(f"{name}[{bad[0]}] is {a[bad[0]]}: record holds NaN/inf")
    if v is None:
        v = velocity_of(x, dt)
    else:
        v = np.asarray(v, dtype=np.float64)
        if v.shape != x.shape or not np.all(np.isfinite(v)):
            raise IdentificationError(f"v must be finite with shape {x.shape}, got {v.shape}")
    if np.ptp(x) == 0:
        raise IdentificationError("x is constant: nothing to identify")
    return x, f, v


def least_squares_kc(x: np.ndarray, f: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """(k N/m, c N s/m) minimising sum (f - k x - c v)^2 (``np.linalg.lstsq``)."""
    a = np.column_stack([x, v])
    (k, c), *_ = np.linalg.lstsq(a, f, rcond=None)
    return float(k), float(c)


def fit_linear(
    x, f, dt: float = PAPER_DT, v=None, seed: int = 0, progress: bool = False
) -> LinearBushing:
    """Least-squares Kelvin-Voigt model of a record (``seed``/``progress`` unused: exact)."""
    x, f, v = check_record(x, f, dt, v)
    k, c = least_squares_kc(x, f, v)
    if progress:
        print(f"linear: k = {k:.6g} N/m, c = {c:.6g} N s/m", flush=True)
    return LinearBushing(k_n_per_m=k, c_ns_per_m=c, dt=dt)
