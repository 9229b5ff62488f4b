"""What every excitation family is built from: the ``Family`` type (a unit-cube vector -> one
profile), its error, the limits a family keeps inside, and the small parameter maps families
share (``_lin``, ``_log``: u in [0, 1] onto a range; ``_n``, ``_hold``, ``_move``: samples, holds
and half-cosine moves). The families themselves: ``families_rig.py`` (the test rig, any number
of coordinates) and ``families.py`` (the registry, the road families).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bushenv import excitation as ex
from bushenv.errors import BadInput
from bushenv.models.base import PAPER_DT
from bushenv.scales import MACHINE, BushingScales

MAX_PROFILE_S = 12.0  # the papers' step is held 10 s; 12 s covers their 7.3 s departure
MIN_HOLD_S = 0.5
SPEED_MARGIN = 0.98  # stay 2 % inside the machine's velocity limit
VMAX = ex.MAX_VELOCITY_M_PER_S * SPEED_MARGIN  # the papers' machine; a bushing's own: _limits
ROAD_MAX_HEIGHT_M = 0.15  # QuarterCar-v0's max_road_height_m: kerbs, potholes, the papers' bumps
# QuarterCar-v0 lets the road move at most max_road_step_m = 0.05 m per 1/204.8 s step
# (10.24 m/s); road profiles stay 5 % inside that so the env can replay them.
ROAD_MAX_RATE_M_PER_S = 0.95 * 0.05 * 204.8


class FamilyError(BadInput):
    """Bad family name or parameter vector."""


def _lin(u: float, lo: float, hi: float) -> float:
    return lo + (hi - lo) * float(np.clip(u, 0.0, 1.0))


def _log(u: float, lo: float, hi: float) -> float:
    return float(math.exp(_lin(u, math.log(lo), math.log(hi))))


def _n(duration_s: float, dt: float) -> int:
    return max(0, int(round(duration_s / dt)))


def _hold(value: float, duration_s: float, dt: float) -> np.ndarray:
    return np.full(_n(duration_s, dt), float(value))


def _move(start_m: float, end_m: float, dt: float, speed: float) -> np.ndarray:
    """Half-cosine move from start (excluded) to end at mean ``speed`` (peak pi/2 times it)."""
    dist = abs(end_m - start_m)
    if dist == 0.0:
        return np.zeros(0)
    n = max(1, math.ceil(dist * math.pi / 2 / (speed * dt)))
    s = np.arange(1, n + 1) / n
    return start_m + (end_m - start_m) * 0.5 * (1.0 - np.cos(np.pi * s))


@dataclass(frozen=True)
class Family:
    """One excitation family: ``dim`` unit-cube coordinates -> a (T,) profile ((T, C) for a
    target over C coordinates)."""

    name: str
    dim: int
    target: str  # the TARGETS name: "rig" (bushing displacement, m), "rig3", "quartercar", ...
    build: Callable[[np.ndarray, float, float, BushingScales], tuple[np.ndarray, dict]]
    random: bool = True  # drawn by random search (not so the meta-family "any")
    finish: Callable[[np.ndarray, float, float, BushingScales], np.ndarray] | None = None

    def _check(self, u) -> np.ndarray:
        u = np.asarray(u, dtype=np.float64).reshape(-1)
        if u.shape != (self.dim,):
            raise FamilyError(f"family {self.name!r} takes {self.dim} parameters, got {u.shape}")
        if not np.all(np.isfinite(u)):
            raise FamilyError(f"family {self.name!r}: parameters hold NaN or inf: {u}")
        return np.clip(u, 0.0, 1.0)

    def profile(
        self,
        u,
        dt: float = PAPER_DT,
        max_s: float = MAX_PROFILE_S,
        limits: BushingScales = MACHINE,
    ) -> np.ndarray:
        """The (T,) profile for parameters ``u`` (clipped to [0, 1]) within ``limits`` (the
        bushing's stroke and velocity; default the papers' machine)."""
        x, _ = self.build(self._check(u), dt, max_s, limits)
        if self.finish is not None:
            return self.finish(x, dt, max_s, limits)
        return np.asarray(x, dtype=np.float64)[: _n(max_s, dt)]

    def describe(
        self,
        u,
        dt: float = PAPER_DT,
        max_s: float = MAX_PROFILE_S,
        limits: BushingScales = MACHINE,
    ) -> dict:
        """The physical parameters ``u`` maps to (plain JSON values)."""
        _, params = self.build(self._check(u), dt, max_s, limits)
        return {"family": self.name, **_plain(params)}


def _plain(v):
    if isinstance(v, dict):
        return {k: _plain(w) for k, w in v.items()}
    if isinstance(v, list | tuple):
        return [_plain(w) for w in v]
    if isinstance(v, np.generic):
        return v.item()
    return v
