"""Thermal: stiffness and damping lost as the specimen heats by its own dissipation, with one
or several time scales, from a cold or a warm start."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import signal

from bushenv.diagnose.effects.base import Effect, Scales, Signals

TIME_CONSTANTS_S = (10.0, 30.0, 100.0, 300.0, np.inf)
HEATING = ("viscous", "hysteretic")  # heat input ~ v^2 (a damper) or ~ |v| (friction)


def heating_state(v: np.ndarray, dt: float, tau: float, heating: str, v_rms: float) -> np.ndarray:
    """theta' = P - theta / tau from rest (tau = inf: cumulative), in m^2/s.

    P = v^2 for viscous heating, |v| v_rms for hysteretic (friction-like) heating; v_rms of the
    identification records keeps both in the same units.
    """
    p = v * v if heating == "viscous" else np.abs(v) * v_rms
    if np.isinf(tau):
        return np.cumsum(p) * dt
    a = np.exp(-dt / tau)
    return signal.lfilter([dt], [1.0, -a], p)


def _warm_start(v: np.ndarray, dt: float, tau: float, heating: str, v_rms: float) -> np.ndarray:
    """The heat a record starts with when it was running before as it starts, decaying:
    theta_0 exp(-t / tau) with theta_0 = tau x its mean heating power over the first tau
    (a record cut from a longer run starts warm), in m^2/s."""
    p = v * v if heating == "viscous" else np.abs(v) * v_rms
    first = p[: max(int(round(tau / dt)), 1)]
    return tau * float(np.mean(first)) * np.exp(-np.arange(v.size) * dt / tau)


class Thermal(Effect):
    """``-sum_j theta_j (b_kj x + b_cj v)``: self-heating softens the spring and the damper.

    Each ``theta_j`` integrates a heating power (viscous ``v^2`` or hysteretic ``|v|``) with a
    leak to ambient of time constant ``tau_j`` (10 s .. no leak), all at once with weights
    >= 0: a heat balance with one or several time scales. A record may start cold or warm
    (``theta_j(0)`` that of the same power running before, decaying with ``tau_j``): both
    terms are columns, so the weights say which. Both heating laws are tried.
    """

    name = "thermal"
    form = (
        "-sum_j theta_j (b_kj x + b_cj v), theta_j' = P - theta_j / tau_j, tau_j = 10, 30, "
        "100, 300 s and inf; P = v^2 or abs(v) v_rms; from cold and from warm (theta_j(0) = "
        "tau_j mean P)"
    )
    weights = "b_kj, b_cj >= 0"
    telling_test = (
        "a long constant-amplitude sine with rests (a stiffness that falls while it runs "
        "and recovers in the rests)"
    )
    shape_text = "heating {viscous, hysteretic}"

    def shapes(self, scales: Scales) -> list:
        return list(HEATING)

    def columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        cols = []
        for tau in TIME_CONSTANTS_S:
            theta = heating_state(s.v, s.dt, tau, shape, scales.v_rms)
            cols += [-theta * s.x, -theta * s.v]
            if np.isfinite(tau):
                warm = _warm_start(s.v, s.dt, tau, shape, scales.v_rms)
                cols += [-warm * s.x, -warm * s.v]
        return np.stack(cols, axis=1)

    def columns_count(self, shape: Any, scales: Scales) -> int:
        return 2 * len(TIME_CONSTANTS_S) + 2 * sum(np.isfinite(t) for t in TIME_CONSTANTS_S)

    def describe(self, shape: Any) -> str:
        return f"thermal ({shape} heating)"

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        out, i = [], 0
        for tau in TIME_CONSTANTS_S:
            term = {"time_constant_s": float(tau)}
            term["stiffness_loss_n_per_m_per_heat"] = float(w[i])
            term["damping_loss_ns_per_m_per_heat"] = float(w[i + 1])
            i += 2
            if np.isfinite(tau):
                term["warm_start_stiffness_loss_n_per_m_per_heat"] = float(w[i])
                term["warm_start_damping_loss_ns_per_m_per_heat"] = float(w[i + 1])
                i += 2
            out.append(term)
        return {
            "heating": shape,
            "time_scales": out,
            "heat_unit": "m^2/s (integral of v^2 or |v| v_rms)",
        }
