"""Accuracy metrics as pure functions of arrays (measured ``f_exp``, predicted ``f_pre``).

Shapes: 1-D arrays of equal length T (or any equal shapes; all samples pooled). Percentages are
returned as fractions (0.051 means 5.1 %).

- ``rms_ratio``: seed 000 eq. 8; 1/T in both sums (seed 002 eq. 8 prints 1/2, a typo).
- ``esr``: seed 000 eq. 9, error variance over output variance (0 perfect, 1 = the mean).
- ``max_error``: largest absolute error, N; ``max_error_ratio``: that over max |f_exp|, which is how
  seed 000 Tables 2-3 report MAX in %.
- ``peak_error``: absolute difference of the largest absolute forces, N (seed 002 Table 4).
- ``nrmse`` and ``fit_index``: as the nonlinear_benchmarks package defines them
  (RMSE / std(y); fit = 100 (1 - NRMSE)).
"""

from __future__ import annotations

import numpy as np


def _pair(f_exp, f_pre) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(f_exp, dtype=np.float64)
    b = np.asarray(f_pre, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"measured shape {a.shape} differs from predicted shape {b.shape}")
    if a.size == 0:
        raise ValueError("metrics need at least one sample")
    return a, b


def rms(a) -> float:
    a = np.asarray(a, dtype=np.float64)
    return float(np.sqrt(np.mean(a * a)))


def rms_ratio(f_exp, f_pre) -> float:
    a, b = _pair(f_exp, f_pre)
    return rms(a - b) / rms(a)


def esr(f_exp, f_pre) -> float:
    a, b = _pair(f_exp, f_pre)
    return float(np.mean((a - b) ** 2) / np.mean((a - a.mean()) ** 2))


def max_error(f_exp, f_pre) -> float:
    a, b = _pair(f_exp, f_pre)
    return float(np.max(np.abs(a - b)))


def max_error_ratio(f_exp, f_pre) -> float:
    a, b = _pair(f_exp, f_pre)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(a)))


def peak_error(f_exp, f_pre) -> float:
    a, b = _pair(f_exp, f_pre)
    return float(abs(np.max(np.abs(a)) - np.max(np.abs(b))))


def nrmse(f_exp, f_pre) -> float:
    a, b = _pair(f_exp, f_pre)
    return rms(a - b) / float(np.std(a))


def fit_index(f_exp, f_pre) -> float:
    return 100.0 * (1.0 - nrmse(f_exp, f_pre))


def all_metrics(f_exp, f_pre) -> dict[str, float]:
    """Every metric above in one dict (keys are the function names)."""
    return {
        "rms_ratio": rms_ratio(f_exp, f_pre),
        "esr": esr(f_exp, f_pre),
        "max_error": max_error(f_exp, f_pre),
        "max_error_ratio": max_error_ratio(f_exp, f_pre),
        "peak_error": peak_error(f_exp, f_pre),
        "nrmse": nrmse(f_exp, f_pre),
        "fit_index": fit_index(f_exp, f_pre),
    }
