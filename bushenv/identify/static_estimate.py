"""The static behaviour of a bushing of C coordinates estimated from its random-drive records.

Identification records are random drives: they never hold, so the force a bushing keeps at a
held deflection is not measured. Its best estimate from the records themselves is their
*slow content*: below the lowest frequencies of the drive the force follows the deflection
almost in phase, and the slope of that relation is the stiffness closest to static the records
can show. Over the records (their training parts), with q (T, C) and f (T, C) (C = 1: the
deflection along the axis),

1. the cutoff f_c is the frequency below which ``VARIANCE_QUANTILE`` of the deflections'
   variance lies (each coordinate normalised to unit RMS, so a rotation in rad weighs as much
   as a translation in m; at least ``MIN_CYCLES`` cycles per record and at most a quarter of
   Nyquist);
2. q and f are low-passed at f_c (4th-order Butterworth, forward and backward: no phase);
3. per force channel i, least squares f_lp,i = sum_j K_ij q_lp,j + sum_j C_ij v_lp,j + F0_i
   over every record's slow content.

The estimate is the diagonal line F_s,i(q) = F0_i + K_ii q_i, extrapolated linearly over the
whole stroke (C = 1: F_s(x) = F0 + k_s x). Only the slope can be estimated: at n = 1 the slow
content is a few hundredths of a millimetre (0.03 mm RMS below 2 Hz), too small to show a
curve, and the coupling's cross terms in the least squares are noise (36.7 kN/m
radial-from-axial on the three-axis reference's seed-0 record, where it has none at first
order). Rubber is stiffer at the drive's frequencies than in a hold (relaxation), stiffens at
large deflection (hardening) and, through friction, near rest: a rubber's static curve lies
about 0.8-1.3 times F_s beyond 1 mm and up to 1.8 times within 0.25 mm (the reference rubber:
docs/fit.md, tested in ``tests/identify/test_static_estimate.py``); the certified training
terms (``certified.py``, ``mimo_certified.py``) judge a model's held force in a band about F_s.

**The band** a held force must lie in (``StaticEstimate.band``): with the sign of F_s,i and
s_i = |F_s,i|,

    sign(F_s,i) f_i  in  [low s_i / (1 + c S_i) - floor_i,  high s_i (1 + c S_i) + floor_i]

S_i = sum_{j != i} |K_jj q_j| / rms_j is how far the *other* coordinates are held, in units of
their records' RMS force (0 for C = 1, where the band is [low s - floor, high s + floor]);
``c`` (``COUPLING``) lets coupling scale a coordinate's own force either way. The band is
multiplicative because a mirror-symmetric bushing's strain energy is even in each coordinate,
so its force f_i is odd in q_i: a coordinate held at rest carries no static force whatever the
others do, and must hold within +-floor_i (``FLOOR_FRACTION`` of its RMS force). ``COUPLING`` =
0.08 puts the three-axis reference rubber's held forces (1 s after a 20 ms ramp) at all 343
holds of a 7^3 grid over the rig3 box inside the default band (0.05 leaves 4 moments outside,
at a rotation of 0.015 rad under full radial preload; tested in ``tests/identify``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import butter, sosfiltfilt

from bushenv.errors import DIVERGENCE_RAISES
from bushenv.identify.data import IdentificationError
from bushenv.scales import STATIC_HOLD_S, STATIC_PROBE_M

VARIANCE_QUANTILE = 0.01  # the slowest 1 % of the deflections' variance
MIN_CYCLES = 4.0  # the cutoff leaves at least this many of its cycles in the longest record
FILTER_ORDER = 4
FLOOR_FRACTION = 0.01  # of a channel's RMS force: below it a held force has no sign
COUPLING = 0.08  # c of the band: how much the other coordinates' holds may scale a force
ONE_AXIS = ("deflection",)


@dataclass(frozen=True)
class StaticEstimate:
    """F_s,i(q) = f0_i + k_i q_i per coordinate (N or N m); ``k_matrix`` (C, C) the full slow
    least squares (its off-diagonal is reported, not used), ``force_rms`` (C,) the records' RMS
    force per channel, ``cutoff_hz`` of the slow content it came from."""

    k: np.ndarray
    f0: np.ndarray
    k_matrix: np.ndarray
    cutoff_hz: float
    force_rms: np.ndarray
    coords: tuple[str, ...] = ONE_AXIS

    def force(self, q: np.ndarray) -> np.ndarray:
        """The estimate at holds ``q``: (N, C) for (N, C); (N,) for (N,) when C = 1."""
        q = np.asarray(q, dtype=np.float64)
        if q.ndim == 1 and len(self.k) == 1:
            return self.f0[0] + q * self.k[0]
        return self.f0 + q * self.k

    def band(
        self, q: np.ndarray, low: float, high: float, coupling: float = COUPLING
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per hold and channel, shaped as ``q`` ((N, C), or (N,) when C = 1): the sign of
        F_s, the band's low and high ends along that sign, and the scale the distance outside
        is measured in (max(|F_s|, floor))."""
        q = np.asarray(q, dtype=np.float64)
        q2 = q.reshape(q.shape[0], -1)
        f_s = self.f0 + q2 * self.k
        size = np.abs(f_s)
        floor = FLOOR_FRACTION * self.force_rms
        own = np.abs(q2 * self.k) / self.force_rms
        others = own.sum(axis=1, keepdims=True) - own
        grow = 1.0 + coupling * others
        sign = np.where(f_s >= 0.0, 1.0, -1.0)
        out = (sign, low * size / grow - floor, high * size * grow + floor,
               np.maximum(size, floor))  # fmt: skip
        return tuple(a.reshape(q.shape) for a in out)

    def as_dict(self) -> dict:
        def per(a: np.ndarray) -> dict[str, float]:
            return dict(zip(self.coords, map(float, a), strict=True))

        return {
            "k": per(self.k),
            "f0": per(self.f0),
            "k_matrix": self.k_matrix.tolist(),
            "cutoff_hz": self.cutoff_hz,
            "force_rms": per(self.force_rms),
        }


