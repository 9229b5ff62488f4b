"""WHERE the held-out gap lies: regime masks, residual spectra, drift -- pure array functions.

All functions take (T,) arrays of prescribed displacement ``x`` (m), the force residual ``r``
(measured - simulated, N) and the sample time ``dt`` (s). Shares are fractions of the gap energy
``sum(r**2)`` pooled over all TEST samples (as ``rms_ratio`` pools them), next to the fraction of
samples (time share) the regime covers, so a reader sees where the gap is concentrated.

| regime            | samples                                                                  |
|-------------------|--------------------------------------------------------------------------|
| near_reversal     | within 15 % of the last stroke's length after a turning point of ``x``   |
| in_travel         | the rest                                                                 |
| held_after_step   | runs of ``|v| < 1 %`` of max ``|v|`` lasting >= 0.2 s, after a movement   |
| small_amplitude   | 1 s running max of ``|x|`` below its median over all TEST samples         |
| large_amplitude   | the rest                                                                 |
| low_velocity      | ``|v|`` below its median over all TEST samples                             |
| high_velocity     | the rest                                                                 |
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numba as nb
import numpy as np
from scipy import ndimage, signal

from bushenv.models.base import velocity_of

BANDS_HZ = (0.0, 0.5, 2.0, 8.0, 32.0, np.inf)
REVERSAL_FRACTION = 0.15
HOLD_VELOCITY_FRACTION = 0.01
HOLD_MIN_S = 0.2


@nb.njit(cache=True, nogil=True)
def distance_since_reversal(x: np.ndarray, hysteresis: float) -> tuple[np.ndarray, np.ndarray]:
    """(T,) distance travelled since the last turning point and (T,) length of the last stroke.

    A turning point counts once ``x`` has come back from its running extreme by ``hysteresis``
    (m), so noise on a still signal is not a string of reversals.
    """
    T = x.size
    dist = np.zeros(T)
    stroke = np.zeros(T)
    turn = x[0]
    prev_turn = x[0]
    extreme = x[0]
    ext_i = 0
    direction = 0
    for t in range(T):
        xt = x[t]
        if direction >= 0 and xt > extreme:
            extreme, ext_i = xt, t
            if xt - turn > hysteresis:
                direction = 1
        elif direction <= 0 and xt < extreme:
            extreme, ext_i = xt, t
            if turn - xt > hysteresis:
                direction = -1
        if (direction == 1 and extreme - xt > hysteresis) or (
            direction == -1 and xt - extreme > hysteresis
        ):
            # confirmed: the turning point is the extreme, so the samples since it count too
            prev_turn, turn = turn, extreme
            direction = -direction
            for s in range(ext_i, t):
                dist[s] = abs(x[s] - turn)
                stroke[s] = abs(turn - prev_turn)
            extreme, ext_i = xt, t
        dist[t] = abs(xt - turn)
        stroke[t] = abs(turn - prev_turn)
    return dist, stroke


def near_reversal_mask(x: np.ndarray) -> np.ndarray:
    """True within REVERSAL_FRACTION of the last stroke after a turning point."""
    span = float(np.ptp(x)) or 1.0
    dist, stroke = distance_since_reversal(x, 0.01 * span)
    stroke = np.maximum(stroke, 0.02 * span)
    return dist < REVERSAL_FRACTION * stroke


def held_after_step_mask(x: np.ndarray, dt: float) -> np.ndarray:
    """True on runs where the displacement is held (|v| < 1 % of its max) for >= 0.2 s after
    the record has moved (the initial rest does not count)."""
    v = np.abs(velocity_of(x, dt))
    vmax = float(v.max())
    if vmax == 0:
        return np.zeros(x.size, bool)
    still = v < HOLD_VELOCITY_FRACTION * vmax
    labels, n = ndimage.label(still)
    mask = np.zeros(x.size, bool)
    moved = np.cumsum(~still) > 0
    min_len = max(int(round(HOLD_MIN_S / dt)), 2)
    for sl in ndimage.find_objects(labels):
        seg = sl[0]
        if seg.stop - seg.start >= min_len and moved[seg.start]:
            mask[seg] = True
    return mask


def amplitude_envelope(x: np.ndarray, dt: float, window_s: float = 1.0) -> np.ndarray:
    """Running max of |x| over a centred window (m)."""
    size = max(int(round(window_s / dt)), 1)
    return ndimage.maximum_filter1d(np.abs(x), size=size, mode="nearest")


def residual_spectrum(r: np.ndarray, x: np.ndarray, dt: float):
    """Welch PSD of ``r`` (N^2/Hz) and its coherence with ``x``: (freq, psd, coherence)."""
    fs = 1.0 / dt
    # at least ~8 averaged segments: with one segment the coherence is 1 whatever the signals
    nper = int(min(2 ** int(np.round(np.log2(max(4.0 * fs, 16)))), max(r.size // 8, 16)))
    nper = min(nper, r.size)
    f, p = signal.welch(r, fs=fs, nperseg=nper)
    if np.ptp(x) == 0 or np.ptp(r) == 0:
        coh = np.zeros_like(f)
    else:
        with np.errstate(invalid="ignore", divide="ignore"):  # a held x has no power
            _, coh = signal.coherence(x, r, fs=fs, nperseg=nper)
    return f, p, np.nan_to_num(coh)


def _share(r2: np.ndarray, mask: np.ndarray, total: float) -> dict[str, float]:
    return {
        "energy_share": float(r2[mask].sum() / total) if total > 0 else 0.0,
        "time_share": float(mask.mean()) if mask.size else 0.0,
    }


def where_analysis(
    xs: Sequence[np.ndarray], residuals: Sequence[np.ndarray], dts: Sequence[float]
) -> dict[str, Any]:
    """The gap taken apart by regime, frequency band and time, over all TEST records.

    Returns ``{"regimes": {name: {"energy_share", "time_share"}}, "frequency": {"bands": [...],
    "coherent_share"}, "time": {"thirds": [...], "slow_share", "drift_ratio"}, "summary": [...]}``.
    """
    r_all = np.concatenate([np.asarray(r, float) for r in residuals])
    r2 = r_all * r_all
    total = float(r2.sum())
    near = np.concatenate([near_reversal_mask(x) for x in xs])
    held = np.concatenate([held_after_step_mask(x, dt) for x, dt in zip(xs, dts, strict=True)])
    env = np.concatenate([amplitude_envelope(x, dt) for x, dt in zip(xs, dts, strict=True)])
    speed = np.concatenate(
        [np.abs(velocity_of(np.asarray(x, float), dt)) for x, dt in zip(xs, dts, strict=True)]
    )
    small = env < np.median(env)
    slow = speed < np.median(speed)
    regs = {
        "near_reversal": _share(r2, near, total),
        "in_travel": _share(r2, ~near, total),
        "held_after_step": _share(r2, held, total),
        "small_amplitude": _share(r2, small, total),
        "large_amplitude": _share(r2, ~small, total),
        "low_velocity": _share(r2, slow, total),
        "high_velocity": _share(r2, ~slow, total),
    }

    band_energy = np.zeros(len(BANDS_HZ) - 1)
    coherent = 0.0
    thirds = np.zeros(3)
    slow_energy = 0.0
    for x, r, dt in zip(xs, residuals, dts, strict=True):
        r = np.asarray(r, float)
        e = float(np.sum(r * r))
        if e == 0:
            continue
        f, p, coh = residual_spectrum(r, np.asarray(x, float), dt)
        ptot = float(p.sum()) or 1.0
        for i in range(len(BANDS_HZ) - 1):
            sel = (f >= BANDS_HZ[i]) & (f < BANDS_HZ[i + 1])
            band_energy[i] += e * float(p[sel].sum()) / ptot
        coherent += e * float((coh * p).sum()) / ptot
        for i, part in enumerate(np.array_split(r, 3)):
            thirds[i] += float(np.sum(part * part))
        # slow part: the 5 s running mean of the residual (drift, thermal, slow relaxation)
        size = max(int(round(5.0 / dt)), 1)
        if size < r.size:
            slow_part = ndimage.uniform_filter1d(r, size=size, mode="nearest")
            slow_energy += float(np.sum(slow_part * slow_part))
    denom = total or 1.0
    bands = [
        {"lo_hz": float(BANDS_HZ[i]), "hi_hz": float(BANDS_HZ[i + 1]), "energy_share": float(b)}
        for i, b in enumerate(band_energy / denom)
    ]
    time_part = {
        "thirds": [float(t) for t in thirds / denom],
        "slow_share": float(slow_energy / denom),
        "drift_ratio": float(thirds[2] / thirds[0]) if thirds[0] > 0 else float("inf"),
    }
    freq = {"bands": bands, "coherent_share": float(coherent / denom)}
    return {
        "regimes": regs,
        "frequency": freq,
        "time": time_part,
        "summary": summarise(regs, freq, time_part),
    }


def summarise(regs: dict, freq: dict, time_part: dict) -> list[str]:
    """Plain sentences, most telling first."""
    out = []
    pairs = [
        ("near_reversal", "near reversals"),
        ("held_after_step", "while a deflection is held after a step"),
        ("large_amplitude", "at large amplitude"),
        ("small_amplitude", "at small amplitude"),
        ("high_velocity", "at high velocity"),
        ("low_velocity", "at low velocity"),
    ]
    ranked = []
    for key, words in pairs:
        s = regs[key]
        if s["time_share"] > 0:
            ranked.append((s["energy_share"] / s["time_share"], key, words, s))
    ranked.sort(reverse=True)
    for conc, _key, words, s in ranked[:3]:
        out.append(
            f"{100 * s['energy_share']:.0f} % of the gap energy lies {words}, "
            f"which is {100 * s['time_share']:.0f} % of the time ({conc:.1f}x its share)."
        )
    b = max(freq["bands"], key=lambda d: d["energy_share"])
    hi = "Nyquist" if np.isinf(b["hi_hz"]) else f"{b['hi_hz']:g} Hz"
    out.append(
        f"{100 * b['energy_share']:.0f} % of the gap energy is between {b['lo_hz']:g} Hz and {hi}; "
        f"{100 * freq['coherent_share']:.0f} % is linearly coherent with the displacement "
        "(the rest is nonlinear or noise)."
    )
    t = time_part["thirds"]
    out.append(
        f"Over time: {100 * t[0]:.0f} / {100 * t[1]:.0f} / {100 * t[2]:.0f} % of the gap energy "
        f"in the first / middle / last third of the records; slow drift (5 s mean) holds "
        f"{100 * time_part['slow_share']:.0f} %."
    )
    return out
