"""Where the divergence judge's ``energy`` criterion fires on sines, for comparison with the
linearised non-passive band (``passivity``).

Each profile starts at rest, follows A sin(2 pi f t) for ``DURATION_S`` and then holds its last
value for ``TAIL_S`` (as the search's sine family ends in a hold); model and reference run the
same profiles and ``bushenv.divergence.judge`` decides. Amplitudes the machine cannot drive at a
frequency (2 pi f A above ``excitation.MAX_VELOCITY_M_PER_S``) are not run (``None``).
"""

from __future__ import annotations

import numpy as np

from bushenv import excitation as ex
from bushenv.divergence import judge

DURATION_S = 4.0
TAIL_S = 1.0


def sine_batch(freq_hz: np.ndarray, amplitude_m: float, dt: float) -> np.ndarray:
    """(T, F) sines from rest, each followed by a hold of its last value."""
    t = np.arange(int(round(DURATION_S / dt))) * dt
    x = amplitude_m * np.sin(2.0 * np.pi * np.outer(t, freq_hz))
    tail = np.broadcast_to(x[-1], (int(round(TAIL_S / dt)), x.shape[1]))
    return np.ascontiguousarray(np.concatenate([x, tail]))


def energy_fires(
    model, reference, freq_hz: np.ndarray, amplitudes_m: np.ndarray
) -> list[list[bool | None]]:
    """[amplitude][frequency]: does ``judge`` flag ``energy`` on that sine (None: not drivable).
    ``model`` and ``reference`` are copied (their states are not touched); ``reference`` None:
    judged without one (the model's own work must stay >= 0 at every return)."""
    freq_hz = np.asarray(freq_hz, dtype=np.float64)
    out: list[list[bool | None]] = []
    m, r = model.copy(), None if reference is None else reference.copy()
    for amp in np.asarray(amplitudes_m, dtype=np.float64):
        ok = 2.0 * np.pi * freq_hz * amp <= ex.MAX_VELOCITY_M_PER_S
        row: list[bool | None] = [None] * freq_hz.size
        if np.any(ok):
            x = sine_batch(freq_hz[ok], float(amp), model.dt)
            f_ref = None if r is None else r.simulate(x)  # None: the model's own work
            verdict = judge(x, m.simulate(x), f_ref, model.dt)
            for k, fires in zip(np.flatnonzero(ok), verdict.flags["energy"], strict=True):
                row[k] = bool(fires)
        out.append(row)
    return out


def firing_bands(freq_hz: np.ndarray, fires: list[bool | None]) -> list[tuple[float, float]]:
    """Runs of consecutive frequencies (grid points) where the criterion fired."""
    bands: list[tuple[float, float]] = []
    start = None
    for k, f in enumerate(list(fires) + [False]):
        if f and start is None:
            start = k
        if not f and start is not None:
            bands.append((float(freq_hz[start]), float(freq_hz[k - 1])))
            start = None
    return bands
