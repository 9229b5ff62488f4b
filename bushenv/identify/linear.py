"""Linear (Kelvin-Voigt) identification: least squares of F on [x, v] (seed 000 §4.1)."""

from __future__ import annotations

import sys

import numpy as np

from bushenv import excitation as ex
from bushenv.identify.data import IdentificationError, TrainingSet, check_record
from bushenv.identify.options import NoOptions
from bushenv.models.base import velocity_of
from bushenv.models.linear import LinearBushing
from bushenv.progress import ProgressSpec
from bushenv.scales import BushingScales

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


CONTROL_RECORD_S = 40.0  # the papers' identification record length (seed 000 §4.1)


def fitted_linear(
    source, scales: BushingScales, displacements: list | None = None, seed: int = 0
) -> LinearBushing:
    """Least-squares Kelvin-Voigt fit of ``source``'s response, from rest, to
    ``displacements`` (the records the reference was identified on, so the control sees the
    same band), else to an n = 1 random record scaled to the bushing's stroke (the papers'
    n = 1 peak is 2 mm of a 12.5 mm stroke)."""
    dt = source.dt
    if not displacements:
        x = ex.random_rpc(1.0, CONTROL_RECORD_S, dt, seed)
        x = x * (scales.stroke_m / ex.MAX_DISPLACEMENT_M)
        speed = np.max(np.abs(np.diff(x))) / dt
        if speed > scales.velocity_m_per_s:
            x = x * (scales.velocity_m_per_s / speed)
        displacements = [x]
    xs, vs, fs = [], [], []
    for x in displacements:
        v = velocity_of(np.asarray(x, dtype=np.float64), dt)
        xs.append(x)
        vs.append(v)
        fs.append(source.copy().simulate(x, v))
    k, c = least_squares_kc(np.concatenate(xs), np.concatenate(fs), np.concatenate(vs))
    return LinearBushing(k_n_per_m=k, c_ns_per_m=c, dt=dt)
