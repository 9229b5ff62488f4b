"""ISO 2631-1 frequency weightings Wk and Wd, applied to acceleration histories, and a_w.

ISO 2631-1:1997, Annex A (A.2, Table A.1 holds the parameters): each weighting is the product
of a band limit, an acceleration-velocity transition and an upward step, with s = j 2 pi f,
omega_i = 2 pi f_i:

- band limit, high pass: ``s^2 / (s^2 + omega_1 s / Q_1 + omega_1^2)``, Q_1 = 1/sqrt(2)
- band limit, low pass: ``omega_2^2 / (s^2 + omega_2 s / Q_1 + omega_2^2)``
- a-v transition: ``(1 + s / omega_3) / (1 + s / (Q_4 omega_4) + s^2 / omega_4^2)``
- upward step: ``(s^2 + omega_5 s / Q_5 + omega_5^2) / (s^2 + omega_6 s / Q_6 + omega_6^2)``,
  (f5 / f6)^2 = 1/2 below f5 rising to 1 above f6 (absent for Wd)
- gain K (1 for both)

| weighting | axis       | f1 Hz | f2 Hz | f3 Hz | f4 Hz | Q4   | f5 Hz | Q5   | f6 Hz | Q6   |
|-----------|------------|-------|-------|-------|-------|------|-------|------|-------|------|
| Wk        | z, seated  | 0.4   | 100   | 12.5  | 12.5  | 0.63 | 2.37  | 0.91 | 3.35  | 0.91 |
| Wd        | x, y       | 0.4   | 100   | 2.0   | 2.0   | 0.63 | -     | -    | -     | -    |

``weighting_response`` evaluates the product at given frequencies; ``weighted_acceleration``
applies it to a (T,) or (T, B) history in the frequency domain (the analogue response
multiplied on the DFT of the zero-padded record: no bilinear warping near Nyquist, and the
padding to at least twice the length plus 20 s keeps the 0.4 Hz high pass from wrapping
around); ``weighted_rms`` is a_w of ISO 2631-1 §6.4.1, eq. (1), over the whole record.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bushenv.vehicle.checks import VehicleInputError, positive

__all__ = [
    "WEIGHTINGS",
    "WeightingParams",
    "vibration_dose_value",
    "weighted_acceleration",
    "weighted_rms",
    "weighting_response",
]


@dataclass(frozen=True)
class WeightingParams:
    """One ISO 2631-1 weighting's filter parameters (ISO 2631-1:1997 Table A.1); Hz."""

    f1_hz: float  # band limit, high pass corner
    f2_hz: float  # band limit, low pass corner
    f3_hz: float  # a-v transition zero (inf: none)
    f4_hz: float  # a-v transition pole pair
    q4: float
    f5_hz: float = math.inf  # upward step zero pair (inf: no step)
    q5: float = 1.0
    f6_hz: float = math.inf  # upward step pole pair
    q6: float = 1.0
    gain: float = 1.0


WEIGHTINGS = {
    "Wk": WeightingParams(0.4, 100.0, 12.5, 12.5, 0.63, 2.37, 0.91, 3.35, 0.91),
    "Wd": WeightingParams(0.4, 100.0, 2.0, 2.0, 0.63),
}
_Q1 = 1.0 / math.sqrt(2.0)  # Butterworth band limits
_PAD_S = 20.0  # the 0.4 Hz high pass rings for a few seconds; padding beyond that stops wrap


def _params(weighting: str | WeightingParams) -> WeightingParams:
    if isinstance(weighting, WeightingParams):
        return weighting
    if weighting not in WEIGHTINGS:
        raise VehicleInputError(
            f"weighting={weighting!r} is not known; known: {', '.join(WEIGHTINGS)}"
        )
    return WEIGHTINGS[weighting]


