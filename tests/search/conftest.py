"""Stand-in models for the search tests (the trained defaults may not be in the package).

``UnstableHoldBushing`` is deliberately bad in a known way, like the papers' NN on a held step
(seed 000 §5.2): a Kelvin-Voigt force plus an internal mode that, once the deflection has stayed
beyond ``trigger_m`` for ``delay_s``, grows by ``growth`` per sample. Below the trigger it is
exactly the linear model, so every criterion's verdict on it is predictable.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bushenv.models.base import PAPER_DT, BushingModel
from bushenv.models.hybrid import HybridBushing
from bushenv.models.linear import LinearBushing
from bushenv.models.narx import NarxBushing
from bushenv.reference.rubber import RubberBushing

OLD_MODELS = Path(__file__).resolve().parents[1] / "regressions" / "models"


def old_nn(axis: str) -> str:
    """The NN shipped before certified training, kept with the corpus cases found on it: a
    network with known energy failures, whatever the shipped models are today."""
    return str(OLD_MODELS / f"{axis}_nn-6f15bf3.npz")


class UnstableHoldBushing(BushingModel):
    name = ""  # test-only, not registered
    param_names = ("k_n_per_m", "c_ns_per_m", "trigger_m", "delay_s", "growth")

    def __init__(
        self,
        k_n_per_m=379.68e3,
        c_ns_per_m=4.4e3,
        trigger_m=3e-3,
        delay_s=2.0,
        growth=1.02,
        dt=PAPER_DT,
    ):
        self.k_n_per_m, self.c_ns_per_m = float(k_n_per_m), float(c_ns_per_m)
        self.trigger_m, self.delay_s, self.growth = float(trigger_m), float(delay_s), float(growth)
        super().__init__(dt)

    @property
    def n_state(self):
        return 2  # samples spent beyond the trigger, internal mode

    def _advance(self, x, v, out):
        n_delay = self.delay_s / self.dt
        for t in range(x.shape[0]):
            beyond = np.abs(x[t]) > self.trigger_m
            self.state[0] = np.where(beyond, self.state[0] + 1, 0.0)
            live = self.state[0] > n_delay
            self.state[1] = np.where(live, self.state[1] * self.growth + 1.0, 0.0)
            out[t] = self.k_n_per_m * x[t] + self.c_ns_per_m * v[t] + self.state[1]


@pytest.fixture(scope="session")
def reference_axial():
    return RubberBushing.preset("axial", measurement=False)


@pytest.fixture(scope="session")
def linear_axial():
    return LinearBushing.preset("axial")


@pytest.fixture()
def unstable_model():
    return UnstableHoldBushing()


def bad_narx(seed: int = 3) -> NarxBushing:
    """A NARX net with random weights: wanders off on many profiles (a stand-in 'nn')."""
    return NarxBushing.initialised((-4e-3, 4e-3), (-2000.0, 2000.0), seed=seed)


def tame_hybrid(seed: int = 3) -> HybridBushing:
    """Table 1 backbone + a small random network (|F_nn| <= 40 N): a stand-in 'hybrid'."""
    net = NarxBushing.initialised((-4e-3, 4e-3), (-20.0, 20.0), seed=seed)
    params = {k: getattr(net, k) for k in NarxBushing.param_names}
    return HybridBushing(k_n_per_m=379.68e3, c_ns_per_m=4.4e3, **params)
