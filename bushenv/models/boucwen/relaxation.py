"""Relaxation on the deflection vector: a Prony series of Maxwell branches (generalised Maxwell).

    f_relax = sum_m R_m p_m          p_m' = v - p_m / tau_m        (p_m in m, m, rad)

Each branch is a spring R_m (3x3, N/m ... N m/rad) in series with a dashpot of time constant
tau_m: p_m is the branch spring's deflection, which follows a fast motion and relaxes to zero
under a held one. This is the linear viscoelastic solid of rubber (the Prony series of finite
element codes), here with matrix moduli so a branch can couple the coordinates. A backbone
needs it because a NARX network's 5 lags (10 ms at 500 Hz) cannot carry a 200 ms relaxation
except through its own fed-back outputs (studies/2026-11-planar-fit-unseen).

Discrete law (exact when q moves on a straight line within a sample, as the Bouc-Wen kernel
assumes): p_m,t = a_m p_m,t-1 + b_m (q_t - q_t-1), a_m = exp(-dt / tau_m),
b_m = tau_m (1 - a_m) / dt. With R_m symmetric positive semidefinite (a fit gives diagonal,
non-negative ones) every branch stores and dissipates energy only: its loss matrix adds
R_m w tau / (1 + w^2 tau^2) >= 0 at every frequency, so it keeps the element passive.

Quasi-linear form (``FORMS`` "qlv"; Fung 1981, "Biomechanics", ch. 7; the finite-strain
viscoelasticity of Simo 1987 that finite element codes apply to a hyperelastic rubber): the
branches relax the *elastic force* instead of the deflection,

    f_relax = sum_m R_m s_m          s_m' = F_e(q)' - s_m / tau_m       (s_m in N, N, N m)

with F_e(q) = K q + G3(q) the backbone's elastic force and R_m dimensionless (the reduced
relaxation function's weights). In a filled rubber the chains that relax are the ones that
carry the elastic stress, so the relaxing force scales with the elastic stiffness where the
bushing is: a hardening or coupled-stiffened state relaxes more. For a linear elastic
backbone (G3 = 0) F_e' = K q', so s_m = K p_m and the form is the constant one with gains
R_m K (``qlv_as_constant``). Discrete law as above on the increments of F_e.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from scipy.signal import lfilter

from bushenv.models.planar_base import PlanarModelError, as_matrix

FORMS = ("constant", "qlv")  # what the branches relax: the deflection, or the elastic force


def coefficients(tau: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(a, b) of the discrete branches, each (M,)."""
    a = np.exp(-dt / tau)
    return a, tau * (1.0 - a) / dt


def check(tau, gain) -> tuple[np.ndarray, np.ndarray]:
    """``tau`` (M,) s > 0 and ``gain`` (M, 3, 3) as arrays, or ``PlanarModelError``."""
    tau = np.atleast_1d(np.asarray(tau if tau is not None else [], dtype=np.float64))
    m = tau.shape[0]
    tau = as_matrix("relax_tau", tau, (m,))
    gain = as_matrix("relax_gain", np.zeros((0, 3, 3)) if gain is None else gain, (m, 3, 3))
    if np.any(tau <= 0):
        raise PlanarModelError(f"relax_tau: time constants must be > 0 s, got {tau.tolist()}")
    return tau, gain


def branch_deflections(q: np.ndarray, dt: float, tau: np.ndarray) -> np.ndarray:
    """(T, 3 M) p_m of a record ``q`` (T, 3) run from rest, branch by branch (the fit's
    columns; the kernel's recursion, so a fitted model reproduces them)."""
    if tau.shape[0] == 0:
        return np.zeros((q.shape[0], 0))
    dq = np.diff(q, axis=0, prepend=np.zeros((1, 3)))
    a, b = coefficients(tau, dt)
    return np.hstack([lfilter([bm], [1.0, -am], dq, axis=0) for am, bm in zip(a, b, strict=True)])


@nb.njit(cache=True)
def _add_branches(gain, state, b_, out_tb):  # pragma: no cover - compiled
    """out_tb[i] += sum_m sum_j gain[m, i, j] s_m,j: the branches' force on each coordinate."""
    for i in range(3):
        acc = 0.0
        for m in range(gain.shape[0]):
            for j in range(3):
                acc += gain[m, i, j] * state[3 * m + j, b_]
        out_tb[i] += acc


