"""The dynamic stiffness K(jw) (C x C) of a bushing model about a held deflection: analytic for
a linear model, linearised for a NARX network, measured by sines for any model.

**Linearised network.** About a fixed point (q0, y*) of the held recurrence (``fixed_points``),
with the lag matrices A_l = dN/dy_{t-l} and B_l = dN/dqs_{t-l} (``NarxNet.lag_matrices``), a
small motion q = q0 + dq gives dy_t = sum_l B_l Q^-1 dq_{t-l} + sum_l A_l dy_{t-l}, hence, with
z = exp(j w T) and T the sample time,

    K(z) = F_s (I - sum_{l>=1} A_l z^-l)^-1 (sum_{l>=0} B_l z^-l) Q^-1 + K_b + C_b V(z)

(F_s, Q the diagonal force and coordinate scales; K_b = C_b = 0 for a pure network). For one
coordinate this is K = (f_scale / x_scale) B(z) / A(z) + k + c V(z). The steady state exists only
about a stable fixed point.

V(z) is the velocity the model is fed, per unit deflection: ``"central"``, (z - 1/z) / (2T),
is what ``simulate`` uses (``base.velocity_of``, ``np.gradient``; the machine and the search
evaluators); ``"backward"``, (1 - 1/z) / T, is the rigs' (x_k - x_{k-1}) / dt. Both have
Im V = sin(w T) / T, so the convention changes Re K only: the passivity verdict is the same.

**By sines** (any model, the reference among them): the machine's step to the hold, ``SETTLE_S``
held, then a sine on one coordinate at a time; each force's phasor fitted by least squares.
"""

from __future__ import annotations

import numpy as np

from bushenv import excitation as ex
from bushenv.certify.network import CertifyError, NarxNet
from bushenv.machine import STEP_PRE_S, step_item

VELOCITY_CONVENTIONS = ("central", "backward")
SETTLE_S = 5.0  # hold before a sine: 1000+ samples, the stable fixed points' transients are gone
SKIP_S = 3.0  # start of each sine left out of the fit: the start-up transient decays as rho^n,
# 0.984^614 = 5e-5 for the slowest shipped model (rho = 0.984)
FIT_S = 3.0  # fitted part of the sine, at least; longer for FIT_CYCLES of the lowest frequency
FIT_CYCLES = 4.0


def velocity_factor(freq_hz: np.ndarray, dt: float, velocity: str = "central") -> np.ndarray:
    """(F,) V(z): the velocity fed to the model per unit deflection (see the module doc)."""
    if velocity not in VELOCITY_CONVENTIONS:
        raise CertifyError(f"velocity must be one of {VELOCITY_CONVENTIONS}, got {velocity!r}")
    zinv = np.exp(-2j * np.pi * np.asarray(freq_hz, dtype=np.float64) * dt)
    return (1.0 / zinv - zinv) / (2.0 * dt) if velocity == "central" else (1.0 - zinv) / dt


def dynamic_stiffness(
    net: NarxNet,
    q: np.ndarray,
    y: np.ndarray,
    freq_hz: np.ndarray,
    velocity: str = "central",
) -> np.ndarray:
    """(P, F, C, C) complex K of ``net`` linearised about the P fixed points (q, y), each
    (P, C) (one coordinate: (P,) too); ``freq_hz`` (F,). N/m, N/rad, N m/m or N m/rad."""
    v = velocity_factor(freq_hz, net.dt_s, velocity)
    dim = net.n_coords
    q = np.asarray(q, dtype=np.float64).reshape(-1, dim)
    y = np.asarray(y, dtype=np.float64).reshape(-1, dim)
    a, b = net.lag_matrices(net.held(q), y)  # (P, La, C, C), (P, Lb, C, C)
    zinv = np.exp(-2j * np.pi * np.asarray(freq_hz, dtype=np.float64) * net.dt_s)  # (F,)
    # term by term (a handful of lags): a (P, lags) @ (lags, F) product goes through
    # multi-threaded BLAS, which on a loaded machine is 20-50 times slower than this loop
    num = np.zeros((len(q), zinv.size, dim, dim), dtype=complex)
    for j in range(b.shape[1]):
        num += b[:, None, j] * (zinv**j)[None, :, None, None]
    den = np.broadcast_to(np.eye(dim, dtype=complex), num.shape).copy()
    for j in range(a.shape[1]):
        den -= a[:, None, j] * (zinv ** (j + 1))[None, :, None, None]
    ratio = num / den if dim == 1 else np.linalg.solve(den, num)
    k = net.f_scale[:, None] * ratio / net.q_scale[None, :]
    return k + net.k + v[None, :, None, None] * net.c


def linear_stiffness(model, freq_hz: np.ndarray) -> np.ndarray:
    """(F, C, C) K = K0 + C V(z) of a ``linear`` model (any hold: it is linear)."""
    if hasattr(model, "k_matrix"):
        k0, c0 = np.asarray(model.k_matrix), np.asarray(model.c_matrix)
    else:
        k0, c0 = np.array([[model.k_n_per_m]]), np.array([[model.c_ns_per_m]])
    v = velocity_factor(freq_hz, model.dt)
    return k0[None] + v[:, None, None] * c0[None]


