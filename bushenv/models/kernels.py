"""Compiled free-run kernels shared by every model's ``step`` and ``simulate``.

Each kernel takes (T, B) arrays of displacement and velocity, a state array (n_state, B) that
it updates in place, the model's parameters, and writes forces into a (T, B) ``out``. The loop
over the B profiles is innermost so numba vectorises it. ``cache=True`` keeps the compiled code
on disk: the first import compiles (seconds), later ones load.

Every column b of the state evolves from its own inputs and parameters only, so a batch of B
histories gives, bit for bit, what B separate runs give.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from bushenv.models.fastmath import tanh

# error_model="numpy": no zero-division guard branches, so the loops over profiles vectorise.
JIT = dict(cache=True, fastmath=False, nogil=True, error_model="numpy")


@nb.njit(**JIT)
def linear_kernel(x, v, k, c, out):  # pragma: no cover - compiled
    T, B = x.shape
    for t in range(T):
        for b in range(B):
            out[t, b] = k * x[t, b] + c * v[t, b]


# ----- NARX network (nn, hybrid) -----------------------------------------------------------
# State rows: 0 = step counter (modulo n_past_x * n_past_f; equal in every column),
# 1 .. n_past_x = ring of past SCALED displacements, then n_past_f rows = ring of past SCALED
# network outputs. Lag j of a ring of length n sits in slot (counter - j) mod n.


NARX_TILE = 64  # profiles per tile: 11 inputs + 9 hidden x 64 x 8 B = 10 KB, well inside L1


@nb.njit(**JIT)
def narx_kernel(  # pragma: no cover - compiled
    x,
    v,
    state,
    n_past_x,
    n_past_f,
    x_offset,
    x_scale,
    f_offset,
    f_scale,
    w1,
    b1,
    w2,
    b2,
    w_out,
    b_out,
    k,
    c,
    out,
):
    """out = k x + c v + f_offset + f_scale * net(scaled x_t, x_{t-1..}, own y_{t-1..}).

    ``w1`` (H1, 1 + n_past_x + n_past_f), ``b1`` (H1,); ``w2`` (H2, H1) and ``b2`` (H2,) for a
    second tanh layer, or shapes (0, H1) and (0,) for none; ``w_out`` (H_last,), ``b_out``
    a float. The pure NN passes k = c = 0.
    """
    T, B = x.shape
    n_in = w1.shape[1]
    h1n = w1.shape[0]
    h2n = w2.shape[0]
    # Profiles are processed in tiles of NARX_TILE so the hidden-layer arrays stay in L1 cache
    # while the loops over profiles inside a tile vectorise. Each profile's arithmetic is the
    # same whatever the tile, so tiling changes no result.
    inp = np.empty((n_in, NARX_TILE))
    h1 = np.empty((h1n, NARX_TILE))
    h2 = np.empty((max(h2n, 1), NARX_TILE))
    y = np.empty(NARX_TILE)
    period = n_past_x * n_past_f
    for lo in range(0, B, NARX_TILE):
        n = min(NARX_TILE, B - lo)
        for t in range(T):
            cnt = int(state[0, lo])
            for b in range(n):
                inp[0, b] = (x[t, lo + b] - x_offset) / x_scale
            for j in range(1, n_past_x + 1):
                row = 1 + (cnt + n_past_x - j) % n_past_x
                for b in range(n):
                    inp[j, b] = state[row, lo + b]
            for j in range(1, n_past_f + 1):
                row = 1 + n_past_x + (cnt + n_past_f - j) % n_past_f
                for b in range(n):
                    inp[n_past_x + j, b] = state[row, lo + b]
            for h in range(h1n):
                for b in range(n):
                    h1[h, b] = b1[h]
                for i in range(n_in):
                    wi = w1[h, i]
                    for b in range(n):
                        h1[h, b] += wi * inp[i, b]
                for b in range(n):
                    h1[h, b] = tanh(h1[h, b])
            if h2n > 0:
                for h in range(h2n):
                    for b in range(n):
                        h2[h, b] = b2[h]
                    for i in range(h1n):
                        wi = w2[h, i]
                        for b in range(n):
                            h2[h, b] += wi * h1[i, b]
                    for b in range(n):
                        h2[h, b] = tanh(h2[h, b])
                for b in range(n):
                    y[b] = b_out
                for h in range(h2n):
                    wo = w_out[h]
                    for b in range(n):
                        y[b] += wo * h2[h, b]
            else:
                for b in range(n):
                    y[b] = b_out
                for h in range(h1n):
                    wo = w_out[h]
                    for b in range(n):
                        y[b] += wo * h1[h, b]
            row_x = 1 + cnt % n_past_x
            row_f = 1 + n_past_x + cnt % n_past_f
            nxt = float((cnt + 1) % period)
            for b in range(n):
                out[t, lo + b] = k * x[t, lo + b] + c * v[t, lo + b] + (f_offset + f_scale * y[b])
                state[row_x, lo + b] = inp[0, b]
                state[row_f, lo + b] = y[b]
                state[0, lo + b] = nxt


# ----- Bouc-Wen (seed 002 eqs. 1-5) -----------------------------------------------------------
# Parameter rows of ``p`` (16, B), SI: see BW_ORDER. State rows: y, w, z1, z2, x_prev, v_prev,
# substeps used in the last sample (diagnostic).
BW_ORDER = (
    "c0",
    "k0",
    "c1",
    "k1",
    "c2",
    "k2",
    "A1",
    "A2",
    "beta1",
    "beta2",
    "gamma1",
    "gamma2",
    "n1",
    "n2",
    "a1",
    "a2",
)
BW_N_STATE = 7
RK4_STABLE_FRACTION = 2.0  # RK4 is stable for h*|lambda| < 2.785 on the real axis; keep ~70 %
BW_MAX_SUBSTEPS = 200_000  # per sample; beyond this the parameters are not integrable here


@nb.njit(**JIT)
def _sgn(a):  # pragma: no cover - compiled
    if a > 0.0:
        return 1.0
    if a < 0.0:
        return -1.0
    return 0.0


@nb.njit(**JIT)
def _bw_rhs(p, b, xx, u, y, w, z1, z2):  # pragma: no cover - compiled
    c0 = p[0, b]
    k0 = p[1, b]
    c1 = p[2, b]
    k1 = p[3, b]
    c2 = p[4, b]
    k2 = p[5, b]
    dy = (c1 * u + k1 * (xx - y) - k0 * y + p[14, b] * z1) / c1  # eq. 3
    dw = (c2 * u + k2 * (xx - w) + p[15, b] * z2) / (c0 + c2)  # eq. 4
    d1 = u - dy
    d2 = u - dw
    dz1 = d1 * (p[6, b] - (p[10, b] + p[8, b] * _sgn(d1) * _sgn(z1)) * abs(z1) ** p[12, b])  # 1
    dz2 = d2 * (p[7, b] - (p[11, b] + p[9, b] * _sgn(d2) * _sgn(z2)) * abs(z2) ** p[13, b])  # 2
    return dy, dw, dz1, dz2


@nb.njit(**JIT)
def _bw_rate(p, b, xx, u, y, w, z1, z2):  # pragma: no cover - compiled
    """Upper estimate of the stiffest eigenvalue magnitude of eqs. 1-4 at this state (1/s).

    Linearising eqs. 1 and 3 in (y, z1) gives eigenvalues 0 and -(k0 + k1 + a1 G1) / c1 with
    G1 = A1 - (gamma1 + beta1 s) |z1|^n1, plus d1 * dG1/dz1 from the |z1|^n1 term; likewise
    (k2 + a2 G2) / (c0 + c2) for eqs. 2 and 4. Absolute values make it an upper estimate.
    For n < 1, |z|^(n-1) is evaluated no closer to 0 than A * 1e-6 m (one micrometre's worth of
    hysteretic variable): the singular slope at z = 0 is crossed, not dwelt in.
    """
    c0 = p[0, b]
    k0 = p[1, b]
    c1 = p[2, b]
    k1 = p[3, b]
    c2 = p[4, b]
    k2 = p[5, b]
    dy, dw, _, _ = _bw_rhs(p, b, xx, u, y, w, z1, z2)
    d1 = abs(u - dy)
    d2 = abs(u - dw)
    bg1 = abs(p[8, b]) + abs(p[10, b])
    bg2 = abs(p[9, b]) + abs(p[11, b])
    az1 = abs(z1)
    az2 = abs(z2)
    g1 = abs(p[6, b]) + bg1 * az1 ** p[12, b]
    g2 = abs(p[7, b]) + bg2 * az2 ** p[13, b]
    zf1 = max(az1, abs(p[6, b]) * 1e-6)
    zf2 = max(az2, abs(p[7, b]) * 1e-6)
    s1 = d1 * bg1 * abs(p[12, b]) * zf1 ** (p[12, b] - 1.0)
    s2 = d2 * bg2 * abs(p[13, b]) * zf2 ** (p[13, b] - 1.0)
    r1 = (abs(k0) + abs(k1) + abs(p[14, b]) * g1) / abs(c1) + s1
    r2 = (abs(k2) + abs(p[15, b]) * g2) / abs(c0 + c2) + s2
    return r1 + r2


@nb.njit(**JIT)
def boucwen_kernel(x, v, state, p, dt, max_substeps, out):  # pragma: no cover - compiled
    """Integrate seed 002 eqs. 1-4 over each sample with RK4 sub-steps; F by eq. 5.

    Inside a sample x and its rate u are interpolated linearly between the previous and the
    current sample. Sub-steps: before each one, h = remaining / ceil(remaining * rate / 2.0)
    with ``rate`` from ``_bw_rate``, so every sub-step sits inside RK4's stability interval and
    the last one ends exactly on the sample. Returns the number of columns that needed more than
    ``max_substeps`` in one sample (their output is NaN from then on; the model raises, the
    identification scores them infeasible).
    """
    T, B = x.shape
    n_bad = 0
    for t in range(T):
        for b in range(B):
            y = state[0, b]
            w = state[1, b]
            z1 = state[2, b]
            z2 = state[3, b]
            x0 = state[4, b]
            u0 = state[5, b]
            x1 = x[t, b]
            u1 = v[t, b]
            tau = 0.0
            n_sub = 0
            ok = True
            while tau < dt:
                remaining = dt - tau
                s = tau / dt
                rate = _bw_rate(p, b, x0 + s * (x1 - x0), u0 + s * (u1 - u0), y, w, z1, z2)
                if not (rate < 1e300):  # NaN or inf: no finite step is stable
                    ok = False
                    break
                n_left = math.ceil(remaining * rate / RK4_STABLE_FRACTION)
                if n_left < 1:
                    n_left = 1
                if n_sub + n_left > max_substeps:
                    ok = False
                    break
                h = remaining / n_left
                sa = tau / dt
                sm = (tau + 0.5 * h) / dt
                se = (tau + h) / dt
                if n_left == 1:
                    se = 1.0
                xa = x0 + sa * (x1 - x0)
                ua = u0 + sa * (u1 - u0)
                xm = x0 + sm * (x1 - x0)
                um = u0 + sm * (u1 - u0)
                xe = x0 + se * (x1 - x0)
                ue = u0 + se * (u1 - u0)
                ky1, kw1, kz11, kz21 = _bw_rhs(p, b, xa, ua, y, w, z1, z2)
                hh = 0.5 * h
                ky2, kw2, kz12, kz22 = _bw_rhs(
                    p, b, xm, um, y + hh * ky1, w + hh * kw1, z1 + hh * kz11, z2 + hh * kz21
                )
                ky3, kw3, kz13, kz23 = _bw_rhs(
                    p, b, xm, um, y + hh * ky2, w + hh * kw2, z1 + hh * kz12, z2 + hh * kz22
                )
                ky4, kw4, kz14, kz24 = _bw_rhs(
                    p, b, xe, ue, y + h * ky3, w + h * kw3, z1 + h * kz13, z2 + h * kz23
                )
                h6 = h / 6.0
                y += h6 * (ky1 + 2.0 * ky2 + 2.0 * ky3 + ky4)
                w += h6 * (kw1 + 2.0 * kw2 + 2.0 * kw3 + kw4)
                z1 += h6 * (kz11 + 2.0 * kz12 + 2.0 * kz13 + kz14)
                z2 += h6 * (kz21 + 2.0 * kz22 + 2.0 * kz23 + kz24)
                n_sub += 1
                if n_left == 1:
                    tau = dt
                else:
                    tau += h
            if not ok:
                n_bad += 1
                y = np.nan
                w = np.nan
                z1 = np.nan
                z2 = np.nan
            c0 = p[0, b]
            c2 = p[4, b]
            dw = (c2 * u1 + p[5, b] * (x1 - w) + p[15, b] * z2) / (c0 + c2)
            out[t, b] = p[1, b] * y + c0 * dw  # eq. 5
            state[0, b] = y
            state[1, b] = w
            state[2, b] = z1
            state[3, b] = z2
            state[4, b] = x1
            state[5, b] = u1
            state[6, b] = n_sub
    return n_bad


def warm_up() -> None:
    """Compile (or load from cache) every kernel once, e.g. before timing."""
    z = np.zeros((2, 1))
    linear_kernel(z, z, 1.0, 1.0, np.empty_like(z))
    for h2 in (0, 2):
        narx_kernel(
            z,
            z,
            np.zeros((1 + 2 + 2, 1)),
            2,
            2,
            0.0,
            1.0,
            0.0,
            1.0,
            np.zeros((3, 5)),
            np.zeros(3),
            np.zeros((h2, 3)),
            np.zeros(h2),
            np.zeros(h2 or 3),
            0.0,
            0.0,
            0.0,
            np.empty_like(z),
        )
    from bushenv.models import narx_kernels  # generated per network shape, see there

    narx_kernels.warm_up()
    p = np.ones((len(BW_ORDER), 1))
    boucwen_kernel(z, z, np.zeros((BW_N_STATE, 1)), p, 1e-3, BW_MAX_SUBSTEPS, np.empty_like(z))