@nb.njit(cache=True)
def relaxation_kernel(q, q_before, state, a, b, gain, out):  # pragma: no cover - compiled
    """Add sum_m R_m p_m to ``out`` (T, B, 3); ``state`` (3 M, B) the branches' p_m, updated;
    ``q_before`` (3, B) the deflection before the first sample."""
    T, B, _ = q.shape
    M = a.shape[0]
    for b_ in range(B):
        for t in range(T):
            for i in range(3):
                prev = q_before[i, b_] if t == 0 else q[t - 1, b_, i]
                dq = q[t, b_, i] - prev
                for m in range(M):
                    r = 3 * m + i
                    state[r, b_] = a[m] * state[r, b_] + b[m] * dq
            _add_branches(gain, state, b_, out[t, b_])


@nb.njit(cache=True)
def _elastic(q0, q1, q2, k, g, i):  # pragma: no cover - compiled
    """F_e,i = K_i q + sum_j G_ij q_i q_j^2 (the backbone's elastic force on coordinate i)."""
    qq = (q0, q1, q2)
    acc = 0.0
    for j in range(3):
        acc += k[i, j] * qq[j] + g[i, j] * qq[i] * qq[j] * qq[j]
    return acc


@nb.njit(cache=True)
def qlv_kernel(q, q_before, state, a, b, gain, k, g, out):  # pragma: no cover - compiled
    """The quasi-linear form: add sum_m R_m s_m to ``out`` (T, B, 3); ``state`` (3 M, B) the
    branches' s_m (N, N, N m), updated on the increments of F_e = K q + G3(q)."""
    T, B, _ = q.shape
    M = a.shape[0]
    for b_ in range(B):
        for t in range(T):
            for i in range(3):
                if t == 0:
                    before = _elastic(q_before[0, b_], q_before[1, b_], q_before[2, b_], k, g, i)
                else:
                    before = _elastic(q[t - 1, b_, 0], q[t - 1, b_, 1], q[t - 1, b_, 2], k, g, i)
                df = _elastic(q[t, b_, 0], q[t, b_, 1], q[t, b_, 2], k, g, i) - before
                for m in range(M):
                    r = 3 * m + i
                    state[r, b_] = a[m] * state[r, b_] + b[m] * df
            _add_branches(gain, state, b_, out[t, b_])


def qlv_as_constant(gain: np.ndarray, k: np.ndarray) -> np.ndarray:
    """The constant-form gains R_m K that a quasi-linear relaxation with weights ``gain``
    (M, 3, 3) on a linear elastic backbone of stiffness ``k`` (3, 3) equals."""
    return gain @ k


SEPARABLE_INFLATION = 1e4  # a column the others explain to 1 part in 10^4 (R^2 0.9999)


def inseparable(q: np.ndarray, v: np.ndarray, p: np.ndarray, tau: np.ndarray) -> list[list[float]]:
    """Per coordinate, the time constants whose branch deflections (``p`` (T, 3 M), as
    ``branch_deflections``) records cannot tell from the deflection ``q``, the rate ``v`` and
    the other branches: the largest variance inflation removed one at a time while it is at
    least ``SEPARABLE_INFLATION``. A branch slower than a record's slowest motion
    (1/(2 pi tau) below its band) moves with q: its gain and the static stiffness are not
    identified apart, nor the force under a held deflection."""
    out: list[list[float]] = []
    for i in range(3):
        keep, lost = list(range(tau.shape[0])), []
        while keep:
            x = np.column_stack([q[:, i], v[:, i], *(p[:, 3 * m + i] for m in keep)])
            x = x / np.maximum(np.linalg.norm(x, axis=0), 1e-300)
            inflation = np.diag(np.linalg.pinv(x.T @ x))[2:]
            j = int(np.argmax(inflation))
            if inflation[j] < SEPARABLE_INFLATION:
                break
            lost.append(float(tau[keep.pop(j)]))
        out.append(sorted(lost))
    return out