def sine_s(freq_hz: np.ndarray) -> float:
    """Length of the sines of :func:`sine_stiffness`, s: ``SKIP_S`` + the fitted part."""
    return SKIP_S + max(FIT_S, FIT_CYCLES / float(np.min(freq_hz)))


def _head(q0: np.ndarray, units: tuple[str, ...], dt: float) -> np.ndarray:
    """(Th, C) the machine's step from rest to ``q0``, every coordinate together, then
    ``SETTLE_S`` held."""
    rise = 0.0  # the shortest half-cosine rise within the machine's velocity (translations)
    for x, u in zip(q0, units, strict=True):
        if u == "m" and abs(x) / dt > ex.MAX_VELOCITY_M_PER_S:
            rise = max(rise, 0.5 * np.pi * abs(x) / ex.MAX_VELOCITY_M_PER_S * (1 + 1e-6))
    rise_s = None if len(q0) == 1 else rise
    return np.stack(
        [step_item(float(x), SETTLE_S, dt, pre_s=STEP_PRE_S, rise_s=rise_s).x for x in q0], -1
    )


def sine_stiffness(
    model, q0, freq_hz: np.ndarray, amplitude, velocity: str = "central"
) -> np.ndarray:
    """(M, F, C, C) complex K measured on ``model`` (any bushing model) by sines about each hold
    of ``q0`` (M, C) (one coordinate: a number or (M,) too).

    Column j: the machine's step to the hold, ``SETTLE_S`` held, then q0 + A_j sin(w t) on
    coordinate j alone for :func:`sine_s`; ``amplitude`` A (C,) or one number. Each force is
    fitted by least squares on the sine after its first ``SKIP_S`` (the last sample, where the
    central-difference velocity is one-sided, is left out) as p sin + q cos + r + s t (the trend
    absorbs a slow relaxation still going on, as the reference rubber's 3 s branch);
    K_ij = (p + j q) / A_j. ``velocity``: what the model is fed (:func:`velocity_factor`).
    """
    velocity_factor(np.zeros(0), model.dt, velocity)  # checks the convention
    dim, dt = model.n_coords, model.dt
    q0 = np.asarray(q0, dtype=np.float64).reshape(-1, dim)
    freq_hz = np.atleast_1d(np.asarray(freq_hz, dtype=np.float64))
    amp = np.broadcast_to(np.asarray(amplitude, dtype=np.float64), (dim,))
    heads = [_head(x, tuple(model.units), dt) for x in q0]
    t = np.arange(int(round(sine_s(freq_hz) / dt))) * dt
    sines = np.sin(2.0 * np.pi * np.outer(t, freq_hz))  # (Ts, F)
    n_head = max(len(h) for h in heads)
    M, F = len(q0), freq_hz.size
    q = np.empty((n_head + t.size, M, F, dim, dim))  # (T, hold, freq, driven j, coordinate)
    for m, h in enumerate(heads):
        q[:n_head, m] = np.concatenate([h, np.repeat(h[-1:], n_head - len(h), 0)])[:, None, None, :]
        q[n_head:, m] = q0[m]
    for j in range(dim):
        q[n_head:, :, :, j, j] += amp[j] * sines[:, None, :]
    x = np.ascontiguousarray(q.reshape(q.shape[0], -1, dim))
    if dim == 1:
        x = x[..., 0]
    v = None
    if velocity == "backward":
        v = np.zeros_like(x)
        v[1:] = np.diff(x, axis=0) / dt
    f = model.copy().simulate(x, v).reshape(q.shape[0], M, F, dim, dim)
    sel = slice(int(round(SKIP_S / dt)), t.size - 1)
    ts, fs = t[sel], f[n_head:][sel]  # (N,), (N, hold, freq, driven, force)
    ph = np.outer(ts, 2.0 * np.pi * freq_hz)  # (N, F)
    basis = np.stack(  # (N, F, 4)
        [
            np.sin(ph),
            np.cos(ph),
            np.ones_like(ph),
            np.broadcast_to((ts - ts.mean())[:, None], ph.shape),
        ],
        axis=-1,
    )
    # normal equations per frequency, all at once (well conditioned: near-orthogonal columns)
    gram = np.einsum("nfi,nfj->fij", basis, basis)
    rhs = np.einsum("nfi,nmfjk->fimjk", basis, fs).reshape(F, 4, -1)
    coef = np.linalg.solve(gram, rhs).reshape(F, 4, M, dim, dim)
    k = (coef[:, 0] + 1j * coef[:, 1]) / amp[None, None, :, None]  # (F, hold, driven j, force i)
    return np.swapaxes(k, -1, -2).transpose(1, 0, 2, 3)
