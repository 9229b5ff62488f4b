"""Relaxation: viscoelastic memory with a broad spectrum of relaxation times."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import signal

from bushenv.diagnose.effects.base import Effect, Scales, Signals

PER_DECADE = 3  # Maxwell branches per decade of relaxation time
TAU_MIN_S = 1e-2  # shorter times look like damping and a negative mass (a delay)
TAU_MAX_S = 1e4
RICH_PER_DECADE = 6  # the richest form: twice as dense, from 5 ms to 10 x the longest record
RICH_TAU_MIN_S = 5e-3
RICH_SPAN = 10.0
EXAMPLE_BRANCHES = ((0.1, 0.5), (1.0, 0.3))  # (tau_s, k_i / k) of a typical rubber


def maxwell_state(x: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """h with h' = v - h / tau from rest: x minus its first-order low-pass (exact for x linear
    between samples, trapezoidal in x). Units m."""
    a = np.exp(-dt / tau)
    b = np.array([(1 - a) / 2, (1 - a) / 2])
    return x - signal.lfilter(b, [1.0, -a], x)


def tau_grid_s(
    scales: Scales, tau_min_s: float = TAU_MIN_S, span: float = 2.0, per_decade: int = PER_DECADE
) -> np.ndarray:
    """Relaxation times from max(2 dt, ``tau_min_s``) to ``span`` x the longest record,
    ``per_decade`` per decade (s)."""
    lo = max(2.0 * scales.dt, tau_min_s)
    hi = min(max(span * scales.duration_s, 4.0 * lo), TAU_MAX_S)
    n = int(np.floor(np.log10(hi / lo) * per_decade)) + 1
    return lo * 10.0 ** (np.arange(n) / per_decade)


class Relaxation(Effect):
    """A relaxation spectrum: ``sum_i k_i h_i``, ``h_i' = v - h_i / tau_i`` (Maxwell branches).

    The relaxation times cover the records' time scale densely (three per decade, from 10 ms
    or 2 dt to twice the longest record; shorter ones act as a damper and a negative mass,
    like a delay), so any smooth spectrum -- power-law, stretched
    exponential, log-normal, off-grid Prony -- is a non-negative combination of them; the
    relaxation modulus ``G(t) = sum_i k_i exp(-t / tau_i)`` is monotone by construction.
    """

    name = "relaxation"
    form = (
        "sum_i k_i h_i, h_i' = v - h_i / tau_i; tau_i 3 per decade from max(2 dt, 10 ms) "
        "to 2 x the longest record"
    )
    weights = "k_i >= 0 (N/m)"
    telling_test = (
        "a step held for longer than its time scale (the force decays at constant deflection)"
    )

    def columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        return np.stack([maxwell_state(s.x, s.dt, t) for t in tau_grid_s(scales)], axis=1)

    def rich_columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        taus = tau_grid_s(scales, RICH_TAU_MIN_S, RICH_SPAN, RICH_PER_DECADE)
        return np.stack([maxwell_state(s.x, s.dt, t) for t in taus], axis=1)

    def example(self, scales: Scales, k_n_per_m: float) -> tuple[Any, np.ndarray]:
        """Two branches, k_i = 0.5 k and 0.3 k, at the grid's times nearest 0.1 s and 1 s."""
        taus = tau_grid_s(scales)
        w = np.zeros(taus.size)
        for tau, share in EXAMPLE_BRANCHES:
            w[np.argmin(np.abs(np.log(taus / tau)))] += share * k_n_per_m
        return None, w

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        taus = tau_grid_s(scales)
        keep = w > 1e-9 * max(float(np.max(np.abs(w))), 1e-300)
        t_eval = [t for t in (0.01, 0.1, 1.0, 10.0, 100.0, 1000.0) if t <= 2 * taus[-1]]
        out: dict[str, Any] = {
            "spectrum": [
                {"tau_s": float(t), "k_n_per_m": float(k)}
                for t, k in zip(taus[keep], w[keep], strict=True)
            ],
            "relaxing_stiffness_n_per_m": float(np.sum(w)),
            "relaxation_modulus_n_per_m": {
                f"{t:g}_s": float(np.sum(w * np.exp(-t / taus))) for t in t_eval
            },
        }
        if np.sum(w) > 0:
            # mean of log10(tau) weighted by k: where the spectrum lies
            out["median_tau_s"] = float(10 ** (np.sum(w * np.log10(taus)) / np.sum(w)))
        return out
