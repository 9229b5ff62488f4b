"""The error every vehicle-input generator raises, and the argument checks they share."""

from __future__ import annotations

import math

import numpy as np

from bushenv.errors import BadInput
from bushenv.excitation import n_samples


class VehicleInputError(BadInput):
    """A vehicle-input argument is invalid; the message names the argument and its value."""


def positive(name: str, value: float) -> float:
    """``value`` as a float if finite and > 0, else a ``VehicleInputError`` naming it."""
    if not (isinstance(value, int | float | np.floating | np.integer) and math.isfinite(value)):
        raise VehicleInputError(f"{name} must be a finite number > 0, got {value!r}")
    if value <= 0:
        raise VehicleInputError(f"{name} must be > 0, got {value!r}")
    return float(value)


def nonnegative(name: str, value: float) -> float:
    """``value`` as a float if finite and >= 0, else a ``VehicleInputError`` naming it."""
    if not (isinstance(value, int | float | np.floating | np.integer) and math.isfinite(value)):
        raise VehicleInputError(f"{name} must be a finite number >= 0, got {value!r}")
    if value < 0:
        raise VehicleInputError(f"{name} must be >= 0, got {value!r}")
    return float(value)


def finite(name: str, value: float) -> float:
    """``value`` as a float if finite, else a ``VehicleInputError`` naming it."""
    if not (isinstance(value, int | float | np.floating | np.integer) and math.isfinite(value)):
        raise VehicleInputError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def sample_count(duration_s: float, dt_s: float) -> int:
    """T = round(duration_s / dt_s) samples (``bushenv.excitation.n_samples``), at least 2."""
    positive("dt_s", dt_s)
    positive("duration_s", duration_s)
    count = n_samples(duration_s, dt_s)
    if count < 2:
        raise VehicleInputError(
            f"duration_s={duration_s!r} at dt_s={dt_s!r} gives {count} sample(s); at least 2"
        )
    return count


def signal_1d(name: str, values: np.ndarray) -> np.ndarray:
    """``values`` as a finite float (T,) array with T >= 2, else an error naming it."""
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1 or arr.size < 2:
        raise VehicleInputError(f"{name} must be a (T,) array with T >= 2, got shape {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise VehicleInputError(f"{name}[{bad[0]}] is {arr[bad[0]]!r}: every sample must be finite")
    return arr
