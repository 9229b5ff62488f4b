"""Inertia: a mass between the specimen and the load cell (the fixture)."""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.diagnose.effects.base import Effect, Scales, Signals


class Inertia(Effect):
    """``m a``: the load cell also carries a fixture mass."""

    name = "inertia"
    form = "m a, a = d2x/dt2"
    weights = "m >= 0 (kg)"
    telling_test = (
        "a small-amplitude sweep to high frequency (a force growing with the square of "
        "frequency, in phase with the deflection)"
    )

    def columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        return s.a[:, None].copy()

    def columns_count(self, shape: Any, scales: Scales) -> int:
        return 1

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        return {"mass_kg": float(w[0])}
