"""A record shifted in time by a fraction of a sample: what the delay and every effect's
forward form (seen through the force channel) share."""

from __future__ import annotations

import numpy as np

TAPS = 8  # points of the Lagrange interpolation (7th order)


def lagrange_weights(f: float, taps: int = TAPS) -> list[tuple[int, float]]:
    """(offset, weight) of Lagrange interpolation at ``f`` in [0, 1) past a sample."""
    offsets = range(-(taps // 2) + 1, taps // 2 + 1)
    out = []
    for k in offsets:
        w = 1.0
        for m in offsets:
            if m != k:
                w *= (f - m) / (k - m)
        out.append((k, w))
    return out


def shift_columns(cols: np.ndarray, delay_s: float, dt: float) -> np.ndarray:
    """cols(t - delay) by 8-point Lagrange interpolation ((T,) or (T, p)); the first and last
    values hold beyond the ends. Exact for whole-sample delays."""
    if delay_s == 0.0:
        return cols
    n = delay_s / dt
    whole = int(np.floor(n))
    f = n - whole  # the value sits f samples before sample t - whole
    if f == 0.0:
        weights = [(0, 1.0)]
    else:
        weights = [(-k, w) for k, w in lagrange_weights(1.0 - f)]
        whole += 1  # interpolate forward from sample t - whole - 1
    last = cols.shape[0] - 1
    base = np.arange(cols.shape[0]) - whole
    out = np.zeros(cols.shape)
    for k, w in weights:
        out += w * cols[np.clip(base - k, 0, last)]
    return out
