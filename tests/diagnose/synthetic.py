"""Small synthetic bushing records for the diagnosis tests (own forms, independent of the
candidates' generic forms where possible: an elasto-plastic Jenkins friction element, Maxwell
branches off the candidates' tau grid, a stiffness that softens with dissipated energy)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

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


def force(x: np.ndarray, dt: float, effect: str = "none", strength: float = 1.0) -> np.ndarray:
    v = np.gradient(x, dt)
    f = K * x + C * v
    if effect == "relaxation":
        for k, tau in ((0.5 * K, 0.07), (0.3 * K, 1.3)):
            a = np.exp(-dt / tau)
            h = signal.lfilter([1.0], [1.0, -a], v * dt)  # h' = v - h/tau
            f = f + strength * k * h
    elif effect == "friction":
        fmax, kf = 0.15 * K * np.std(x) * 3, 20 * K
        z = np.zeros_like(x)
        for t in range(1, x.size):
            z[t] = np.clip(z[t - 1] + kf * (x[t] - x[t - 1]), -fmax, fmax)
        f = f + strength * z
    elif effect == "hardening":
        s = np.std(x)
        f = f + strength * 0.08 * K * s * (x / s) ** 3
    elif effect == "thermal":
        e = np.cumsum(C * v * v) * dt  # dissipated energy, J
        f = f * (1 - strength * 0.3 * e / e[-1])
    elif effect == "delay":
        d = strength * 0.006
        t = np.arange(x.size) * dt
        f = np.interp(t - d, t, f, left=0.0)
    elif effect == "inertia":
        f = f + strength * 40.0 * np.gradient(v, dt)
    elif effect != "none":
        raise ValueError(effect)
    return f


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
