"""The statistics the naming rule rests on: a test of one model's cut in judged error against
another's, on contiguous blocks of the judged residuals, and the force's measurement noise.

Neighbouring residual samples are correlated (a misfit is smooth in time), so a test that
counts samples as independent finds anything significant. The judged samples are cut into
blocks of ``BLOCK_S`` seconds per record, and the spread of a cut is summed block by block.
"""

from __future__ import annotations

import numpy as np

from bushenv.diagnose.design import whole_record_psd

BLOCK_S = 1.0  # seconds per block: longer than a misfit's correlation at bushing rates
QUIET = 1e-4  # a frequency where the displacement's PSD is below this share of its peak ...
NOISE_TOP = 0.75  # ... and below this share of Nyquist holds noise only


def block_edges(sizes: list[int], dts: list[float]) -> list[tuple[int, int]]:
    """(start, stop) of every block over the concatenated judged samples, none across records."""
    out = []
    start = 0
    for n, dt in zip(sizes, dts, strict=True):
        per = max(int(round(BLOCK_S / dt)), 1)
        count = max(n // per, 1)
        edges = np.linspace(start, start + n, count + 1).round().astype(int)
        out += list(zip(edges[:-1], edges[1:], strict=True))
        start += n
    return out


def cut_z(
    y: np.ndarray, worse: np.ndarray, better: np.ndarray, edges: list[tuple[int, int]]
) -> float:
    """z score of the cut in judged squared error from prediction ``worse`` to ``better``.

    The cut is ``sum(e_w^2 - e_b^2) = sum(2 e_b d + d^2)`` with ``d = better - worse``; were
    ``better`` only fitting noise, its size would be that of ``2 sum e_b d``, whose spread is
    taken over blocks (``sum_b (2 sum_{t in b} e_b d)^2``) so that correlated residuals count
    as what they are. A large, localised cut (relaxation seen only in a hold) scores high;
    a cut that is small against the residual it leaves does not.
    """
    e_b = y - better
    d = better - worse
    cut = float(np.sum((y - worse) ** 2) - np.sum(e_b**2))
    prod = e_b * d
    var = sum(float(np.sum(prod[a:b])) ** 2 for a, b in edges)
    if var <= 0:
        return np.inf if cut > 0 else 0.0
    return cut / (2.0 * np.sqrt(var))


def noise_variance(residuals: list[np.ndarray], xs: list[np.ndarray], dts: list[float]) -> float:
    """Force measurement-noise variance (N^2) from residuals, taken as white: the median of
    their PSD over the frequencies where the displacement has no motion (PSD below
    ``QUIET`` of its peak) up to ``NOISE_TOP`` of Nyquist (an anti-alias filter may cut the
    top), times the band; where there are no such frequencies, the median above it.

    Per record, pooled by sample count.
    """
    total, count = 0.0, 0
    for e, x, dt in zip(residuals, xs, dts, strict=True):
        if e.size < 256:
            continue
        f, p = whole_record_psd(e, dt, 1024)
        _, px = whole_record_psd(x, dt, 1024)
        quiet = (f > 0) & (px < QUIET * px.max()) & (f <= NOISE_TOP * f[-1])
        if quiet.sum() < 8:
            quiet = f >= NOISE_TOP * f[-1]
        total += float(np.median(p[quiet])) * f[-1] * e.size
        count += e.size
    return total / count if count else 0.0
