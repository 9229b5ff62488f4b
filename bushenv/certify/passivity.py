"""Small-signal passivity: the dynamic stiffness of a NARX model about a hold, and where it
gives energy back.

Linearised about a fixed point (x0, y*) of the held recurrence (``fixed_points``), with
a_j = dN/dy_{t-j} and b_j = dN/dxs_{t-j} (``network.lag_gradients``), a small displacement
x = x0 + dx gives dy_t = sum_j b_j dx_{t-j} / x_scale + sum_j a_j dy_{t-j}, hence, with
z = exp(j w T) and T the sample time,

    K(z) = F / x = (f_scale / x_scale) B(z) / A(z) + k + c V(z)
    B(z) = sum_{j=0}^{n_past_x} b_j z^-j,     A(z) = 1 - sum_{j=1}^{n_past_f} a_j z^-j

(k = c = 0 for the pure NN). V(z) is the velocity the model is fed, per unit displacement:
``"central"``, (z - 1/z) / (2T), is what ``simulate`` uses (``base.velocity_of``,
``np.gradient``; the machine and the search evaluators); ``"backward"``, (1 - 1/z) / T, is the
rigs' (x_k - x_{k-1}) / dt. Both have Im V = sin(w T) / T, so the convention changes Re K only:
the passivity verdict is the same.

Over one cycle of x = x0 + A sin(w t) the work done on the model is pi A^2 Im K (for sampled
motion judged with the trapezoidal rule of ``divergence.cumulative_work``: that times
sinc(w T), same sign). Frequencies where Im K < 0 are where the model generates energy. The
steady state exists only about a stable fixed point.
"""

from __future__ import annotations

import numpy as np

from bushenv.certify.network import CertifyError, NarxNet, lag_gradients
from bushenv.machine import STEP_PRE_S, step_item

VELOCITY_CONVENTIONS = ("central", "backward")
SETTLE_S = 5.0  # hold before a sine: 1000+ samples, the stable fixed points' transients are gone
SINE_S = 6.0  # sine length; its first half is left out of the fit: the start-up transient
SKIP_S = 3.0  # decays as rho^n, 0.984^614 = 5e-5 for the slowest shipped model (rho = 0.984)


def dynamic_stiffness(
    net: NarxNet,
    x_m: np.ndarray,
    y: np.ndarray,
    freq_hz: np.ndarray,
    velocity: str = "central",
) -> np.ndarray:
    """(P, F) complex K, N/m, of ``net`` linearised about the P fixed points (x_m, y).

    ``x_m``, ``y``: (P,) holds and scaled outputs; ``freq_hz`` (F,).
    """
    if velocity not in VELOCITY_CONVENTIONS:
        raise CertifyError(f"velocity must be one of {VELOCITY_CONVENTIONS}, got {velocity!r}")
    x_m, y = np.atleast_1d(x_m), np.atleast_1d(y)
    a, b = lag_gradients(net, net.held_preactivation(x_m), y)
    w_t = 2.0 * np.pi * np.asarray(freq_hz, dtype=np.float64) * net.dt_s
    zinv = np.exp(-1j * w_t)
    # B and A term by term (a handful of lags): a (P, lags) @ (lags, F) product goes through
    # multi-threaded BLAS, which on a loaded machine is 20-50 times slower than this loop
    num = np.zeros((x_m.size, w_t.size), dtype=complex)
    for j in range(b.shape[1]):
        num += b[:, j : j + 1] * zinv**j
    den = np.ones((x_m.size, w_t.size), dtype=complex)
    for j in range(a.shape[1]):
        den -= a[:, j : j + 1] * zinv ** (j + 1)
    if velocity == "central":
        v = (1.0 / zinv - zinv) / (2.0 * net.dt_s)
    else:
        v = (1.0 - zinv) / net.dt_s
    return net.f_scale_n / net.x_scale_m * num / den + net.k_n_per_m + net.c_ns_per_m * v


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


def _sine_profiles(x0_m: float, freq_hz: np.ndarray, amplitude_m: float, dt: float):
    """(T, F) step to x0, ``SETTLE_S`` hold, then x0 + A sin(2 pi f t); index of the sine."""
    head = step_item(x0_m, SETTLE_S, dt, pre_s=STEP_PRE_S).x
    t = np.arange(int(round(SINE_S / dt))) * dt
    sines = x0_m + amplitude_m * np.sin(2.0 * np.pi * np.outer(t, freq_hz))
    return np.concatenate(
        [np.broadcast_to(head[:, None], (head.size, freq_hz.size)), sines]
    ), head.size


def sine_stiffness(
    model, x0_m: float, freq_hz: np.ndarray, amplitude_m: float, velocity: str = "central"
) -> np.ndarray:
    """(F,) complex K, N/m, measured on ``model`` (any bushing model) by sines about a hold.

    The model steps from rest to ``x0_m`` (the machine's step), holds ``SETTLE_S``, then
    follows x0 + A sin(w t) for ``SINE_S``. Fitted by least squares on the sine after its
    first ``SKIP_S`` (the last sample, where the central-difference velocity is one-sided, is
    left out): F ~ p sin(w t) + q cos(w t) + r + s t, K = (p + j q) / A. The trend term s t
    absorbs a slow relaxation still going on (the reference rubber's 3 s branch).
    ``velocity``: what the model is fed, as in :func:`dynamic_stiffness`.
    """
    if velocity not in VELOCITY_CONVENTIONS:
        raise CertifyError(f"velocity must be one of {VELOCITY_CONVENTIONS}, got {velocity!r}")
    freq_hz = np.atleast_1d(np.asarray(freq_hz, dtype=np.float64))
    x, k0 = _sine_profiles(x0_m, freq_hz, amplitude_m, model.dt)
    x = np.ascontiguousarray(x)
    v = None
    if velocity == "backward":
        v = np.zeros_like(x)
        v[1:] = np.diff(x, axis=0) / model.dt
    f = model.copy().simulate(x, v)
    skip = int(round(SKIP_S / model.dt))
    t = np.arange(x.shape[0] - k0) * model.dt
    sel = slice(skip, t.size - 1)
    ts, fs = t[sel], f[k0:][sel]  # (N,), (N, F)
    w = 2.0 * np.pi * freq_hz
    ph = np.outer(ts, w)
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
    rhs = np.einsum("nfi,nf->fi", basis, fs)
    coef = np.linalg.solve(gram, rhs[..., None])[..., 0]
    return (coef[:, 0] + 1j * coef[:, 1]) / amplitude_m
