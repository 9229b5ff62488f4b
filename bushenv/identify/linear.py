"""Linear (Kelvin-Voigt) identification: least squares of F on [x, v] (seed 000 §4.1)."""

from __future__ import annotations

import sys

import numpy as np

from bushenv.identify.data import IdentificationError, TrainingSet, check_record
from bushenv.identify.options import NoOptions
from bushenv.models.linear import LinearBushing
from bushenv.progress import ProgressSpec

__all__ = ["IdentificationError", "check_record", "fit_linear", "least_squares_kc"]


def least_squares_kc(x: np.ndarray, f: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """(k N/m, c N s/m) minimising sum (f - k x - c v)^2 (``np.linalg.lstsq``)."""
    a = np.column_stack([x, v])
    (k, c), *_ = np.linalg.lstsq(a, f, rcond=None)
    return float(k), float(c)


def fit_linear(
    data: TrainingSet,
    options: NoOptions | None = None,
    seed: int = 0,
    progress: ProgressSpec = False,
) -> LinearBushing:
    """Least-squares Kelvin-Voigt model of every sample of ``data`` (exact: no seed, no
    options); each record's velocity is its own central difference."""
    x, f, v = data.concatenated()
    k, c = least_squares_kc(x, f, v)
    line = f"linear: k = {k:.6g} N/m, c = {c:.6g} N s/m"
    if callable(progress):
        progress(line)
    elif progress:
        print(line, file=sys.stderr, flush=True)
    model = LinearBushing(k_n_per_m=k, c_ns_per_m=c, dt=data.dt)
    model.training = {"k_n_per_m": k, "c_ns_per_m": c, "seconds": 0.0}
    return model
