"""A stand-in "real" bushing for identification tests (not the package's reference rubber).

F = k x + c v + two Maxwell branches + a smooth friction element + cubic hardening, driven by
band-limited Gaussian noise scaled to 2 mm peak. Written independently of bushenv so the tests
identify something the models were not built from.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import butter, sosfiltfilt

DT = 1.0 / 204.8


def standin_drive(duration_s: float, seed: int, peak_m: float = 0.002) -> np.ndarray:
    """Filtered Gaussian noise (0.5-20 Hz), (T,) in m, peak |x| = peak_m."""
    rng = np.random.default_rng(seed)
    T = int(round(duration_s / DT))
    sos = butter(4, [0.5, 20.0], btype="band", fs=1.0 / DT, output="sos")
    x = sosfiltfilt(sos, rng.normal(size=T + 400))[200:-200]
    ramp = np.minimum(1.0, np.minimum(np.arange(T), np.arange(T)[::-1]) / 100.0)
    x = x * ramp
    return x * (peak_m / np.max(np.abs(x)))


def standin_force(x: np.ndarray, dt: float = DT) -> np.ndarray:
    """Force (T,) in N of the stand-in bushing for displacement x (T,) in m."""
    k, c, k3 = 300e3, 800.0, 1.0e10
    branches = ((100e3, 0.01), (60e3, 0.2))  # (k_i N/m, tau_i s) Maxwell
    f_slip, k_f = 80.0, 2.0e6  # smooth friction: F_f' = k_f (v - |v| F_f / f_slip), exact

    v = np.gradient(x, dt)
    fm = np.zeros(len(branches))
    ff = 0.0
    out = np.empty_like(x)
    for t in range(len(x)):
        vt = v[t]
        for i, (ki, tau) in enumerate(branches):
            a = np.exp(-dt / tau)
            fm[i] = a * fm[i] + ki * tau * (1.0 - a) * vt
        if vt != 0.0:
            f_eq = np.sign(vt) * f_slip
            ff = f_eq + (ff - f_eq) * np.exp(-k_f * abs(vt) * dt / f_slip)
        out[t] = k * x[t] + c * vt + k3 * x[t] ** 3 + fm.sum() + ff
    return out
