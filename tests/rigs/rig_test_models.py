"""Helper models and names for the rig tests (imported by the test modules)."""

from __future__ import annotations

import numpy as np
import pytest

from bushenv.errors import ModelRefused
from bushenv.models import PAPER_DT, BushingModel, default_model_path

ALL_MODELS = ("linear", "nn", "hybrid", "boucwen", "rubber")
TRAINED = ("nn", "hybrid", "boucwen")


def model_or_skip(name: str, axis: str = "axial") -> str:
    """``name`` if its default model exists in this checkout, else skip the test saying why."""
    if name in TRAINED and not default_model_path(name, axis).is_file():
        pytest.skip(
            f"no default {name!r} model file {default_model_path(name, axis)} yet "
            "(scripts/train_default_models.py writes it)"
        )
    return name


class NanAfter(BushingModel):
    """Test double: a spring k x that returns NaN from sample ``after`` on."""

    name = "nan_after_test_double"
    param_names = ()

    def __init__(self, after: int = 5, k: float = 1.0e5, dt: float = PAPER_DT) -> None:
        self.after, self.k = int(after), float(k)
        super().__init__(dt)

    @property
    def n_state(self) -> int:
        return 1

    def _advance(self, x, v, out):
        for t in range(x.shape[0]):
            self.state[0] += 1
            out[t] = np.where(self.state[0] > self.after, np.nan, self.k * x[t])

    def copy(self):
        return NanAfter(self.after, self.k, self.dt)

    def reset_columns(self, mask):  # its sample counter is per history
        self.state[:, mask] = 0.0


class NanAfter3(NanAfter):
    """``NanAfter`` over three coordinates (axial, radial, rotation): k q per coordinate."""

    name = "nan_after_3_test_double"
    coords = ("axial", "radial", "rotation")
    units = ("m", "m", "rad")
    force_units = ("N", "N", "N m")

    def _advance(self, x, v, out):
        for t in range(x.shape[0]):
            self.state[0] += 1
            out[t] = np.where(self.state[0][:, None] > self.after, np.nan, self.k * x[t])

    def copy(self):
        return NanAfter3(self.after, self.k, self.dt)


class RaisesAfter(NanAfter):
    name = "raises_after_test_double"

    def _advance(self, x, v, out):
        super()._advance(x, v, out)
        if not np.isfinite(out).all():
            raise ModelRefused("test double gave up")  # its own state ran away: a divergence

    def copy(self):
        return RaisesAfter(self.after, self.k, self.dt)


class Buggy(BushingModel):
    """A model whose force has a bug after ``after`` steps (a numpy shape error): an error of
    the model's own, never a divergence."""

    name = "buggy_test_double"
    param_names = ()

    def __init__(self, after: int = 3, dt: float = PAPER_DT) -> None:
        self.after = int(after)
        super().__init__(dt)

    @property
    def n_state(self) -> int:
        return 1

    def _advance(self, x, v, out):
        for t in range(x.shape[0]):
            self.state[0] += 1
            if self.state[0, 0] > self.after:
                np.ones(3) + np.ones(4)  # ValueError: operands could not be broadcast together
            out[t] = 1e5 * x[t]

    def copy(self):
        return Buggy(self.after, self.dt)


class DiffKV(BushingModel):
    """Kelvin-Voigt with its velocity from the displacement history, k x_k + c (x_k - x_k-1)/dt,
    ignoring the v input (as a NARX network does)."""

    name = "diffkv_test_double"
    param_names = ()

    def __init__(self, k: float, c: float, dt: float = PAPER_DT) -> None:
        self.k, self.c = float(k), float(c)
        super().__init__(dt)

    @property
    def n_state(self) -> int:
        return 1

    def _advance(self, x, v, out):
        for t in range(x.shape[0]):
            out[t] = self.k * x[t] + self.c * (x[t] - self.state[0]) / self.dt
            self.state[0] = x[t]

    def copy(self):
        return DiffKV(self.k, self.c, self.dt)


class ValueAfter(NanAfter):
    """Test double: a spring k x until sample ``after``, then ``value`` N -- or, with ``error``
    (an exception instance), raises it instead of returning anything."""

    name = "value_after_test_double"

    def __init__(self, after=5, value=np.nan, error=None, k=1.0e5, dt=PAPER_DT) -> None:
        self.value, self.error = float(value), error
        super().__init__(after, k, dt)

    def _advance(self, x, v, out):
        for t in range(x.shape[0]):
            self.state[0] += 1
            late = self.state[0] > self.after
            if late.any() and self.error is not None:
                raise self.error
            out[t] = np.where(late, self.value, self.k * x[t])

    def copy(self):
        return ValueAfter(self.after, self.value, self.error, self.k, self.dt)
