"""Delay: the force channel lags the displacement channel."""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.diagnose.effects.base import Effect, Scales, Signals
from bushenv.diagnose.effects.timeshift import shift_columns

DELAY_GRID_S = tuple(float(d) for d in 1e-3 * np.geomspace(0.25, 40.0, 25))
RICH_DELAY_GRID_S = tuple(float(d) for d in 1e-3 * np.geomspace(0.1, 60.0, 48))
# The richest form spreads the lag: the spring's and the damper's force also at these shares of
# d before and after it (a causal lag kernel on [0, 2 d] of mean d, non-negative weights).
SPREAD_SHARES = (-1.0, -0.5, 0.5, 1.0)
EXAMPLE_DELAY_S = 6e-3  # between grid values: the shape search must refine it


class Delay(Effect):
    """The whole predicted force at ``t - d`` (a fractional shift, cubic interpolation)."""

    name = "delay"
    form = "the whole predicted force at t - d"
    weights = "none"
    telling_test = (
        "a broadband random or a sweep to the highest frequency the machine drives (a "
        "phase lag growing linearly with frequency at unchanged gain)"
    )
    shape_text = "d on 25 values 0.25..40 ms, refined by a bounded 1-D search"
    continuous_shape = True

    def shapes(self, scales: Scales) -> list:
        return list(DELAY_GRID_S)

    def rich_shapes(self, scales: Scales) -> list:
        return list(RICH_DELAY_GRID_S)

    def columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        return np.zeros((s.x.size, 0))  # no weights: the shift is all of it

    def rich_columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        """A lag spread over [0, 2 d]: the spring's and the damper's force also shifted by
        each of ``SPREAD_SHARES`` x d around the delay, weights >= 0. A measurement chain lags
        through a filter (an average, an anti-alias stage), which lowers the gain as the lag
        spreads (by ``w^2 var / 2``, as a mass would); a pure shift is only its narrowest case."""
        xv = np.stack([s.x, s.v], axis=1)
        return np.concatenate([shift_columns(xv, q * shape, s.dt) for q in SPREAD_SHARES], axis=1)

    def example(self, scales: Scales, k_n_per_m: float) -> tuple[Any, np.ndarray]:
        return EXAMPLE_DELAY_S, np.zeros(0)

    def delay_s(self, shape: Any) -> float:
        return float(shape or 0.0)

    def describe(self, shape: Any) -> str:
        return f"delay (d={1e3 * shape:.3g} ms)"

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        return {"delay_s": float(shape)}