def slow_cutoff_hz(xs: Sequence[np.ndarray], dt: float) -> float:
    """Frequency, Hz, below which ``VARIANCE_QUANTILE`` of the displacements' variance lies
    (periodograms of every signal summed), clipped to [MIN_CYCLES / longest, Nyquist / 4]."""
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
    histories: Sequence[tuple[np.ndarray, np.ndarray]],
    dt: float,
    coords: Sequence[str] | None = None,
) -> StaticEstimate:
    """The estimate (module docstring) from ``(q, f)`` records, (T,) each for one coordinate or
    (T, C) each for C (``coords`` names them in messages). Refuses records whose slow force
    does not rise with its own coordinate (K_ii <= 0): nothing to certify against."""
    qs = [np.asarray(q, dtype=np.float64) for q, _ in histories]
    qs = [q.reshape(q.shape[0], -1) for q in qs]
    fs = [np.asarray(f, dtype=np.float64).reshape(q.shape)
          for (_, f), q in zip(histories, qs, strict=True)]  # fmt: skip
    c = qs[0].shape[1]
    names = tuple(coords) if coords is not None else ONE_AXIS
    if len(names) != c:
        names = tuple(f"coordinate {i}" for i in range(c))
    spread = np.sqrt(np.mean(np.vstack(qs) ** 2, axis=0))
    if np.any(spread == 0.0):
        bad = names[int(np.argmin(spread))]
        what = "displacement" if c == 1 else f"{bad} coordinate"
        raise IdentificationError(f"the records' {what} is constant: no static stiffness")
    f_c = slow_cutoff_hz([q[:, j] / spread[j] for q in qs for j in range(c)], dt)
    sos = butter(FILTER_ORDER, f_c, fs=1.0 / dt, output="sos")
    rows, rhs = [], []
    for q, f in zip(qs, fs, strict=True):
        pad = min(q.shape[0] - 1, 3 * (2 * len(sos) + 1))
        ql = sosfiltfilt(sos, q, axis=0, padlen=pad)
        rows.append(np.c_[ql, np.gradient(ql, dt, axis=0), np.ones(q.shape[0])])
        rhs.append(sosfiltfilt(sos, f, axis=0, padlen=pad))
    sol = np.linalg.lstsq(np.vstack(rows), np.vstack(rhs), rcond=None)[0]
    k_matrix, f0 = sol[:c].T, sol[2 * c]
    k = np.diag(k_matrix).copy()
    if not np.all(np.isfinite(k) & (k > 0)):
        i = int(np.argmin(np.where(np.isfinite(k), k, -np.inf)))
        what = "stiffness" if c == 1 else f"{names[i]} stiffness"
        raise IdentificationError(
            f"the records' slow content (below {f_c:.3g} Hz) gives a static {what} of "
            f"{k[i]:.4g}: the force does not rise with the deflection; a certified training "
            "needs records whose slow force follows each coordinate"
        )
    rms = np.sqrt(np.mean(np.vstack(fs) ** 2, axis=0))
    return StaticEstimate(k, f0, k_matrix, f_c, np.maximum(rms, 1e-12), names)


# the rotation's probe: the one-axis probe at this lever arm, m
STIFFNESS_LEVER_M = 0.04


def coordinate_stiffness(model) -> np.ndarray:
    """(C,) secant static stiffness per coordinate (N/m, or N m/rad for a rotation): each alone
    ramped in 0.2 s to +-the probe (``scales.STATIC_PROBE_M``; a rotation the same at the
    lever ``STIFFNESS_LEVER_M``) and held ``STATIC_HOLD_S`` (``scales.static_force``'s hold),
    the others at rest; NaN where the model is not finite."""
    dt, c = model.dt, model.n_coords
    units = getattr(model, "units", ("m",) * c)
    probe = np.array([STATIC_PROBE_M / (STIFFNESS_LEVER_M if u == "rad" else 1.0) for u in units])
    n_ramp, n_hold = max(2, int(round(0.2 / dt))), int(round(STATIC_HOLD_S / dt))
    shape = np.concatenate([np.linspace(0.0, 1.0, n_ramp), np.ones(n_hold)])
    q = np.zeros((shape.size, 2 * c, c))
    for i in range(c):
        q[:, 2 * i, i] = shape * probe[i]
        q[:, 2 * i + 1, i] = -shape * probe[i]
    try:
        f = model.copy().simulate(q if c > 1 else q[..., 0])[-1].reshape(2 * c, c)
    except DIVERGENCE_RAISES:
        return np.full(c, np.nan)
    return np.array([(f[2 * i, i] - f[2 * i + 1, i]) / (2 * probe[i]) for i in range(c)])
