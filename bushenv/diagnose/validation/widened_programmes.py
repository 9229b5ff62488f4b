"""Programmes of the widened validation set, on a fine grid (m): random, multisine, sweeps,
sine blocks at several amplitudes, step-holds, rounded triangles for bushings; constant-rate
pulls and relaxation holds of 40-160 mm for quasi-static tests."""

from __future__ import annotations

import numpy as np
from scipy import ndimage, signal


def _logu(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


# ----- programmes (fine grid) ----------------------------------------------------------------
def _smooth_steps(levels: list[float], holds: list[float], rise_s: float, dt: float) -> np.ndarray:
    out = [np.zeros(max(int(0.5 / dt), 1))]
    cur = 0.0
    n_rise = max(int(rise_s / dt), 2)
    ramp = 0.5 - 0.5 * np.cos(np.linspace(0, np.pi, n_rise))
    for lev, hold in zip(levels, holds, strict=True):
        out.append(cur + (lev - cur) * ramp)
        out.append(np.full(int(hold / dt), lev))
        cur = lev
    return np.concatenate(out)


def _band_noise(n: int, dt: float, f_lo: float, f_hi: float, rng) -> np.ndarray:
    spec = rng.normal(size=n // 2 + 1) + 1j * rng.normal(size=n // 2 + 1)
    f = np.fft.rfftfreq(n, dt)
    shape = 1.0 / np.maximum(f, f_lo) ** rng.uniform(0.0, 1.5)  # a tilted spectrum
    shape[(f < f_lo) | (f > f_hi)] = 0.0
    x = np.fft.irfft(spec * shape, n)
    env = 0.35 + 0.65 * np.abs(np.sin(np.pi * np.arange(n) * dt / (n * dt) * rng.uniform(1, 4)))
    return x * env


def _multisine(n: int, dt: float, f_lo: float, f_hi: float, rng) -> np.ndarray:
    t = np.arange(n) * dt
    freqs = np.geomspace(f_lo, f_hi, 24) * rng.uniform(0.97, 1.03, 24)
    amps = freqs ** -rng.uniform(0.3, 1.0)
    x = sum(
        a * np.sin(2 * np.pi * fr * t + rng.uniform(0, 2 * np.pi))
        for a, fr in zip(amps, freqs, strict=True)
    )
    return np.asarray(x)


def _sweep(n: int, dt: float, f_lo: float, f_hi: float, rng) -> np.ndarray:
    t = np.arange(n) * dt
    x = signal.chirp(t, f_lo, t[-1], f_hi, method="logarithmic")
    return x * (f_lo / np.geomspace(f_lo, f_hi, n)) ** rng.uniform(0.0, 0.7)


def _sine_blocks(n: int, dt: float, f_lo: float, f_hi: float, rng) -> np.ndarray:
    out = np.zeros(n)
    block = max(int(rng.uniform(2.0, 4.0) / dt), 8)
    t = np.arange(block) * dt
    win = np.minimum(1.0, np.minimum(t, t[::-1]) / 0.3)
    for start in range(0, n - block + 1, block):
        fr = _logu(rng, f_lo, f_hi)
        out[start : start + block] = rng.uniform(0.2, 1.0) * np.sin(2 * np.pi * fr * t) * win
    return out


def _dynamic_programme(kind: str, duration_s: float, dt: float, band, rng) -> np.ndarray:
    n = int(duration_s / dt)
    f_lo, f_hi = band
    if kind == "steps":
        k = int(rng.integers(2, 5))
        levels = [rng.uniform(0.3, 1.0) * rng.choice([-1, 1]) for _ in range(k)] + [0.0]
        holds = [rng.uniform(2.0, 8.0) for _ in range(k)] + [rng.uniform(1.0, 3.0)]
        return _smooth_steps(levels, holds, rng.uniform(0.03, 0.2), dt)
    if kind == "triangle":
        period = _logu(rng, 0.5, 4.0)
        t = np.arange(n) * dt
        # a machine rounds the reversals: 3 % of the period
        return ndimage.gaussian_filter1d(
            signal.sawtooth(2 * np.pi * t / period, 0.5), 0.03 * period / dt
        )
    gen = {
        "bandnoise": _band_noise,
        "multisine": _multisine,
        "sweep": _sweep,
        "sine_blocks": _sine_blocks,
    }[kind]
    return gen(n, dt, f_lo, f_hi, rng)


def regrid(x: np.ndarray, dt: float, dt_new: float) -> np.ndarray:
    """The programme ``x`` (sampled every ``dt``) on a grid of step ``dt_new``."""
    t = np.arange(x.size) * dt
    return np.interp(np.arange(int(t[-1] / dt_new) + 1) * dt_new, t, x)


def _normalised(x: np.ndarray, peak: float) -> np.ndarray:
    x = x - x[0]
    return x * (peak / (np.max(np.abs(x)) or 1.0))


def bushing_programmes(rng, dt_fine: float, min_rate_hz: float) -> tuple[list, list, dict]:
    """TRAIN (random, sometimes with a held step) and 1-3 TESTs of other kinds and sizes;
    the band stays below a tenth of the slower record rate."""
    band = (_logu(rng, 0.2, 1.0), min(_logu(rng, 8.0, 40.0), min_rate_hz / 10))
    peak = _logu(rng, 0.6e-3, 6e-3)
    kind = str(rng.choice(["bandnoise", "multisine", "sine_blocks"]))
    x = _normalised(_dynamic_programme(kind, rng.uniform(8.0, 60.0), dt_fine, band, rng), peak)
    if rng.random() < 0.4:
        x = np.concatenate([x, x[-1] + peak * _dynamic_programme("steps", 0, dt_fine, band, rng)])
    train = [x]
    tests, kinds = [], []
    for _ in range(int(rng.integers(1, 4))):
        k = str(rng.choice(["bandnoise", "multisine", "sweep", "sine_blocks", "steps", "triangle"]))
        d = rng.uniform(5.0, 30.0)
        tests.append(
            _normalised(_dynamic_programme(k, d, dt_fine, band, rng), peak * _logu(rng, 0.6, 1.6))
        )
        kinds.append(k)
    info = {
        "train": kind,
        "tests": kinds,
        "band_hz": [round(b, 2) for b in band],
        "peak_mm": round(1e3 * peak, 3),
    }
    return train, tests, info


def _pull(x_max: float, rate: float, dt: float, cycles: int) -> np.ndarray:
    n = int(x_max / rate / dt)
    up = np.linspace(0.0, x_max, n)
    one = np.concatenate([up, up[::-1][1:]])
    return np.concatenate([np.zeros(int(1.0 / dt))] + [one] * cycles)


def _hold(level: float, rate: float, hold_s: float, dt: float, unload: bool) -> np.ndarray:
    up = np.linspace(0.0, level, max(int(level / rate / dt), 2))
    parts = [np.zeros(int(1.0 / dt)), up, np.full(int(hold_s / dt), level)]
    if unload:
        parts += [up[::-1], np.zeros(int(min(hold_s, 60.0) / dt))]
    return np.concatenate(parts)


def quasi_static_programmes(rng, dt_fine: float, min_rate_hz: float) -> tuple[list, list, dict]:
    """Constant-rate pulls at three rates and relaxation holds, 50 Hz, 40-160 mm."""
    x_max = rng.uniform(0.04, 0.16)
    rates = sorted(rng.choice([0.5e-3, 0.8e-3, 1.5e-3, 2.4e-3, 4e-3, 6e-3], 3, replace=False))
    order = rng.permutation(3)
    train = [_pull(x_max, rates[order[0]], dt_fine, int(rng.integers(1, 3)))]
    tests = [_pull(x_max, rates[i], dt_fine, 1) for i in order[1:]]
    for _ in range(int(rng.integers(1, 3))):
        tests.append(
            _hold(
                x_max * rng.uniform(0.5, 1.0),
                rng.uniform(8e-3, 25e-3),
                rng.uniform(60.0, 400.0),
                dt_fine,
                bool(rng.random() < 0.5),
            )
        )
    info = {"x_max_mm": round(1e3 * x_max, 1), "rates_mm_per_s": [1e3 * r for r in rates]}
    return train, tests, info
