"""Passivity of a planar model as a matrix test on its dynamic stiffness K(jw) (3 x 3).

**Derivation.** About a held deflection vector q0 let the model's small-signal response to
q = q0 + Re(X e^{jwt}) (X in C^3) be f = f0 + Re(K X e^{jwt}), K = K(jw) complex 3 x 3. The
mean power flowing into the element is the mean of f^T dq/dt; for phasors, mean(Re(a e^{jwt})
Re(b e^{jwt})) = Re(a^H b) / 2 elementwise, so

    P = Re((jw X)^H K X) / 2 = (w / 2) Re(-j X^H K X) = (w / 2) Im(X^H K X).

Split K = H_R + j H_I with the two Hermitian matrices H_R = (K + K^H) / 2 and
H_I = (K - K^H) / (2j); then X^H K X = X^H H_R X + j X^H H_I X with both quadratic forms real,
so the work done on the element over one cycle is

    W = 2 pi P / w = pi X^H H_I X.

The element takes energy from every small motion at w (passive) iff H_I(w) is positive
semidefinite; where an eigenvalue of H_I is negative, the motion along its eigenvector (an
elliptic orbit when the eigenvector is complex) *gives* energy back each cycle: the model
generates energy. For K = K0 + jw C with real K0, C: H_I = w (C + C^T) / 2 - j (K0 - K0^T) / 2,
so a linear element is passive iff the symmetric part of C is PSD and K0 is symmetric (a
circulatory, non-symmetric stiffness does net work on a closed orbit; at low w it dominates).

Units and scaling. q mixes m and rad, so the eigenvalues of H_I depend on units (their signs,
by Sylvester's law of inertia, do not). Reported are the eigenvalues of D H_I D with
D = diag(``AMPLITUDES``), the papers' n = 1 peaks (2 mm, 2 mm, 0.05 rad): lambda is the work per
cycle / pi, in J, on the worst unit-norm combination of those amplitudes.

Sampled models: the velocity the model is fed is the central difference (``simulate``),
V(z) = (z - 1/z) / (2T), Im V = sin(wT) / T: a linear model's H_I carries sin(wT)/T for w.

K(jw) is obtained three ways: analytically for ``linear``; for the networks by linearising the
held recurrence about each stable fixed point (``fixed_points``): with the lag matrices A_l,
B_l, K(z) = F_s (I - sum_l A_l z^-l)^-1 (sum_l B_l z^-l) Q^-1 + K_b + C_b V(z); for any model
by sines about the hold (``sine_stiffness``: one coordinate at a time, each force's phasor
fitted by least squares), which is how the reference is measured.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bushenv.certify.passivity import negative_bands
from bushenv.models.planar_base import PlanarModel, PlanarModelError
from bushenv.models.planar_linear import PlanarLinear
from bushenv.models.planar_narx import PlanarNarx
from bushenv.planar.fixed_points import HeldNetwork, fixed_points

AMPLITUDES = np.array([2e-3, 2e-3, 0.05])  # D: n = 1 peaks, m, m, rad
RAMP_S = 0.5  # half-cosine ramp to the hold
SETTLE_S = 5.0  # hold before the sine (relaxation, friction settle)
SKIP_S = 3.0  # start of each sine left out of the fit (start-up transient)
FIT_S = 3.0  # fitted part of the sine, at least; longer for FIT_CYCLES of the lowest frequency
FIT_CYCLES = 4.0
SINE_FRACTION = 0.02  # sine amplitude as a fraction of AMPLITUDES: small signal


def loss_matrix(k: np.ndarray) -> np.ndarray:
    """H_I = (K - K^H) / (2j) of complex K (..., 3, 3): Hermitian; work per cycle pi X^H H_I X."""
    k = np.asarray(k, dtype=complex)
    return (k - np.conj(np.swapaxes(k, -1, -2))) / 2j


def loss_eigenvalues(k: np.ndarray, amplitudes: np.ndarray = AMPLITUDES) -> np.ndarray:
    """(..., 3) ascending eigenvalues of D H_I D, J (work per cycle / pi), D = diag(amplitudes)."""
    d = np.asarray(amplitudes, dtype=np.float64)
    return np.linalg.eigvalsh(loss_matrix(k) * d[:, None] * d[None, :])


def central_velocity(freq_hz: np.ndarray, dt: float) -> np.ndarray:
    """(F,) V(z) of the central difference, (z - 1/z) / (2T) = j sin(wT) / T."""
    return 1j * np.sin(2 * np.pi * np.asarray(freq_hz, dtype=np.float64) * dt) / dt


def linear_stiffness(model: PlanarLinear, freq_hz: np.ndarray) -> np.ndarray:
    """(F, 3, 3) K = K0 + C V(z) of a ``linear`` model (any hold: it is linear)."""
    v = central_velocity(freq_hz, model.dt)
    return model.k_matrix[None] + v[:, None, None] * model.c_matrix[None]


def network_stiffness(
    model: PlanarNarx, q: np.ndarray, y: np.ndarray, freq_hz: np.ndarray
) -> np.ndarray:
    """(P, F, 3, 3) K(z) of a planar network linearised about fixed points (q (P, 3), y (P, 3))."""
    net = HeldNetwork.of(model)
    q, y = np.atleast_2d(q), np.atleast_2d(y)
    a, b = net.lag_matrices(net.held(q), y)  # (P, 5, 3, 3), (P, 6, 3, 3)
    zinv = np.exp(-2j * np.pi * np.asarray(freq_hz, dtype=np.float64) * net.dt)  # (F,)
    pa = zinv[:, None] ** np.arange(1, a.shape[1] + 1)[None, :]  # (F, 5)
    pb = zinv[:, None] ** np.arange(b.shape[1])[None, :]  # (F, 6)
    den = np.eye(3) - np.einsum("fl,plij->pfij", pa, a)
    num = np.einsum("fl,plij->pfij", pb, b) / net.q_scale  # d(qs)/dq = 1 / q_scale
    k = net.f_scale[:, None] * np.linalg.solve(den, num)
    v = central_velocity(freq_hz, net.dt)
    return k + net.k + v[None, :, None, None] * net.c


def _sine_profiles(q0: np.ndarray, freq_hz: np.ndarray, amp: np.ndarray, dt: float):
    """(T, M F 3, 3): ramp to each hold, settle, then a sine on one coordinate at a time."""
    t_r = np.arange(int(round(RAMP_S / dt))) * dt
    ramp = 0.5 * (1 - np.cos(np.pi * t_r / RAMP_S))
    n_hold = int(round(SETTLE_S / dt))
    head = np.concatenate([ramp, np.ones(n_hold)])[:, None] * 1.0  # (Th, 1)
    sine_s = SKIP_S + max(FIT_S, FIT_CYCLES / float(np.min(freq_hz)))
    t = np.arange(int(round(sine_s / dt))) * dt
    sines = np.sin(2 * np.pi * np.outer(t, freq_hz))  # (Ts, F)
    M, F = len(q0), len(freq_hz)
    q = np.empty((len(head) + len(t), M, F, 3, 3))
    q[:] = q0[None, :, None, None, :]
    q[: len(head)] *= head[:, :, None, None, None]
    for j in range(3):
        q[len(head) :, :, :, j, j] += amp[j] * sines[:, None, :]
    return q.reshape(q.shape[0], M * F * 3, 3), len(head), t


def sine_stiffness(model: PlanarModel, q0: np.ndarray, freq_hz: np.ndarray) -> np.ndarray:
    """(M, F, 3, 3) K measured on any planar model by sines about each hold of ``q0`` (M, 3).

    Column j: a sine of ``SINE_FRACTION`` of ``AMPLITUDES[j]`` on coordinate j alone after a
    ramp and a ``SETTLE_S`` hold; each force fitted on the sine after its first ``SKIP_S`` (at
    least ``FIT_S`` and ``FIT_CYCLES`` periods of the lowest frequency) as
    p sin + q cos + r + s t (the trend absorbs a slow relaxation still going on); K_ij =
    (p + j q) / amplitude_j.
    """
    q0 = np.atleast_2d(np.asarray(q0, dtype=np.float64))
    freq_hz = np.atleast_1d(np.asarray(freq_hz, dtype=np.float64))
    amp = SINE_FRACTION * AMPLITUDES
    q, k0, t = _sine_profiles(q0, freq_hz, amp, model.dt)
    f = model.copy().simulate(np.ascontiguousarray(q))  # (T, M F 3, 3)
    M, F = len(q0), len(freq_hz)
    sel = slice(int(round(SKIP_S / model.dt)), len(t) - 1)  # last sample: one-sided velocity
    ts = t[sel]
    fs = f[k0:][sel].reshape(len(ts), M, F, 3, 3)  # (N, hold, freq, driven j, force i)
    k = np.empty((M, F, 3, 3), dtype=complex)
    for fi, w in enumerate(2 * np.pi * freq_hz):
        basis = np.stack([np.sin(w * ts), np.cos(w * ts), np.ones_like(ts), ts - ts.mean()], 1)
        coef, *_ = np.linalg.lstsq(basis, fs[:, :, fi].reshape(len(ts), -1), rcond=None)
        ph = (coef[0] + 1j * coef[1]).reshape(M, 3, 3)  # (hold, driven j, force i)
        k[:, fi] = np.swapaxes(ph, -1, -2) / amp[None, None, :]
    return k


@dataclass
class PassivityReport:
    """Per hold (and per stable fixed point for networks) the loss eigenvalues over frequency.

    ``q`` (P, 3) the hold of each row; ``eig`` (P, F, 3) eigenvalues of D H_I D, J;
    ``freq_hz`` (F,); ``method``: "analytic", "linearised" or "sines"; ``no_stable``: holds
    (M, 3) where a network has no stable fixed point (no steady state to judge).
    """

    model: str
    method: str
    freq_hz: np.ndarray
    q: np.ndarray
    eig: np.ndarray
    no_stable: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

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


def passivity(model: PlanarModel, q0: np.ndarray, freq_hz: np.ndarray) -> PassivityReport:
    """The passivity report of ``model`` at the holds ``q0`` (M, 3) over ``freq_hz`` (F,)."""
    q0 = np.atleast_2d(np.asarray(q0, dtype=np.float64))
    freq_hz = np.atleast_1d(np.asarray(freq_hz, dtype=np.float64))
    if np.any(freq_hz <= 0) or np.any(freq_hz >= 0.5 / model.dt):
        raise PlanarModelError(f"frequencies must lie in (0, {0.5 / model.dt:g}) Hz (Nyquist)")
    if isinstance(model, PlanarLinear):
        k = np.broadcast_to(linear_stiffness(model, freq_hz), (len(q0), len(freq_hz), 3, 3))
        return PassivityReport(model.name, "analytic", freq_hz, q0, loss_eigenvalues(k))
    if isinstance(model, PlanarNarx):
        fp = fixed_points(model, q0)
        keep = fp.stable
        k = network_stiffness(model, fp.q[fp.hold[keep]], fp.y[keep], freq_hz)
        missing = q0[fp.stable_count == 0]
        return PassivityReport(
            model.name, "linearised", freq_hz, fp.q[fp.hold[keep]], loss_eigenvalues(k), missing
        )
    k = sine_stiffness(model, q0, freq_hz)
    return PassivityReport(model.name, "sines", freq_hz, q0, loss_eigenvalues(k))
