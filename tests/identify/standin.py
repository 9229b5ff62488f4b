"""Stand-in "real" bushings for identification tests (not the package's reference rubbers).

One axis (``standin_force``):
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


# Three axes: a small coupled bushing and the files a rig might write of it.


def bushing(fs=500.0, seconds=4.0, preload=(0.0, 0.0, 0.0), rest_s=0.2):
    """A small coupled bushing of its own (no bushenv code): 3x3 stiffness with off-diagonal
    terms, viscous damping, a cubic radial-torsion coupling and a radial Maxwell branch,
    driven from rest by three sines (after ``rest_s`` at rest), around ``preload``."""
    t = np.arange(int(fs * seconds)) / fs
    ramp = np.clip((t - rest_s) / 0.5, 0.0, 1.0)[:, None]
    drive = np.column_stack(
        [1.5e-3 * np.sin(2.2 * t), 1e-3 * np.sin(3.1 * t + 1.0), 0.04 * np.sin(1.7 * t + 2.0)]
    )
    q = ramp * (drive + np.asarray(preload))
    v = np.gradient(q, 1.0 / fs, axis=0)
    k = np.array([[5e5, -4e4, 600.0], [-4e4, 2e6, -1500.0], [600.0, -1500.0, 1000.0]])
    f = q @ k.T + v * [200.0, 600.0, 0.4]
    s = q[:, 1] ** 2 + (0.04 * q[:, 2]) ** 2
    f[:, 1] += 2e10 * s * q[:, 1]
    f[:, 2] += 2e10 * s * 0.04**2 * q[:, 2]
    a, p = np.exp(-1.0 / (fs * 0.05)), 0.0
    for i in range(t.size):  # Maxwell branch, tau 50 ms, on the radial axis
        p = a * p + 3e5 * 0.05 * (1.0 - a) * v[i, 1]
        f[i, 1] += p
    return t, q, f


def write(path, header, cols):
    rows = [",".join(f"{x:.10g}" for x in r) for r in np.column_stack(cols)]
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def user_columns(t, q, f):
    """Grouped per axis, in ms, mm, deg, kN and N m, as a rig's own export might be."""
    header = (
        "time [ms],displacement_axial [mm],force_axial [kN],displacement_radial [mm],"
        "force_radial [kN],rotation [deg],moment [N m]"
    )
    cols = [1e3 * t, 1e3 * q[:, 0], 1e-3 * f[:, 0], 1e3 * q[:, 1], 1e-3 * f[:, 1]]
    return header, [*cols, np.degrees(q[:, 2]), f[:, 2]]
