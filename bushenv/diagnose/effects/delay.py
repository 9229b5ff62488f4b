"""Delay: the force channel lags the displacement channel."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import ndimage

from bushenv.diagnose.effects.base import Effect, Scales

DELAY_GRID_S = tuple(float(d) for d in 1e-3 * np.geomspace(0.25, 40.0, 25))


def shift_columns(cols: np.ndarray, delay_s: float, dt: float) -> np.ndarray:
    """cols(t - delay) by cubic-spline interpolation; the first value holds before t = 0."""
    if delay_s == 0.0:
        return cols
    n = delay_s / dt
    shift = (n,) + (0,) * (cols.ndim - 1)
    return ndimage.shift(cols, shift, order=3, mode="nearest")


class Delay(Effect):
    """The whole predicted force at ``t - d`` (a fractional shift by cubic splines)."""

    name = "delay"
    form = "the whole predicted force at t - d"
    weights = "none"
    shape_text = "d on 25 values 0.25..40 ms, refined by a bounded 1-D search"
    continuous_shape = True

    def shapes(self, scales: Scales) -> list:
        return list(DELAY_GRID_S)

    def delay_s(self, shape: Any) -> float:
        return float(shape or 0.0)

    def describe(self, shape: Any) -> str:
        return f"delay (d={1e3 * shape:.3g} ms)"

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        return {"delay_s": float(shape)}
