"""The 3-axis test programme: random on all axes with the amplitude index n per axis
(independent and correlated), and the coupled sine sets (radial preload under a rotation
sweep, the reverse, and an axial preload under a radial sweep). Pure functions: (T, 3)
profiles in m, m, rad, deterministic per seed.

Amplitude index (seed 001 §3.2.2, as ``bushenv.excitation.random_rpc``): the peak of each
coordinate is n times its peak at n = 1, ``PEAK_AT_N1`` = (2 mm, 2 mm, 0.05 rad; the rotation
assumed, see ``reference.py``). n = 1 identifies, n = 1.5 verifies.
"""

from __future__ import annotations

import numpy as np

from bushenv.excitation import chirp, random_rpc
from bushenv.reference.planar import THETA_N1_RAD

PEAK_AT_N1 = np.array([2.0e-3, 2.0e-3, THETA_N1_RAD])
CORRELATION = 0.8  # share of the common drive in the correlated set


def random_independent(n_index: float, duration_s: float, dt: float, seed: int) -> np.ndarray:
    """Each coordinate its own RPC-like random drive, peak n * PEAK_AT_N1."""
    return np.stack(
        [
            random_rpc(n_index, duration_s, dt, 3 * seed + i, peak_m_at_n1=PEAK_AT_N1[i])
            for i in range(3)
        ],
        axis=1,
    )


def random_correlated(n_index: float, duration_s: float, dt: float, seed: int) -> np.ndarray:
    """All coordinates driven by one common random drive (weight 0.8) plus their own (0.6),
    signs (+, +, -): the axes move together, as on a car where one load path drives all."""
    common = random_rpc(1.0, duration_s, dt, 10_000 + seed, peak_m_at_n1=1.0)
    own = random_independent(1.0, duration_s, dt, seed) / PEAK_AT_N1
    mix = (
        CORRELATION * common[:, None] * np.array([1.0, 1.0, -1.0])
        + np.sqrt(1 - CORRELATION**2) * own
    )
    return mix / np.abs(mix).max(axis=0) * n_index * PEAK_AT_N1


def _hold(level: float, T: int, ramp_n: int) -> np.ndarray:
    out = np.full(T, level)
    out[:ramp_n] = level * 0.5 * (1 - np.cos(np.pi * np.arange(ramp_n) / ramp_n))
    return out


def preload_sweep(
    held: int,
    held_value: float,
    swept_amplitude: float,
    duration_s: float,
    dt: float,
    f_hz: tuple[float, float] = (0.5, 5.0),
    swept: int | None = None,
) -> np.ndarray:
    """Coordinate ``held`` ramped (1 s, half-cosine) to ``held_value`` and held; coordinate
    ``swept`` swept from 1.5 s on (linear chirp ``f_hz``, ``swept_amplitude``); the third at
    rest. ``held=1``: radial preload with a rotation sweep; ``held=2``: the reverse; ``held=0``:
    axial preload with a radial sweep. ``swept`` defaults to those pairs."""
    swept = {0: 1, 1: 2, 2: 1}[held] if swept is None else swept
    if held == swept or {held, swept} - {0, 1, 2}:
        raise ValueError(f"preload_sweep: held {held} and swept {swept} must be two of 0, 1, 2")
    T = int(round(duration_s / dt))
    q = np.zeros((T, 3))
    q[:, held] = _hold(held_value, T, int(round(1.0 / dt)))
    start = int(round(1.5 / dt))
    q[start:, swept] = chirp(f_hz[0], f_hz[1], swept_amplitude, (T - start) * dt, dt)[: T - start]
    return q


def held_sweeps(n_index: float, dt: float, duration_s: float = 10.0) -> list:
    """Every held combination a vehicle loads a bushing in: each coordinate held at +- n x its
    n = 1 peak (``PEAK_AT_N1``) while each other one is swept (0.5-5 Hz, n x its peak), the
    third at rest: 12 named (T, 3) motions (``coverage.every_combination``'s list)."""
    from bushenv.models.planar_base import COORDS

    out = []
    for held in range(3):
        for sign in (1.0, -1.0):
            for swept in range(3):
                if swept == held:
                    continue
                level, amp = sign * n_index * PEAK_AT_N1[held], n_index * PEAK_AT_N1[swept]
                name = f"{COORDS[held]}_held_{'+' if sign > 0 else '-'}_{COORDS[swept]}_sweep"
                out.append((name, preload_sweep(held, level, amp, duration_s, dt, swept=swept)))
    return out


def programme(
    dt: float, seed: int, n_verify: float = 1.5, duration_s: float = 20.0
) -> dict[str, np.ndarray]:
    """The unseen verification records, by name (``duration_s`` each): random at the training
    amplitude n = 1 (new seeds), then at the verification amplitude ``n_verify`` and the
    coupled sets there (the axial one last). The one list: ``bushenv reproduce --planar`` and
    the planar scripts judge on these."""
    axial, radial, theta = n_verify * PEAK_AT_N1
    return {
        "random independent n=1": random_independent(1.0, duration_s, dt, 3000 + seed),
        "random correlated n=1": random_correlated(1.0, duration_s, dt, 4000 + seed),
        "random independent": random_independent(n_verify, duration_s, dt, 1000 + seed),
        "random correlated": random_correlated(n_verify, duration_s, dt, 2000 + seed),
        "radial preload + rotation sweep": preload_sweep(1, radial, theta, duration_s, dt),
        "rotation preload + radial sweep": preload_sweep(2, theta, radial, duration_s, dt),
        "axial preload + radial sweep": preload_sweep(0, axial, radial, duration_s, dt),
    }
