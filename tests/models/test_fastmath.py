import math

import numba as nb
import numpy as np

from bushenv.models.fastmath import tanh


@nb.njit(error_model="numpy")
def _apply(a, out):
    for i in range(a.size):
        out[i] = tanh(a[i])


def test_fast_tanh_matches_libm_to_1e_14_everywhere():
    x = np.concatenate(
        [np.linspace(-25, 25, 400_001), [0.0, -0.0, 1e-300, -1e-12, 1e-8, 19.0, 700.0, -1e308]]
    )
    out = np.empty_like(x)
    _apply(x, out)
    ref = np.array([math.tanh(v) for v in x])
    assert np.max(np.abs(out - ref)) < 1e-14
    assert np.all(np.abs(out) <= 1.0)


def test_fast_tanh_is_odd_and_keeps_nan_and_saturates_inf():
    x = np.array([0.3, -0.3, np.nan, np.inf, -np.inf])
    out = np.empty_like(x)
    _apply(x, out)
    assert out[0] == -out[1]
    assert np.isnan(out[2])
    assert out[3] == 1.0 and out[4] == -1.0
