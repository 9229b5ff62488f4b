"""Linear (Kelvin-Voigt) identification: least squares of F on [x, v] (seed 000 §4.1), for a
bushing of any number of coordinates: k and c for one, the C x C matrices K and C for several
(each force row its own least squares on every coordinate's displacement and velocity)."""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from bushenv import excitation as ex
from bushenv.identify.data import IdentificationError, TrainingSet, check_record
from bushenv.identify.options import NoOptions
from bushenv.models.base import BushingModel, velocity_of
from bushenv.models.linear import LinearBushing
from bushenv.models.registry import MODELS
from bushenv.progress import ProgressSpec

__all__ = ["IdentificationError", "check_record", "fit_linear", "least_squares_kc"]


def least_squares_kc(x: np.ndarray, f: np.ndarray, v: np.ndarray) -> tuple[Any, Any]:
    """(k N/m, c N s/m) minimising sum (f - k x - c v)^2 (``np.linalg.lstsq``) for (N,)
    arrays; for (N, C) arrays the (C, C) matrices K, C minimising |f - K x - C v|^2 row by row,
    each column scaled to its largest value first (millimetres and radians differ by orders)."""
    if np.ndim(x) == 1:
        a = np.column_stack([x, v])
        (k, c), *_ = np.linalg.lstsq(a, f, rcond=None)
        return float(k), float(c)
    a = np.hstack([x, v])
    scale = np.maximum(np.abs(a).max(axis=0), 1e-300)
    coef, *_ = np.linalg.lstsq(a / scale, f, rcond=None)
    coef = (coef / scale[:, None]).T  # (C, 2 C): force row i = [K_i, C_i]
    n = x.shape[1]
    return coef[:, :n], coef[:, n:]


def fit_linear(
    data: TrainingSet,
    options: NoOptions | None = None,
    seed: int = 0,
    progress: ProgressSpec = False,
) -> BushingModel:
    """Least-squares Kelvin-Voigt model of every sample of ``data`` (exact: no seed, no
    options); each record's velocity is its own central difference. One coordinate: a
    ``LinearBushing``; the three in-plane ones: a ``PlanarLinear`` (3x3 K and C)."""
    x, f, v = data.concatenated()
    k, c = least_squares_kc(x, f, v)
    if data.n_coords == 1:
        line = f"linear: k = {k:.6g} N/m, c = {c:.6g} N s/m"
        model = LinearBushing(k_n_per_m=k, c_ns_per_m=c, dt=data.dt)
        model.training = {"k_n_per_m": k, "c_ns_per_m": c, "seconds": 0.0}
    else:
        cls = MODELS["linear"].model_class(data.n_coords)
        model = cls(k, c, dt=data.dt)
        diag = ", ".join(f"{n} {kk:.6g}" for n, kk in zip(model.coords, np.diag(k), strict=True))
        line = f"linear: K diagonal {diag} (SI)"
    if callable(progress):
        progress(line)
    elif progress:
        print(line, file=sys.stderr, flush=True)
    return model


CONTROL_RECORD_S = 40.0  # the papers' identification record length (seed 000 §4.1)


def fitted_linear(source, scales, displacements: list | None = None, seed: int = 0):
    """Least-squares Kelvin-Voigt fit of ``source``'s response, from rest, to
    ``displacements`` (the records the reference was identified on, so the control sees the
    same band), else to an n = 1 random record per coordinate (seeds ``seed``, ``seed`` + 1,
    ...) scaled to the bushing's stroke (the papers' n = 1 peak is 2 mm of a 12.5 mm stroke)
    and kept within its rate. ``scales``: one coordinate's ``BushingScales`` (``stroke_m``,
    ``velocity_m_per_s``), or limits per coordinate (``stroke``, ``rate``: sequences of C, as
    ``search.limits.CoordinateLimits``). A ``LinearBushing``, or the linear model over C."""
    dt, c = source.dt, source.n_coords
    if c == 1:
        stroke, rate = [scales.stroke_m], [scales.velocity_m_per_s]
    else:
        stroke, rate = list(scales.stroke), list(scales.rate)
    if not displacements:
        cols = []
        for i in range(c):
            x = ex.random_rpc(1.0, CONTROL_RECORD_S, dt, seed + i)
            x = x * (stroke[i] / ex.MAX_DISPLACEMENT_M)
            speed = np.max(np.abs(np.diff(x))) / dt
            if speed > rate[i]:
                x = x * (rate[i] / speed)
            cols.append(x)
        displacements = [cols[0] if c == 1 else np.stack(cols, axis=1)]
    xs, vs, fs = [], [], []
    for x in displacements:
        x = np.asarray(x, dtype=np.float64)
        v = velocity_of(x, dt)
        xs.append(x)
        vs.append(v)
        fs.append(source.copy().simulate(x, v))
    k, damping = least_squares_kc(np.concatenate(xs), np.concatenate(fs), np.concatenate(vs))
    if c == 1:
        return LinearBushing(k_n_per_m=k, c_ns_per_m=damping, dt=dt)
    return MODELS["linear"].model_class(c)(k, damping, dt=dt)
