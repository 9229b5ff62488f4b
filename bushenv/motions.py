"""Motions of a bushing of C coordinates at once: random on every coordinate with the amplitude
index n per coordinate (independent and correlated), one coordinate held while another sweeps
(``preload_sweep``, ``held_sweeps``, ``coupled_sets``) and the unseen verification motions.
Pure functions: (T, C) profiles in SI (m, m, rad for the three in-plane coordinates),
deterministic per seed; ``bushenv.excitation`` holds the one-coordinate signals they are made of.

Amplitude index (seed 001 §3.2.2, as ``bushenv.excitation.random_rpc``): the peak of each
coordinate is n times its peak at n = 1, ``peaks`` (C,), by default ``PEAK_AT_N1`` = (2 mm,
2 mm, 0.05 rad; the rotation assumed, see ``bushenv/reference/planar.py``). n = 1 identifies,
n = 1.5 verifies.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from bushenv.excitation import chirp, random_rpc
from bushenv.reference.planar import THETA_N1_RAD

PEAK_AT_N1 = np.array([2.0e-3, 2.0e-3, THETA_N1_RAD])
COORDS = ("axial", "radial", "rotation")  # the coordinates PEAK_AT_N1 is for
CORRELATION = 0.8  # share of the common drive in the correlated set
N_VERIFY = 1.5
# the coordinate swept under each held one in the coupled sets (axial: radial, radial:
# rotation, rotation: radial)
SWEPT_UNDER = {0: 1, 1: 2, 2: 1}


def random_independent(
    n_index: float, duration_s: float, dt: float, seed: int, peaks: np.ndarray = PEAK_AT_N1
) -> np.ndarray:
    """(T, C): each coordinate its own RPC-like random drive, peak n * ``peaks``."""
    return np.stack(
        [
            random_rpc(n_index, duration_s, dt, len(peaks) * seed + i, peak_m_at_n1=peak)
            for i, peak in enumerate(peaks)
        ],
        axis=1,
    )


def random_correlated(
    n_index: float, duration_s: float, dt: float, seed: int, peaks: np.ndarray = PEAK_AT_N1
) -> np.ndarray:
    """(T, C): all coordinates driven by one common random drive (weight 0.8) plus their own
    (0.6), signs (+, +, -, +, ...): the axes move together, as on a car where one load path
    drives all."""
    peaks = np.asarray(peaks, dtype=np.float64)
    common = random_rpc(1.0, duration_s, dt, 10_000 + seed, peak_m_at_n1=1.0)
    own = random_independent(1.0, duration_s, dt, seed, peaks) / peaks
    signs = np.ones(len(peaks))
    signs[2::3] = -1.0
    mix = CORRELATION * common[:, None] * signs + np.sqrt(1 - CORRELATION**2) * own
    return mix / np.abs(mix).max(axis=0) * n_index * peaks


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
    n_coords: int = 3,
) -> np.ndarray:
    """(T, ``n_coords``): coordinate ``held`` ramped (1 s, half-cosine) to ``held_value`` and
    held; coordinate ``swept`` swept from 1.5 s on (linear chirp ``f_hz``,
    ``swept_amplitude``); the others at rest. ``held=1``: radial preload with a rotation
    sweep; ``held=2``: the reverse; ``held=0``: axial preload with a radial sweep. ``swept``
    defaults to those pairs (``SWEPT_UNDER``)."""
    swept = SWEPT_UNDER.get(held, 0) if swept is None else swept
    if held == swept or {held, swept} - set(range(n_coords)):
        raise ValueError(
            f"preload_sweep: held {held} and swept {swept} must be two of "
            f"{', '.join(map(str, range(n_coords)))}"
        )
    T = int(round(duration_s / dt))
    q = np.zeros((T, n_coords))
    q[:, held] = _hold(held_value, T, int(round(1.0 / dt)))
    start = int(round(1.5 / dt))
    q[start:, swept] = chirp(f_hz[0], f_hz[1], swept_amplitude, (T - start) * dt, dt)[: T - start]
    return q


def held_sweeps(
    n_index: float,
    dt: float,
    duration_s: float = 10.0,
    peaks: np.ndarray = PEAK_AT_N1,
    coords: Sequence[str] = COORDS,
) -> list[tuple[str, np.ndarray]]:
    """Every held combination a vehicle loads a bushing in: each coordinate held at +- n x its
    n = 1 peak (``peaks``) while each other one is swept (0.5-5 Hz, n x its peak), the others
    at rest: C (C - 1) x 2 named (T, C) motions (``coverage.every_combination``'s list)."""
    c = len(peaks)
    out = []
    for held in range(c):
        for sign in (1.0, -1.0):
            for swept in range(c):
                if swept == held:
                    continue
                level, amp = sign * n_index * peaks[held], n_index * peaks[swept]
                name = f"{coords[held]}_held_{'+' if sign > 0 else '-'}_{coords[swept]}_sweep"
                motion = preload_sweep(held, level, amp, duration_s, dt, swept=swept, n_coords=c)
                out.append((name, motion))
    return out


def coupled_sets(
    n_index: float, dt: float, duration_s: float = 20.0
) -> list[tuple[str, np.ndarray]]:
    """The coupled sine sets of the three in-plane coordinates at amplitude index n, named by
    their preloads: a radial preload of n x 2 mm under a 0.5-5 Hz rotation sweep of n x 0.05
    rad, a rotation preload of n x 0.05 rad under a radial sweep of n x 2 mm, and an axial
    preload of n x 2 mm under a radial sweep of n x 2 mm (without it no record holds the axial
    coordinate, and its slow relaxation is not told from its static stiffness)."""
    axial, radial, theta = n_index * PEAK_AT_N1
    return [
        (
            f"radial_preload_{radial * 1e3:g}mm_rotation_sweep",
            preload_sweep(1, radial, theta, duration_s, dt),
        ),
        (
            f"rotation_preload_{theta:g}rad_radial_sweep",
            preload_sweep(2, theta, radial, duration_s, dt),
        ),
        (
            f"axial_preload_{axial * 1e3:g}mm_radial_sweep",
            preload_sweep(0, axial, radial, duration_s, dt),
        ),
    ]


def verification_motions(
    dt: float, seed: int, n_verify: float = N_VERIFY, duration_s: float = 20.0
) -> dict[str, np.ndarray]:
    """The unseen verification motions of the three in-plane coordinates, by name
    (``duration_s`` each): random at the training amplitude n = 1 (new seeds), then at the
    verification amplitude ``n_verify`` and the coupled sets there (the axial one last). The one
    list: ``bushenv reproduce --planar`` and the three-axis scripts judge on these."""
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
