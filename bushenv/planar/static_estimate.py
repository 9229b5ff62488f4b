"""The static behaviour of a planar bushing estimated from its random-drive records, per coordinate.

The one-axis estimate (``bushenv.identify.static_estimate``) in three coordinates: one cutoff
f_c below which ``VARIANCE_QUANTILE`` of the displacements' variance lies (each coordinate
normalised to unit RMS, so a rotation in rad weighs as much as a translation in m), q and f
low-passed at f_c, and per force channel i least squares f_lp,i = sum_j K_ij q_lp,j + sum_j
C_ij v_lp,j + F0_i. The estimate is the diagonal line F_s,i(q) = F0_i + K_ii q_i: the slow
content of an n = 1 random drive (tens of micrometres) shows the slopes, not the coupling,
whose cross terms in the least squares are noise (36.7 kN/m radial-from-axial on the
reference's seed-0 record, where the reference has none at first order).

**The band** a held force must lie in (``band``): with the sign of F_s,i and s_i = |F_s,i|,

    sign(F_s,i) f_i  in  [low s_i / (1 + c S_i) - floor_i,  high s_i (1 + c S_i) + floor_i]

S_i = sum_{j != i} |K_jj q_j| / rms_j is how far the *other* coordinates are held, in units of
their records' RMS force; ``c`` (``COUPLING``) lets coupling scale a coordinate's own force
either way. The band is multiplicative because a mirror-symmetric bushing's strain energy is
even in each coordinate, so its force f_i is odd in q_i: a coordinate held at rest carries no
static force whatever the others do (the reference's coupling: radial deflection stiffens axial
shear, rotation softens then stiffens radial). So a coordinate at rest must hold within
+-floor_i (1 % of its RMS force), and the cross-force a network invents there is penalised.
``COUPLING`` = 0.08 puts the reference rubber's held forces (1 s after a 20 ms ramp) at all
343 holds of a 7^3 grid over the rig3 box inside the default band (0.05 leaves 4 moments
outside, at a rotation of 0.015 rad under full radial preload, where the moment falls to 0.45
of the estimate; tested in ``tests/planar/test_certified.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import butter, sosfiltfilt

from bushenv.errors import DIVERGENCE_RAISES
from bushenv.identify.static_estimate import FILTER_ORDER, slow_cutoff_hz
from bushenv.models.planar_base import COORDS, PlanarModelError
from bushenv.scales import STATIC_HOLD_S, STATIC_PROBE_M

FLOOR_FRACTION = 0.01  # of a channel's RMS force: below it a held force has no sign
COUPLING = 0.08  # c of the band: how much the other coordinates' holds may scale a force


@dataclass(frozen=True)
class PlanarStaticEstimate:
    """F_s,i(q) = f0_i + k_i q_i (N, N, N m); ``k_matrix`` the full slow least squares (its
    off-diagonal is reported, not used), ``force_rms`` (3,) the records' RMS force per channel."""

    k: np.ndarray
    f0: np.ndarray
    k_matrix: np.ndarray
    cutoff_hz: float
    force_rms: np.ndarray

    def force(self, q: np.ndarray) -> np.ndarray:
        """(N, 3) the estimate at holds ``q`` (N, 3)."""
        return self.f0 + np.asarray(q, dtype=np.float64) * self.k

    def band(
        self, q: np.ndarray, low: float, high: float, coupling: float = COUPLING
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per hold and channel (N, 3): the sign of F_s, the band's low and high ends along
        that sign, and the scale the distance outside is measured in (max(|F_s|, floor))."""
        f_s = self.force(q)
        size = np.abs(f_s)
        floor = FLOOR_FRACTION * self.force_rms
        own = np.abs(np.asarray(q) * self.k) / self.force_rms
        others = own.sum(axis=1, keepdims=True) - own
        grow = 1.0 + coupling * others
        sign = np.where(f_s >= 0.0, 1.0, -1.0)
        return sign, low * size / grow - floor, high * size * grow + floor, np.maximum(size, floor)

    def as_dict(self) -> dict:
        return {
            "k": dict(zip(COORDS, map(float, self.k), strict=True)),
            "f0": dict(zip(COORDS, map(float, self.f0), strict=True)),
            "k_matrix": self.k_matrix.tolist(),
            "cutoff_hz": self.cutoff_hz,
            "force_rms": dict(zip(COORDS, map(float, self.force_rms), strict=True)),
        }


def planar_static_estimate(
    histories: Sequence[tuple[np.ndarray, np.ndarray]], dt: float
) -> PlanarStaticEstimate:
    """The estimate (module docstring) from ``(q (T, 3), f (T, 3))`` records. Refuses records
    whose slow force does not rise with its own coordinate (K_ii <= 0)."""
    qs = [np.asarray(q, dtype=np.float64) for q, _ in histories]
    fs = [np.asarray(f, dtype=np.float64) for _, f in histories]
    spread = np.sqrt(np.mean(np.vstack(qs) ** 2, axis=0))
    if np.any(spread == 0.0):
        bad = COORDS[int(np.argmin(spread))]
        raise PlanarModelError(f"the records' {bad} coordinate is constant: no static stiffness")
    f_c = slow_cutoff_hz([q[:, j] / spread[j] for q in qs for j in range(3)], dt)
    sos = butter(FILTER_ORDER, f_c, fs=1.0 / dt, output="sos")
    rows, rhs = [], []
    for q, f in zip(qs, fs, strict=True):
        pad = min(q.shape[0] - 1, 3 * (2 * len(sos) + 1))
        ql = sosfiltfilt(sos, q, axis=0, padlen=pad)
        rows.append(np.c_[ql, np.gradient(ql, dt, axis=0), np.ones(q.shape[0])])
        rhs.append(sosfiltfilt(sos, f, axis=0, padlen=pad))
    sol = np.linalg.lstsq(np.vstack(rows), np.vstack(rhs), rcond=None)[0]
    k_matrix, f0 = sol[:3].T, sol[6]
    k = np.diag(k_matrix).copy()
    if not np.all(np.isfinite(k) & (k > 0)):
        i = int(np.argmin(np.where(np.isfinite(k), k, -np.inf)))
        raise PlanarModelError(
            f"the records' slow content (below {f_c:.3g} Hz) gives a static {COORDS[i]} stiffness "
            f"of {k[i]:.4g}: the force does not rise with the deflection; certified training needs "
            "records whose slow force follows each coordinate"
        )
    rms = np.sqrt(np.mean(np.vstack(fs) ** 2, axis=0))
    return PlanarStaticEstimate(k, f0, k_matrix, f_c, np.maximum(rms, 1e-12))


# the rotation's probe: the one-axis probe at this lever arm, m
STIFFNESS_LEVER_M = 0.04
# holds of the static stiffness per coordinate: the one-axis probe, the rotation at the lever arm
STIFFNESS_PROBE = np.array([STATIC_PROBE_M, STATIC_PROBE_M, STATIC_PROBE_M / STIFFNESS_LEVER_M])


def static_stiffness3(model) -> np.ndarray:
    """(3,) secant static stiffness per coordinate (N/m, N/m, N m/rad): each alone ramped in
    0.2 s to +-``STIFFNESS_PROBE`` and held ``STATIC_HOLD_S`` (``scales.static_force``'s hold),
    the others at rest; NaN where the model is not finite."""
    dt = model.dt
    n_ramp, n_hold = max(2, int(round(0.2 / dt))), int(round(STATIC_HOLD_S / dt))
    shape = np.concatenate([np.linspace(0.0, 1.0, n_ramp), np.ones(n_hold)])
    q = np.zeros((shape.size, 6, 3))
    for i in range(3):
        q[:, 2 * i, i] = shape * STIFFNESS_PROBE[i]
        q[:, 2 * i + 1, i] = -shape * STIFFNESS_PROBE[i]
    try:
        f = model.copy().simulate(q)[-1]
    except DIVERGENCE_RAISES:
        return np.full(3, np.nan)
    return np.array([(f[2 * i, i] - f[2 * i + 1, i]) / (2 * STIFFNESS_PROBE[i]) for i in range(3)])
