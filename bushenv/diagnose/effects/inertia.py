"""Inertia: a mass between the specimen and the load cell (the fixture)."""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.diagnose.effects.base import Effect, Scales, Signals

EXAMPLE_RESONANCE_HZ = 16.0


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

    def example(self, scales: Scales, k_n_per_m: float) -> tuple[Any, np.ndarray]:
        """A fixture that would resonate with the bushing's spring at 16 Hz."""
        return None, np.array([k_n_per_m / (2 * np.pi * EXAMPLE_RESONANCE_HZ) ** 2])

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        return {"mass_kg": float(w[0])}
