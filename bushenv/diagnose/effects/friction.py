"""Friction: rate-independent hysteresis and amplitude-dependent stiffness (the Payne effect)."""

from __future__ import annotations

from typing import Any

import numba as nb
import numpy as np

from bushenv.diagnose.effects.base import Effect, Scales, Signals

DAHL_FRACTIONS = np.array([0.003, 0.01, 0.03, 0.1, 0.3, 1.0])  # x_j / sigma_x
PAYNE_MEMORY_S = (2.0, 20.0)  # decay times of the amplitude envelope
RICH_FRACTIONS = np.geomspace(0.001, 3.0, 15)  # the richest form: a denser, wider Iwan set
RICH_MEMORY_S = (0.5, 2.0, 8.0, 30.0, 120.0)
EXAMPLE_SLIP = (0.03, 0.45)  # slip length / sigma_x, slip force / (k sigma_x)


@nb.njit(cache=True, nogil=True)
def dahl_states(x, xs, out):  # pragma: no cover - compiled
    """Rate-independent Dahl elements: dz/dx = (sgn(dx) - z) / xs, exact per displacement step."""
    T = x.shape[0]
    J = xs.shape[0]
    for j in range(J):
        out[0, j] = 0.0
    for t in range(1, T):
        dx = x[t] - x[t - 1]
        if dx == 0.0:
            for j in range(J):
                out[t, j] = out[t - 1, j]
            continue
        sgn = 1.0 if dx > 0 else -1.0
        adx = abs(dx)
        for j in range(J):
            out[t, j] = sgn - (sgn - out[t - 1, j]) * np.exp(-adx / xs[j])


@nb.njit(cache=True, nogil=True)
def amplitude_envelope(x, decay):  # pragma: no cover - compiled
    """Peak hold of |x| that decays by ``decay`` per sample: the recent amplitude (m)."""
    out = np.empty(x.size)
    e = 0.0
    for t in range(x.size):
        e = max(abs(x[t]), e * decay)
        out[t] = e
    return out


def _friction_columns(s: Signals, scales: Scales, fractions, memories_s) -> np.ndarray:
    xs = np.asarray(fractions) * scales.sigma_x
    out = np.empty((s.x.size, xs.size + len(memories_s)))
    dahl = np.empty((s.x.size, xs.size))
    dahl_states(s.x, xs, dahl)
    out[:, : xs.size] = dahl
    for m, tau in enumerate(memories_s):
        env = amplitude_envelope(s.x, float(np.exp(-s.dt / tau)))
        out[:, xs.size + m] = -s.x * env / scales.sigma_x
    return out


class Friction(Effect):
    """Dahl elements of several slip lengths plus stiffness lost with the recent amplitude.

    ``sum_j F_j z_j`` with ``dz_j/dx = (sgn dx - z_j) / x_j`` (a discrete Iwan distribution of
    Dahl elements: the loop, its rounding at reversals and the secant stiffness falling with
    amplitude), and ``-sum_m q_m x A_m / sigma_x`` with ``A_m`` the amplitude envelope (peak of
    ``|x|`` decaying over 2 s and 20 s): a stiffness that falls with the recent amplitude and
    recovers slowly, without a loop -- the Payne effect where it differs from friction.
    """

    name = "friction"
    shows_dissipation = True
    holds_its_law = True  # a law of the deflection's history: the same at every moment
    form = (
        "sum_j F_j z_j, dz_j/dx = (sgn dx - z_j)/x_j, x_j = sigma_x {0.003..1}; "
        "- sum_m q_m x A_m / sigma_x, A_m = envelope of abs(x) (2 s, 20 s)"
    )
    weights = "F_j >= 0 (N), q_m >= 0 (N/m)"
    telling_test = (
        "sines at one amplitude and rates a decade apart (a loop that does not change "
        "with rate) and at several amplitudes"
    )

    def columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        return _friction_columns(s, scales, DAHL_FRACTIONS, PAYNE_MEMORY_S)

    def rich_columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        return _friction_columns(s, scales, RICH_FRACTIONS, RICH_MEMORY_S)

    def example(self, scales: Scales, k_n_per_m: float) -> tuple[Any, np.ndarray]:
        """One stiff element (slip at 3 % of sigma_x, slip force 0.45 k sigma_x): nearly a
        Jenkins element, a loop with sharp corners; no amplitude softening."""
        w = np.zeros(DAHL_FRACTIONS.size + len(PAYNE_MEMORY_S))
        fraction, force = EXAMPLE_SLIP
        w[int(np.argmin(np.abs(DAHL_FRACTIONS - fraction)))] = force * k_n_per_m * scales.sigma_x
        return None, w

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        xs = DAHL_FRACTIONS * scales.sigma_x
        n = xs.size
        return {
            "elements": [
                {"slip_length_m": float(x), "slip_force_n": float(f)}
                for x, f in zip(xs, w[:n], strict=True)
                if f > 0
            ],
            "slip_force_total_n": float(np.sum(w[:n])),
            "amplitude_softening_n_per_m_per_m": {
                f"memory_{tau:g}_s": float(q / scales.sigma_x)
                for tau, q in zip(PAYNE_MEMORY_S, w[n:], strict=True)
            },
        }
