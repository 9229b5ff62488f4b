"""Compiled free-run kernels shared by every model's ``step`` and ``simulate``.

Each kernel takes (T, B) arrays of displacement and velocity, a state array (n_state, B) that
it updates in place, the model's parameters, and writes forces into a (T, B) ``out``. The loop
over the B profiles is innermost so numba vectorises it. ``cache=True`` keeps the compiled code
on disk: the first import compiles (seconds), later ones load.

Every column b of the state evolves from its own inputs and parameters only, so a batch of B
histories gives, bit for bit, what B separate runs give.
"""

from __future__ import annotations

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
# The models run the kernels generated per network shape in narx_kernels.py; this generic one
# is their reference (they give its bits: tests/models/test_narx_kernels.py).
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


# ----- Bouc-Wen (seed 002 eqs. 1-5): in boucwen_kernels.py, re-exported here ---------------
from bushenv.models.boucwen.kernels import (  # noqa: E402, F401
    BW_MAX_SUBSTEPS,
    BW_N_STATE,
    boucwen_kernel,
)
from bushenv.models.boucwen.reference import boucwen_fixed_step  # noqa: E402, F401
from bushenv.models.boucwen.tables import BW_ORDER, BW_RTOL, prepare  # noqa: E402, F401


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
    p = np.ones((1, len(BW_ORDER)))
    tabs, bc, _ = prepare(p, 1e-3, BW_RTOL)
    index = np.array([[0], [1]], dtype=np.int64)
    boucwen_kernel(
        z, z, np.zeros((BW_N_STATE, 1)), tabs, bc, index, 1e-3, BW_MAX_SUBSTEPS, np.empty_like(z)
    )
