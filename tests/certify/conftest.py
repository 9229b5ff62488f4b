"""Hand-built NARX models with known hold behaviour for the certificate tests.

``fold_nn``: one tanh unit fed back on itself, y_t = tanh(g sum_j w_j y_{t-j} + u),
u = sum_i v_i xs_{t-i} with the weights w, v each summing to 1 and xs = x / 1 mm. In a hold
its fixed points solve y = tanh(g y + u): for g > 1 three of them while |u| < u_f and one
beyond, with folds at u = +-u_f, u_f = g y_f - artanh(y_f), y_f = sqrt(1 - 1/g) (where
g sech^2 = 1). The force offset makes rest (F = 0) the output ``rest_y``: with rest_y < 0 the
run starts on the lower branch, which vanishes at x = +u_f mm.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bushenv.models.hybrid import HybridBushing
from bushenv.models.narx import NarxBushing

X_SCALE_M = 1e-3

OLD_MODELS = Path(__file__).resolve().parents[1] / "regressions" / "models"


def old_nn(axis: str) -> str:
    """The NN shipped before certified training, kept with the corpus cases found on it: a
    network with known energy failures, whatever the shipped models are today."""
    return str(OLD_MODELS / f"{axis}_nn-6f15bf3.npz")


def fold_u(g: float) -> float:
    """The analytic fold of y = tanh(g y + u): u_f > 0 (folds at +-u_f)."""
    yf = np.sqrt(1.0 - 1.0 / g)
    return float(g * yf - np.arctanh(yf))


def fold_roots(g: float, u: float) -> np.ndarray:
    """Roots of y = tanh(g y + u) by a dense bracketed search (independent of bushenv)."""
    y = np.linspace(-1.0, 1.0, 2_000_001)
    f = np.tanh(g * y + u) - y
    neg = f < 0
    k = np.flatnonzero(neg[:-1] != neg[1:])
    return y[k] - f[k] * (y[k + 1] - y[k]) / (f[k + 1] - f[k])


def _fold_params(g, y_weights, x_weights, f_scale_n, rest_y):
    wy = g * np.asarray(y_weights, dtype=float) / np.sum(y_weights)
    wx = np.asarray(x_weights, dtype=float) / np.sum(x_weights)
    return dict(
        x_offset_m=0.0,
        x_scale_m=X_SCALE_M,
        f_offset_n=-rest_y * f_scale_n,
        f_scale_n=f_scale_n,
        w1=np.concatenate([wx, wy])[None, :],
        b1=np.zeros(1),
        w2=np.zeros((0, 1)),
        b2=np.zeros(0),
        w_out=np.ones(1),
        b_out=0.0,
        n_past_x=len(wx) - 1,
        n_past_f=len(wy),
    )


def fold_nn(
    g=2.0,
    y_weights=(0.4, 0.3, 0.15, 0.1, 0.05),
    x_weights=(0.3, 0.2, 0.2, 0.1, 0.1, 0.1),
    f_scale_n=1000.0,
    rest_y=-0.9,
) -> NarxBushing:
    return NarxBushing(**_fold_params(g, y_weights, x_weights, f_scale_n, rest_y))


def fold_hybrid(k_n_per_m=2.0e5, c_ns_per_m=2.0e3, **kw) -> HybridBushing:
    """The fold network as the residual of a hybrid (the issue's kind of hold departure)."""
    p = _fold_params(
        kw.get("g", 2.0),
        kw.get("y_weights", (0.5, 0.2, 0.2, 0.1)),
        kw.get("x_weights", (0.5, 0.3, 0.2)),
        kw.get("f_scale_n", 300.0),
        kw.get("rest_y", -0.9),
    )
    return HybridBushing(k_n_per_m=k_n_per_m, c_ns_per_m=c_ns_per_m, **p)


def wrong_sign_hybrid(k_n_per_m=1.0e5, beta=1.0, f_scale_n=200.0, feedback=0.3) -> HybridBushing:
    """F = k x + f_scale y, y = tanh(-beta xs + feedback * mean of past y): near x = 0 the
    network's -f_scale beta x / 1 mm outweighs k x (200 N/mm against 100 N/mm by default)."""
    n = 5
    w1 = np.concatenate([np.full(n + 1, -beta / (n + 1)), np.full(n, feedback / n)])[None, :]
    return HybridBushing(
        k_n_per_m=k_n_per_m,
        c_ns_per_m=1.0e3,
        x_offset_m=0.0,
        x_scale_m=X_SCALE_M,
        f_offset_n=0.0,
        f_scale_n=f_scale_n,
        w1=w1,
        b1=np.zeros(1),
        w2=np.zeros((0, 1)),
        b2=np.zeros(0),
        w_out=np.ones(1),
        b_out=0.0,
    )


def random_narx(rng: np.random.Generator, hidden=(6,), n_past_x=3, n_past_f=4, gain=1.5):
    """A random network whose own-output feedback (``gain``) is strong enough to give several
    fixed points at some holds; one or two hidden layers, any lags."""
    n_in = 1 + n_past_x + n_past_f
    w1 = rng.normal(0, 1, (hidden[0], n_in))
    w1[:, 1 + n_past_x :] *= gain
    if len(hidden) == 2:
        w2 = rng.normal(0, 1.5, (hidden[1], hidden[0]))
        b2 = rng.normal(0, 0.5, hidden[1])
    else:
        w2, b2 = np.zeros((0, hidden[0])), np.zeros(0)
    return NarxBushing(
        x_offset_m=0.0,
        x_scale_m=2e-3,
        f_offset_n=float(rng.normal(0, 50)),
        f_scale_n=500.0,
        w1=w1,
        b1=rng.normal(0, 0.5, hidden[0]),
        w2=w2,
        b2=b2,
        w_out=rng.normal(0, 1.0, hidden[-1]),
        b_out=float(rng.normal(0, 0.2)),
        n_past_x=n_past_x,
        n_past_f=n_past_f,
    )


def pulling_nn(f_scale_n=500.0, beta=0.5) -> NarxBushing:
    """A NARX network that pulls: y_t = tanh(-beta (xs_t + xs_{t-1}) / 2 + 0.2 y_{t-1}),
    F = f_scale y, so a
    held +4 mm gives about -460 N (the sign against the deflection, no reference needed)."""
    return NarxBushing(
        x_offset_m=0.0,
        x_scale_m=X_SCALE_M,
        f_offset_n=0.0,
        f_scale_n=f_scale_n,
        w1=np.array([[-beta / 2, -beta / 2, 0.2]]),
        b1=np.zeros(1),
        w2=np.zeros((0, 1)),
        b2=np.zeros(0),
        w_out=np.ones(1),
        b_out=0.0,
        n_past_x=1,
        n_past_f=1,
    )


def ringing_hybrid(g=1.004, beta=0.25, x_ring_m=-1.25e-3, f_scale_n=3000.0) -> HybridBushing:
    """A hybrid (Table-1-like k, c) whose residual y_t = tanh(-g y_{t-1} + beta (xs_t +
    xs_{t-1}) / 2), xs = (x - x_ring) / 1 mm, has a hold fixed point of spectral radius
    g (1 - y*^2) slightly above 1 (a flip: it rings at the Nyquist rate) within about
    +-0.3 mm of ``x_ring``. Its input reaches the network through (1 + z^-1) / 2, which has no
    gain at Nyquist, so a slow ramp to the hold barely excites the ring (it grows as
    g^n from almost nothing: a few N after 4 s); a sine stopping abruptly, or a step, excites
    it at once and it rings at its limit cycle, hundreds of N peak to peak. F = 0 at rest."""
    y = 0.0
    for _ in range(5000):  # the fixed point at rest, by damped iteration
        y = 0.5 * y + 0.5 * np.tanh(-g * y + beta * (0.0 - x_ring_m) / X_SCALE_M)
    return HybridBushing(
        k_n_per_m=3.8e5,
        c_ns_per_m=500.0,
        x_offset_m=x_ring_m,
        x_scale_m=X_SCALE_M,
        f_offset_n=-f_scale_n * y,
        f_scale_n=f_scale_n,
        w1=np.array([[beta / 2, beta / 2, -g]]),
        b1=np.zeros(1),
        w2=np.zeros((0, 1)),
        b2=np.zeros(0),
        w_out=np.ones(1),
        b_out=0.0,
        n_past_x=1,
        n_past_f=1,
    )


# ----- networks over three coordinates ------------------------------------------------------
SCALE3 = np.array([2e-3, 2e-3, 0.05])


def bistable(gain_q=0.5, out=2.0):
    """Three single-axis networks, each y = out tanh(2 y + gain_q qs); out = 2: three roots per
    axis at rest (+-1.998651 stable, 0 unstable), one beyond a fold."""
    from bushenv.models.planar_narx import N_IN, PlanarNarxPerAxis

    h = 27
    w1, w_out = np.zeros((h, N_IN)), np.zeros((3, h))
    for ax in range(3):
        u = 9 * ax
        w1[u, 18 + ax :: 3] = 0.4  # own output, lags 1..5: sum 2
        w1[u, ax] = gain_q  # own coordinate, lag 0
        w_out[ax, u] = out
    return PlanarNarxPerAxis(
        q_offset=np.zeros(3), q_scale=SCALE3, f_offset=np.zeros(3),
        f_scale=np.array([100.0, 100.0, 10.0]), w1=w1, b1=np.zeros(h), w_out=w_out,
        b_out=np.zeros(3),
    )  # fmt: skip


def scalar_roots(c):
    """Roots of 2 tanh(2 y + c) - y by a fine scan and bisection (independent of the boxes)."""
    g = lambda y: 2 * np.tanh(2 * y + c) - y  # noqa: E731
    ys = np.linspace(-2.5, 2.5, 200_000)  # even: no grid point on a root at 0
    v = g(ys)
    roots = []
    for i in np.flatnonzero(np.sign(v[:-1]) != np.sign(v[1:])):
        a, b = ys[i], ys[i + 1]
        for _ in range(80):
            m = 0.5 * (a + b)
            a, b = (m, b) if np.sign(g(m)) == np.sign(g(a)) else (a, m)
        roots.append(0.5 * (a + b))
    return np.array(roots)


def ringing3(g=1.004, beta=0.25, ring_m=-1.25e-3, f_scale_n=3000.0):
    """``ringing_hybrid``'s ring on the radial coordinate of a three-axis hybrid (Table-1-like
    diagonal backbone): the radial residual y_t = tanh(-g y_{t-1} + beta (qs_t + qs_{t-1}) / 2),
    qs = (radial - ``ring_m``) / 1 mm, rings at the Nyquist rate when held within about
    +-0.3 mm of ``ring_m`` after a sine or a step, barely after a slow ramp; the axial and
    rotation residuals are zero. F = 0 at rest."""
    from bushenv.models.planar_narx import N_IN, PlanarHybrid

    y = 0.0
    for _ in range(5000):  # the radial residual's fixed point at rest, by damped iteration
        y = 0.5 * y + 0.5 * np.tanh(-g * y + beta * (0.0 - ring_m) / X_SCALE_M)
    w1, w_out = np.zeros((3, N_IN)), np.zeros((3, 3))
    w1[1, [1, 4, 19]] = beta / 2, beta / 2, -g  # radial lags 0, 1; its own output, lag 1
    w_out[1, 1] = 1.0
    return PlanarHybrid(
        k_matrix=np.diag([3.8e5, 3.8e5, 3.0e3]), c_matrix=np.diag([500.0, 500.0, 5.0]),
        q_offset=np.array([0.0, ring_m, 0.0]), q_scale=np.array([X_SCALE_M, X_SCALE_M, 0.01]),
        f_offset=np.array([0.0, -f_scale_n * y, 0.0]), f_scale=np.array([1.0, f_scale_n, 1.0]),
        w1=w1, b1=np.zeros(3), w_out=w_out, b_out=np.zeros(3),
    )  # fmt: skip
