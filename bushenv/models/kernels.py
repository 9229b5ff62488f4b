"""Compiled free-run kernels shared by every model's ``step`` and ``simulate``.

Each kernel takes (T, B) arrays of displacement and velocity, a state array (n_state, B) that
it updates in place, the model's parameters, and writes forces into a (T, B) ``out``. The loop
over the B profiles is innermost so numba vectorises it. ``cache=True`` keeps the compiled code
on disk: the first import compiles (seconds), later ones load.
"""

from __future__ import annotations

import numba as nb
import numpy as np

JIT = dict(cache=True, fastmath=False, nogil=True)


@nb.njit(**JIT)
def linear_kernel(x, v, k, c, out):  # pragma: no cover - compiled
    T, B = x.shape
    for t in range(T):
        for b in range(B):
            out[t, b] = k * x[t, b] + c * v[t, b]


def warm_up() -> None:
    """Compile (or load from cache) every kernel once, e.g. before timing."""
    z = np.zeros((2, 1))
    linear_kernel(z, z, 1.0, 1.0, np.empty_like(z))
