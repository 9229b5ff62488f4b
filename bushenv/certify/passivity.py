"""Small-signal passivity as a matrix test on the dynamic stiffness K(jw) (C x C,
``stiffness``); for one coordinate the test is Im K >= 0.

**Derivation.** About a held deflection q0 let the model's small-signal response to
q = q0 + Re(X e^{jwt}) (X in C^C) be f = f0 + Re(K X e^{jwt}). The mean power flowing into the
element is the mean of f^T dq/dt; for phasors, mean(Re(a e^{jwt}) Re(b e^{jwt})) = Re(a^H b) / 2
elementwise, so

    P = Re((jw X)^H K X) / 2 = (w / 2) Re(-j X^H K X) = (w / 2) Im(X^H K X).

Split K = H_R + j H_I with the two Hermitian matrices H_R = (K + K^H) / 2 and
H_I = (K - K^H) / (2j); then X^H K X = X^H H_R X + j X^H H_I X with both quadratic forms real,
so the work done on the element over one cycle is

    W = 2 pi P / w = pi X^H H_I X.

The element takes energy from every small motion at w (passive) iff H_I(w) is positive
semidefinite; where an eigenvalue of H_I is negative, the motion along its eigenvector (an
elliptic orbit when the eigenvector is complex) *gives* energy back each cycle: the model
generates energy. For one coordinate H_I = Im K and W = pi A^2 Im K (for sampled motion judged
with the trapezoidal rule of ``divergence.cumulative_work``: that times sinc(w T), same sign).
For K = K0 + jw C with real K0, C: H_I = w (C + C^T) / 2 - j (K0 - K0^T) / 2, so a linear element
is passive iff the symmetric part of C is PSD and K0 is symmetric (a circulatory, non-symmetric
stiffness does net work on a closed orbit).

Units and scaling. q may mix m and rad, so the eigenvalues of H_I depend on units (their signs,
by Sylvester's law of inertia, do not). Reported are the eigenvalues of D H_I D with
D = diag(amplitudes), by default the papers' n = 1 peaks (2 mm per translation, 0.05 rad per
rotation, ``AMPLITUDES``): lambda is the work per cycle / pi, in J, on the worst unit-norm
combination of those amplitudes. A sampled model fed the central difference has
Im V = sin(wT) / T for w.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bushenv.certify.network import CertifyError, narx_net
from bushenv.certify.stiffness import dynamic_stiffness, linear_stiffness, sine_stiffness

AMPLITUDES = {"m": 2e-3, "rad": 0.05}  # D: the papers' n = 1 peaks, per unit of a coordinate
SINE_FRACTION = 0.02  # sines measuring K: this fraction of the amplitudes, small signal


def amplitudes(units: tuple[str, ...]) -> np.ndarray:
    """(C,) the scaling amplitudes D of coordinates in ``units``."""
    return np.array([AMPLITUDES[u] for u in units])


def negative_bands(freq_hz: np.ndarray, values: np.ndarray) -> list[tuple[float, float]]:
    """Intervals of ``freq_hz`` (F,) ascending where ``values`` (F,) < 0, edges found by linear
    interpolation of the zero crossings; an interval open at a grid end stops there."""
    f, v = np.asarray(freq_hz, dtype=np.float64), np.asarray(values, dtype=np.float64)
    neg = np.concatenate([[False], v < 0, [False]]).astype(np.int8)
    starts = np.flatnonzero(np.diff(neg) == 1)  # first negative index of each run
    ends = np.flatnonzero(np.diff(neg) == -1) - 1  # last negative index
    bands = []
    for k, j in zip(starts, ends, strict=True):
        lo = f[k] if k == 0 else f[k - 1] + (f[k] - f[k - 1]) * v[k - 1] / (v[k - 1] - v[k])
        hi = f[j] if j == f.size - 1 else f[j] + (f[j + 1] - f[j]) * v[j] / (v[j] - v[j + 1])
        bands.append((float(lo), float(hi)))
    return bands


def loss_matrix(k: np.ndarray) -> np.ndarray:
    """H_I = (K - K^H) / (2j) of complex K (..., C, C): Hermitian; work per cycle pi X^H H_I X."""
    k = np.asarray(k, dtype=complex)
    return (k - np.conj(np.swapaxes(k, -1, -2))) / 2j


def loss_eigenvalues(k: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """(..., C) ascending eigenvalues of D H_I D, J (work per cycle / pi), D = diag(scale)."""
    d = np.asarray(scale, dtype=np.float64)
    return np.linalg.eigvalsh(loss_matrix(k) * d[:, None] * d[None, :])


@dataclass
class PassivityReport:
    """Per hold (and per stable fixed point for networks) the loss eigenvalues over frequency.

    ``q`` (P, C) the hold of each row; ``eig`` (P, F, C) eigenvalues of D H_I D, J;
    ``freq_hz`` (F,); ``method``: "analytic", "linearised" or "sines"; ``no_stable``: holds
    (M, C) where a network has no stable fixed point (no steady state to judge).
    """

    model: str
    method: str
    freq_hz: np.ndarray
    q: np.ndarray
    eig: np.ndarray
    no_stable: np.ndarray = field(default_factory=lambda: np.zeros((0, 1)))

    @property
    def min_eig(self) -> float:
        """The least eigenvalue over every frequency and hold, J."""
        return float(self.eig[..., 0].min()) if self.eig.size else float("nan")

    def active_bands(self) -> list[tuple[int, list[tuple[float, float]]]]:
        """(row, bands in Hz) of every row where the least eigenvalue goes below zero."""
        out = []
        for p in range(len(self.q)):
            bands = negative_bands(self.freq_hz, self.eig[p, :, 0])
            if bands:
                out.append((p, bands))
        return out

    @property
    def passive(self) -> bool:
        return not self.active_bands()


def passivity(model, q0, freq_hz: np.ndarray, velocity: str = "central") -> PassivityReport:
    """The passivity report of ``model`` (any bushing model of C coordinates) at the holds
    ``q0`` (M, C) over ``freq_hz`` (F,): analytic for a linear model, linearised about every
    stable fixed point for a NARX network, by sines (``SINE_FRACTION`` of the amplitudes) for
    any other."""
    from bushenv.certify.fixed_points import fixed_points
    from bushenv.models.linear import LinearBushing
    from bushenv.models.planar_linear import PlanarLinear

    dim = model.n_coords
    q0 = np.asarray(q0, dtype=np.float64).reshape(-1, dim)
    freq_hz = np.atleast_1d(np.asarray(freq_hz, dtype=np.float64))
    if np.any(freq_hz <= 0) or np.any(freq_hz >= 0.5 / model.dt):
        raise CertifyError(f"frequencies must lie in (0, {0.5 / model.dt:g}) Hz (Nyquist)")
    d = amplitudes(tuple(model.units))
    if isinstance(model, LinearBushing | PlanarLinear):
        k = np.broadcast_to(linear_stiffness(model, freq_hz), (len(q0), freq_hz.size, dim, dim))
        return PassivityReport(model.name, "analytic", freq_hz, q0, loss_eigenvalues(k, d))
    try:
        net = narx_net(model)
    except CertifyError:
        k = sine_stiffness(model, q0, freq_hz, SINE_FRACTION * d, velocity)
        return PassivityReport(model.name, "sines", freq_hz, q0, loss_eigenvalues(k, d))
    fp = fixed_points(net, q0)
    keep = fp.stable
    k = dynamic_stiffness(net, fp.q[fp.hold[keep]], fp.y[keep], freq_hz, velocity)
    return PassivityReport(
        model.name,
        "linearised",
        freq_hz,
        fp.q[fp.hold[keep]],
        loss_eigenvalues(k, d),
        q0[fp.stable_count == 0],
    )