def weighting_response(f_hz: np.ndarray, weighting: str | WeightingParams) -> np.ndarray:
    """Complex frequency response of an ISO 2631-1 weighting at ``f_hz`` (Hz, >= 0).

    Parameters
    ----------
    f_hz : array_like
        Frequencies in Hz.
    weighting : {"Wk", "Wd"} or WeightingParams

    Returns
    -------
    ndarray
        Complex response, the shape of ``f_hz``; its modulus is the weighting factor the
        standard tabulates (ISO 2631-1:1997 Table 3, there x 1000).

    Examples
    --------
    >>> round(float(abs(weighting_response(5.0, "Wk"))), 3)
    1.039
    """
    p = _params(weighting)
    f = np.asarray(f_hz, dtype=float)
    if np.any(~np.isfinite(f)) or np.any(f < 0):
        raise VehicleInputError("f_hz must be finite and >= 0")
    s = 2j * np.pi * f
    w1, w2, w3, w4 = (2 * np.pi * x for x in (p.f1_hz, p.f2_hz, p.f3_hz, p.f4_hz))
    high = s**2 / (s**2 + w1 * s / _Q1 + w1**2)
    low = w2**2 / (s**2 + w2 * s / _Q1 + w2**2)
    transition = (1 + s / w3) / (1 + s / (p.q4 * w4) + (s / w4) ** 2)
    h = p.gain * high * low * transition
    if math.isfinite(p.f5_hz):
        w5, w6 = 2 * np.pi * p.f5_hz, 2 * np.pi * p.f6_hz
        h = h * (s**2 + w5 * s / p.q5 + w5**2) / (s**2 + w6 * s / p.q6 + w6**2)
    return h


def weighted_acceleration(
    acceleration_m_per_s2: np.ndarray, dt_s: float, weighting: str | WeightingParams
) -> np.ndarray:
    """The frequency-weighted acceleration history a_w(t), same shape and units as the input.

    Parameters
    ----------
    acceleration_m_per_s2 : ndarray
        (T,) or (T, B) acceleration in m/s^2, time-major.
    dt_s : float
        Sample time in s.
    weighting : {"Wk", "Wd"} or WeightingParams

    Returns
    -------
    ndarray
        The weighted history: the input's DFT (zero-padded to at least 2 T samples plus 20 s)
        times ``weighting_response``, transformed back and cut to T samples.
    """
    dt_s = positive("dt_s", dt_s)
    a = np.asarray(acceleration_m_per_s2, dtype=float)
    if a.ndim not in (1, 2) or a.shape[0] < 2:
        raise VehicleInputError(
            f"acceleration_m_per_s2 must be (T,) or (T, B) with T >= 2, got shape {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise VehicleInputError("acceleration_m_per_s2 holds a sample that is not finite")
    count = a.shape[0]
    padded = 1 << int(math.ceil(math.log2(2 * count + _PAD_S / dt_s)))
    h = weighting_response(np.fft.rfftfreq(padded, dt_s), weighting)
    spectrum = np.fft.rfft(a, n=padded, axis=0)
    shape = (-1,) + (1,) * (a.ndim - 1)
    return np.fft.irfft(spectrum * h.reshape(shape), n=padded, axis=0)[:count]


def weighted_rms(
    acceleration_m_per_s2: np.ndarray, dt_s: float, weighting: str | WeightingParams
) -> np.ndarray | float:
    """a_w: the RMS of the weighted acceleration over the record (ISO 2631-1 §6.4.1, eq. 1).

    Returns a float for a (T,) input, a (B,) array for (T, B); m/s^2.

    Examples
    --------
    >>> t = np.arange(0, 60, 0.001)
    >>> round(float(weighted_rms(np.sqrt(2) * np.sin(2 * np.pi * 1.0 * t), 0.001, "Wd")), 3)
    1.009
    """
    aw = weighted_acceleration(acceleration_m_per_s2, dt_s, weighting)
    out = np.sqrt(np.mean(aw**2, axis=0))
    return float(out) if out.ndim == 0 else out


def vibration_dose_value(
    acceleration_m_per_s2: np.ndarray, dt_s: float, weighting: str | WeightingParams
) -> np.ndarray | float:
    """VDV = (integral of a_w^4 dt)^(1/4) in m/s^1.75 (ISO 2631-1 §6.3.2, eq. 5).

    The fourth-power dose the standard adds where the crest factor exceeds 9 (shocks: the
    pothole and the bump). Same shapes as ``weighted_rms``.
    """
    aw = weighted_acceleration(acceleration_m_per_s2, dt_s, weighting)
    out = (np.sum(aw**4, axis=0) * dt_s) ** 0.25
    return float(out) if out.ndim == 0 else out
