"""Small synthetic bushing records for the diagnosis tests: a spring and damper plus one
registered effect, made by the effect's own forward form at its typical instance
(``Effect.forward``, ``Effect.example``), so every registered effect has records without an
entry here. Forms the candidates do not assume are the widened validation's
(``bushenv/diagnose/validation/truth_forms.py``)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
from scipy import signal

from bushenv.diagnose.candidates import get_effect
from bushenv.diagnose.effects.base import Scales, Signals

K = 380e3  # N/m
C = 4.4e3  # N s/m


@dataclass
class Rec:
    time: np.ndarray
    displacement: np.ndarray
    force: np.ndarray
    dt: float
    name: str = ""


def motion(
    seed: int,
    duration_s: float = 30.0,
    dt: float = 1 / 204.8,
    peak_m: float = 4e-3,
    steps: bool = True,
) -> np.ndarray:
    """Band-limited random motion (0.1-15 Hz) plus, optionally, two step-and-hold segments."""
    rng = np.random.default_rng(seed)
    n = int(round(duration_s / dt))
    w = rng.normal(size=n)
    b, a = signal.butter(2, [0.1 * 2 * dt, 15 * 2 * dt], btype="band")
    x = signal.lfilter(b, a, w)
    x *= peak_m / np.max(np.abs(x))
    # amplitude modulation so small and large amplitudes both occur
    x *= 0.3 + 0.7 * (0.5 + 0.5 * np.sin(2 * np.pi * np.arange(n) * dt / duration_s * 2))
    if steps:
        seg = min(int(round(3.0 / dt)), n // 6)
        ramp = int(round(0.05 / dt))
        for start, level in ((n // 3, 0.6 * peak_m), (2 * n // 3, -0.6 * peak_m)):
            prof = np.full(seg, level)
            prof[:ramp] = np.linspace(x[start - 1], level, ramp)
            prof[-ramp:] = np.linspace(level, x[start + seg], ramp)
            x[start : start + seg] = prof
    return x


@cache
def specimen_scales() -> Scales:
    """What the synthetic specimen's effects are sized by: one default motion's scales, the
    same for every record (one specimen, as on a test machine)."""
    return Scales.of([Signals(motion(0), 1 / 204.8)])


def force(x: np.ndarray, dt: float, effect: str = "none") -> np.ndarray:
    """Force (N) of the spring K, damper C and ``effect`` (a registered name) under ``x``."""
    s = Signals(x, dt)
    if effect == "none":
        return K * x + C * s.v
    eff = get_effect(effect)
    shape, w = eff.example(specimen_scales(), K)
    own = C * s.v if eff.replaces_spring else K * x + C * s.v
    return eff.forward(s, own, shape, w, specimen_scales())


def record(
    seed: int,
    effect: str = "none",
    noise: float = 0.005,
    dt: float = 1 / 204.8,
    duration_s: float = 30.0,
    steps: bool = True,
    name: str = "",
) -> Rec:
    x = motion(seed, duration_s, dt, steps=steps)
    f = force(x, dt, effect)
    rng = np.random.default_rng(seed + 1000)
    f = f + noise * np.std(f) * rng.normal(size=f.size)
    return Rec(np.arange(x.size) * dt, x, f, dt, name or f"rec{seed}")
