"""The static behaviour of a bushing estimated from its random-drive records (no holds needed).

Identification records are random drives: they never hold, so the force a bushing keeps at a
held displacement is not measured. Its best estimate from the records themselves is their
*slow content*: below the lowest frequencies of the drive the force follows the displacement
almost in phase, and the slope of that relation is the stiffness closest to static the records
can show. Here, per record (its training part),

1. the cutoff f_c is the frequency below which ``VARIANCE_QUANTILE`` of the displacement's
   variance lies (the records' own slowest content; at least ``MIN_CYCLES`` cycles per record
   and at most a quarter of Nyquist);
2. x and F are low-passed at f_c (4th-order Butterworth, forward and backward: no phase);
3. least squares F_lp = k_s x_lp + c_s v_lp + F_0 over every record's slow content.

The static estimate is F_s(x) = F_0 + k_s x, extrapolated linearly over the whole stroke. Only
the slope can be estimated: at n = 1 the slow content is a few hundredths of a millimetre
(0.03 mm RMS below 2 Hz), too small to show a curve. Rubber is stiffer at the drive's
frequencies than in a hold (relaxation), stiffens at large deflection (hardening) and, through
friction, near rest: a rubber's static curve lies about 0.8-1.3 times F_s beyond 1 mm and up to
1.8 times within 0.25 mm (the reference rubber: docs/fit.md, tested in
``tests/identify/test_static_estimate.py``); the certified training term (``certified.py``)
judges the model's held force in a band about F_s wide enough for that.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import butter, sosfiltfilt

from bushenv.identify.data import IdentificationError, Segment

VARIANCE_QUANTILE = 0.01  # the slowest 1 % of the displacement's variance
MIN_CYCLES = 4.0  # the cutoff leaves at least this many of its cycles in the longest record
FILTER_ORDER = 4


@dataclass(frozen=True)
class StaticEstimate:
    """F_s(x) = f0_n + k_n_per_m x, N; ``cutoff_hz`` of the slow content it came from,
    ``force_rms_n`` the RMS force of the records (a force scale for the training term)."""

    k_n_per_m: float
    f0_n: float
    cutoff_hz: float
    force_rms_n: float

    def force_n(self, x_m: np.ndarray) -> np.ndarray:
        return self.f0_n + self.k_n_per_m * np.asarray(x_m, dtype=np.float64)

    def as_dict(self) -> dict[str, float]:
        return {
            "k_n_per_m": self.k_n_per_m,
            "f0_n": self.f0_n,
            "cutoff_hz": self.cutoff_hz,
            "force_rms_n": self.force_rms_n,
        }


def slow_cutoff_hz(xs: Sequence[np.ndarray], dt: float) -> float:
    """Frequency, Hz, below which ``VARIANCE_QUANTILE`` of the displacements' variance lies
    (periodograms of every record summed), clipped to [MIN_CYCLES / longest, Nyquist / 4]."""
    if all(np.ptp(x) == 0.0 for x in xs):
        raise IdentificationError("the records' displacement is constant: no static stiffness")
    longest = max(x.size for x in xs)
    freq = np.fft.rfftfreq(longest, dt)
    power = np.zeros(freq.size)
    for x in xs:
        p = np.abs(np.fft.rfft(x - x.mean(), n=longest)) ** 2
        power += p
    power[0] = 0.0
    cum = np.cumsum(power)
    f_c = float(freq[np.searchsorted(cum, VARIANCE_QUANTILE * cum[-1])])
    return float(np.clip(f_c, MIN_CYCLES / (longest * dt), 0.25 * 0.5 / dt))


def static_estimate(
    segments: Sequence[Segment], lengths: Sequence[int], dt: float
) -> StaticEstimate:
    """The records' static estimate (module docstring) from the first ``lengths[r]`` samples of
    each record (their training parts). Refuses records whose slow force does not rise with
    the displacement (k_s <= 0): nothing to certify against."""
    xs = [s.x[:n] for s, n in zip(segments, lengths, strict=True)]
    fs = [s.f[:n] for s, n in zip(segments, lengths, strict=True)]
    f_c = slow_cutoff_hz(xs, dt)
    sos = butter(FILTER_ORDER, f_c, fs=1.0 / dt, output="sos")
    rows, rhs = [], []
    for x, f in zip(xs, fs, strict=True):
        pad = min(x.size - 1, 3 * (2 * len(sos) + 1))
        xl = sosfiltfilt(sos, x, padlen=pad)
        fl = sosfiltfilt(sos, f, padlen=pad)
        rows.append(np.c_[xl, np.gradient(xl, dt), np.ones_like(xl)])
        rhs.append(fl)
    a, b = np.concatenate(rows), np.concatenate(rhs)
    k, _, f0 = np.linalg.lstsq(a, b, rcond=None)[0]
    if not (np.isfinite(k) and k > 0):
        raise IdentificationError(
            f"the records' slow content (below {f_c:.3g} Hz) gives a static stiffness of "
            f"{k:.4g} N/m: the force does not rise with the displacement; a certified training "
            "needs records whose slow force follows the displacement"
        )
    rms = float(np.sqrt(np.mean(np.concatenate(fs) ** 2)))
    return StaticEstimate(float(k), float(f0), f_c, rms)
