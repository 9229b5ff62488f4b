"""A reference for single precision: the NARX recurrence in numpy, in any dtype.

``NarxBushing.simulate(..., dtype="float32")`` runs the compiled kernels in float32 with their
own float32 tanh. This module is the yardstick for it: ``narx_free_run_numpy`` is the kernels'
recurrence written in numpy with every array and constant in ``dtype`` and libm's np.tanh, and
``float32_error`` is the largest |F32 - F64| over the largest |F64| of a batch. In float64 it
agrees with the compiled model to rounding (tests/models/test_precision.py), so its float32
error is what precision alone costs; the kernels' float32 error beyond it is their tanh's.
Slow (a numpy call per step): for measuring, not for running; scripts/bench.py's float32 figure
uses it too.
"""

from __future__ import annotations

import numpy as np

from bushenv.models.narx import NarxBushing


def narx_free_run_numpy(model: NarxBushing, x: np.ndarray, v: np.ndarray, dtype) -> np.ndarray:
    """Free run from rest of a NARX (or hybrid) model over x, v of shape (T, B), in ``dtype``."""
    dt_ = np.dtype(dtype)
    x = np.asarray(x, dtype=dt_)
    v = np.asarray(v, dtype=dt_)
    if x.ndim != 2 or x.shape != v.shape:
        raise ValueError(f"x and v must be (T, B) arrays of one shape, got {x.shape}, {v.shape}")
    T, B = x.shape
    nx, nf = model.n_past_x, model.n_past_f
    c = {k: dt_.type(getattr(model, k)) for k in ("x_offset_m", "x_scale_m")}
    f_off, f_sc = dt_.type(model.f_offset_n), dt_.type(model.f_scale_n)
    k_lin, c_lin = (dt_.type(a) for a in model._backbone())
    w1, b1 = model.w1.astype(dt_), model.b1.astype(dt_)[:, None]
    w2, b2 = model.w2.astype(dt_), model.b2.astype(dt_)[:, None]
    w_out, b_out = model.w_out.astype(dt_), dt_.type(model.b_out)
    # Lags newest first, as the kernels feed them: x_{t-1} .. x_{t-nx}, y_{t-1} .. y_{t-nf}.
    xl = np.full((nx, B), (dt_.type(0) - c["x_offset_m"]) / c["x_scale_m"], dtype=dt_)
    yl = np.full((nf, B), (dt_.type(0) - f_off) / f_sc, dtype=dt_)
    out = np.empty((T, B), dtype=dt_)
    for t in range(T):
        xs = ((x[t] - c["x_offset_m"]) / c["x_scale_m"])[None, :]
        h = np.tanh(w1 @ np.concatenate([xs, xl, yl]) + b1)
        if w2.shape[0]:
            h = np.tanh(w2 @ h + b2)
        y = w_out @ h + b_out
        out[t] = k_lin * x[t] + c_lin * v[t] + (f_off + f_sc * y)
        xl = np.concatenate([xs, xl[:-1]])
        yl = np.concatenate([y[None, :], yl[:-1]])
    return out


def float32_error(model: NarxBushing, x: np.ndarray, v: np.ndarray) -> float:
    """max |F(float32) - F(float64)| / max |F(float64)| of a free run from rest over (T, B)."""
    f64 = narx_free_run_numpy(model, x, v, np.float64)
    f32 = narx_free_run_numpy(model, x, v, np.float32).astype(np.float64)
    return float(np.max(np.abs(f32 - f64)) / np.max(np.abs(f64)))
