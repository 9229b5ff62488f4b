"""fastpow: arithmetic |a| ** n (log/exp from bits and polynomials) against libm."""

import numba as nb
import numpy as np

from bushenv.models.fastpow import exp_, log_pos, pow_abs

EPS = 2.220446049250313e-16


@nb.njit(error_model="numpy")
def _pow(a, n, out):
    for i in range(a.size):
        out[i] = pow_abs(a[i], n[i])


@nb.njit(error_model="numpy")
def _pow_libm(a, n, out):
    for i in range(a.size):
        out[i] = abs(a[i]) ** n[i]


@nb.njit(error_model="numpy")
def _log(a, out):
    for i in range(a.size):
        out[i] = log_pos(a[i])


@nb.njit(error_model="numpy")
def _exp(a, out):
    for i in range(a.size):
        out[i] = exp_(a[i])


def test_log_is_within_one_ulp_of_numpy_over_the_whole_positive_range():
    rng = np.random.default_rng(0)
    a = np.concatenate([10 ** rng.uniform(-307, 308, 500_000), [5e-324, 2.2250738585072014e-308]])
    a = np.concatenate([a, 10 ** rng.uniform(-320, -308, 1000)])  # subnormals
    out = np.empty_like(a)
    _log(a, out)
    ref = np.log(a)
    assert np.max(np.abs(out - ref) / np.abs(ref)) < 1.2 * EPS
    near1 = rng.uniform(np.exp(-1), np.e, 500_000)
    out = np.empty_like(near1)
    _log(near1, out)
    assert np.max(np.abs(out - np.log(near1))) < 1.2 * EPS


def test_exp_is_within_one_ulp_and_underflows_and_overflows_like_libm():
    rng = np.random.default_rng(1)
    y = rng.uniform(-708.0, 709.0, 500_000)
    out = np.empty_like(y)
    _exp(y, out)
    ref = np.exp(y)
    assert np.max(np.abs(out - ref) / ref) < 1.2 * EPS
    sub = np.linspace(-745.0, -709.0, 10_001)  # subnormal results: within one subnormal step
    out = np.empty_like(sub)
    _exp(sub, out)
    assert np.max(np.abs(out - np.exp(sub))) <= 5e-324
    big = np.array([709.79, 720.0, 1e5, -746.0, -1e5])
    out = np.empty_like(big)
    _exp(big, out)
    assert np.array_equal(out, [np.inf, np.inf, np.inf, 0.0, 0.0])


def test_pow_abs_relative_error_is_bounded_by_the_rounding_of_n_log_a():
    rng = np.random.default_rng(2)
    a = 10 ** rng.uniform(-14, 1, 1_000_000) * rng.choice([-1.0, 1.0], 1_000_000)
    n = rng.uniform(0.3, 3.0, 1_000_000)
    out = np.empty_like(a)
    _pow(a, n, out)
    ref = np.abs(a) ** n
    rel = np.abs(out - ref) / ref
    bound = (np.abs(n * np.log(np.abs(a))) + 4.0) * 2.3e-16  # the module docstring's bound
    assert np.all(rel <= bound)
    assert rel.max() < 2e-14  # the Bouc-Wen range |z| >= 1e-14, n <= 3


def test_pow_abs_special_values_follow_c99_pow():
    a = np.array([0, 0, 0, -0.0, np.inf, np.inf, np.inf, -np.inf, np.nan, np.nan, 1, 1, 0, 2])
    a = np.concatenate([a, [-1.0, 1e300, 1e-300, 3.0, 0.5]]).astype(float)
    n = np.array([2, -2, 0, 0.5, 2, -2, 0, 1.5, 0, 2, np.nan, 5, np.nan, np.nan])
    n = np.concatenate([n, [7.3, 2.0, 2.0, np.inf, -np.inf]]).astype(float)
    out = np.empty_like(a)
    ref = np.empty_like(a)
    _pow(a, n, out)
    _pow_libm(a, n, ref)
    assert np.array_equal(out, ref, equal_nan=True)


def test_pow_abs_gives_the_same_bits_in_a_vectorised_loop_and_one_element_at_a_time():
    rng = np.random.default_rng(3)
    a = 10 ** rng.uniform(-10, 0, 4099)
    n = rng.uniform(0.5, 2.5, 4099)
    out = np.empty_like(a)
    _pow(a, n, out)  # long loop: SIMD body plus scalar remainder
    one = np.empty(1)
    for i in range(0, 4099, 97):
        _pow(a[i : i + 1], n[i : i + 1], one)
        assert one[0] == out[i]
