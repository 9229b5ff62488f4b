"""The compiled step of the planar NARX networks (``narx.py``), shared by ``step`` and ``simulate``.

As the one-axis ``bushenv.models.kernels.narx_kernel``: the loop over the B histories is
innermost, in tiles that keep the hidden layer in L1, so numba vectorises it; every column
evolves from its own inputs only, so a batch gives, bit for bit, what B separate runs give.
The state layout is ``PlanarNarx``'s (rows 0..14 past scaled coordinates, lags 1..5, axis
fastest; rows 15..29 past scaled outputs, lags 1..5).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from bushenv.models.fastmath import tanh
from bushenv.models.kernels import JIT

TILE = 128  # histories per tile (z, h: 61 KB, in L2); measured best of 32-256


@nb.njit(**{**JIT, "fastmath": {"contract"}})
def planar_narx_kernel(  # pragma: no cover - compiled
    q, v, state, q_offset, q_scale, f_offset, f_scale, w1, b1, w_out, b_out, k, c, out
):
    """out[t, b] = K q + C v + f_offset + f_scale * net(z); z = scaled q_t, then the state.

    ``q``, ``v``, ``out`` (T, B, 3); ``state`` (30, B) updated in place; ``w1`` (H, 33),
    ``w_out`` (3, H); ``k``, ``c`` (3, 3) (zeros for the pure network).
    """
    T, B, _ = q.shape
    n_state = state.shape[0]
    nq = n_state // 2
    n_in = w1.shape[1]
    hn = w1.shape[0]
    z = np.empty((n_in, TILE))
    h = np.empty((hn, TILE))
    y = np.empty((3, TILE))
    for lo in range(0, B, TILE):
        n = min(TILE, B - lo)
        for t in range(T):
            for i in range(3):
                for b in range(n):
                    z[i, b] = (q[t, lo + b, i] - q_offset[i]) / q_scale[i]
            for r in range(n_state):
                for b in range(n):
                    z[3 + r, b] = state[r, lo + b]
            for u in range(hn):
                for b in range(n):
                    h[u, b] = b1[u]
            # three units x three inputs per pass: each z row loaded once for three units, each
            # h row stored once per three inputs (the loop's memory traffic, not its arithmetic,
            # set the speed)
            h3 = hn - hn % 3
            for u in range(0, h3, 3):
                for i in range(0, n_in, 3):
                    a0, a1, a2 = w1[u, i], w1[u, i + 1], w1[u, i + 2]
                    b0, b1_, b2 = w1[u + 1, i], w1[u + 1, i + 1], w1[u + 1, i + 2]
                    c0, c1, c2 = w1[u + 2, i], w1[u + 2, i + 1], w1[u + 2, i + 2]
                    for b in range(n):
                        za, zb, zc = z[i, b], z[i + 1, b], z[i + 2, b]
                        h[u, b] += a0 * za + a1 * zb + a2 * zc
                        h[u + 1, b] += b0 * za + b1_ * zb + b2 * zc
                        h[u + 2, b] += c0 * za + c1 * zb + c2 * zc
            for u in range(h3, hn):
                for i in range(0, n_in, 3):
                    a0, a1, a2 = w1[u, i], w1[u, i + 1], w1[u, i + 2]
                    for b in range(n):
                        h[u, b] += a0 * z[i, b] + a1 * z[i + 1, b] + a2 * z[i + 2, b]
            for u in range(hn):
                for b in range(n):
                    h[u, b] = tanh(h[u, b])
            for i in range(3):
                for b in range(n):
                    y[i, b] = b_out[i]
                for u in range(hn):
                    wo = w_out[i, u]
                    for b in range(n):
                        y[i, b] += wo * h[u, b]
            for i in range(3):
                for b in range(n):
                    f = f_offset[i] + f_scale[i] * y[i, b]
                    for j in range(3):
                        f += k[i, j] * q[t, lo + b, j] + c[i, j] * v[t, lo + b, j]
                    out[t, lo + b, i] = f
            # shift the two histories by one lag (newest first), as PlanarNarx's state reads
            for r in range(nq - 1, 2, -1):
                for b in range(n):
                    state[r, lo + b] = state[r - 3, lo + b]
                    state[nq + r, lo + b] = state[nq + r - 3, lo + b]
            for i in range(3):
                for b in range(n):
                    state[i, lo + b] = z[i, b]
                    state[nq + i, lo + b] = y[i, b]


@nb.njit(**JIT)
def planar_linear_kernel(q, v, k, c, out):  # pragma: no cover - compiled
    """out = K q + C v per sample and history; ``q``, ``v``, ``out`` (T, B, 3)."""
    T, B, _ = q.shape
    for t in range(T):
        for b in range(B):
            for i in range(3):
                f = 0.0
                for j in range(3):
                    f += k[i, j] * q[t, b, j] + c[i, j] * v[t, b, j]
                out[t, b, i] = f
