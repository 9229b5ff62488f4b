"""Thermal: stiffness and damping lost as the specimen heats by its own dissipation."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import signal

from bushenv.diagnose.effects.base import Effect, Scales, Signals

TIME_CONSTANTS_S = (10.0, 30.0, 100.0, 300.0, np.inf)
RICH_TIME_CONSTANTS_S = (5.0, 10.0, 20.0, 30.0, 60.0, 100.0, 200.0, 300.0, 600.0, 1000.0, np.inf)
HEATING = ("viscous", "hysteretic")  # heat input ~ v^2 (a damper) or ~ |v| (friction)
EXAMPLE_LOSS = 0.3  # stiffness lost by the end of the longest record
EXAMPLE_DAMPING_S = 0.01  # the damping lost with it, as for c = k x 10 ms


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


def cooling(s: Signals, tau: float, offset_s: float = 0.0) -> np.ndarray:
    """exp(-(t + offset) / tau) over the record (1 throughout without a leak)."""
    if np.isinf(tau):
        return np.ones(s.x.size)
    return np.exp(-(np.arange(s.x.size) * s.dt + offset_s) / tau)


def session_heat(s: Signals, tau: float, heating: str, v_rms: float) -> np.ndarray:
    """The record's heat with what the session's records run before it left: their heat at
    their end, cooled over the rest, cools on through this record (a session's unknown start
    is the per-record block's)."""
    theta = heating_state(s.v, s.dt, tau, heating, v_rms)
    if s.before is None:
        return theta
    return theta + end_heat(*s.before, tau, heating, v_rms) * cooling(s, tau)


def end_heat(s: Signals, rest_s: float, tau: float, heating: str, v_rms: float) -> float:
    """The heat a record leaves after ``rest_s`` of rest (remembered per record)."""
    key = ("thermal_end", tau, heating, v_rms)
    if key not in s.memo:
        s.memo[key] = float(session_heat(s, tau, heating, v_rms)[-1])
    return s.memo[key] * (1.0 if np.isinf(tau) else np.exp(-rest_s / tau))


def warm_heat(tau: float, scales: Scales) -> float:
    """The steady heat (m^2/s) at TRAIN's RMS velocity with a leak of ``tau``: the unit of a
    warm start (a record that starts at this heat has run long enough to settle)."""
    return scales.v_rms**2 * tau


class Thermal(Effect):
    """``-theta (b_k x + b_c v)``: self-heating softens the spring and the damper.

    theta integrates a heating power (viscous ``v^2`` or hysteretic ``|v|``) with a leak to
    ambient of time constant ``tau_th``; a record may start warm (a heat that cools with the same
    leak, its stiffness and damping losses at the start fitted). Both heating laws and five
    time constants are tried.
    """

    name = "thermal"
    form = (
        "-theta (b_k x + b_c v) - exp(-t / tau_th) (s_k x + s_c v), theta' = P - theta / tau_th, "
        "P = v^2 or abs(v) v_rms (s_k, s_c: lost at the start of a record that starts warm, "
        "each record its own; with a run order theta is carried over the rests and a session "
        "has one start)"
    )
    weights = "b_k, b_c >= 0; s_k, s_c >= 0 per record"
    telling_test = (
        "a long constant-amplitude sine with rests (a stiffness that falls while it runs "
        "and recovers in the rests)"
    )
    shape_text = (
        "tau_th in {10, 30, 100, 300, inf} s x heating {viscous, hysteretic}, tau_th refined "
        "between the finite values by a bounded 1-D search"
    )
    continuous_shape = True  # the leak: a start's cooling is read through it

    def shapes(self, scales: Scales) -> list:
        return [(h, t) for h in HEATING for t in TIME_CONSTANTS_S]

    def shape_value(self, shape: Any) -> float:
        return float(shape[1])

    def with_shape_value(self, shape: Any, value: float) -> Any:
        return (shape[0], float(value))

    def columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        heating, tau = shape
        theta = session_heat(s, tau, heating, scales.v_rms)
        return np.stack([-theta * s.x, -theta * s.v], axis=1)

    def nuisance_columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        """A record that starts warm cools with the same leak: its stiffness and damping lost
        at the start, its own (records run in any order start at different heats). In a
        session the start is the session's, cooled until the record begins; none if the
        session began cold."""
        tau = shape[1] if isinstance(shape, tuple) else shape
        if not np.isfinite(tau):
            return np.zeros((s.x.size, 0))
        warm = cooling(s, tau, s.session_time_s) * warm_heat(tau, scales)
        if s.session_cold:
            warm = np.zeros_like(warm)
        return np.stack([-warm * s.x, -warm * s.v], axis=1)

    def rich_shapes(self, scales: Scales) -> list:
        return list(RICH_TIME_CONSTANTS_S)

    def rich_columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        """Both heating laws at once, on a finer time-constant grid."""
        return np.concatenate([self.columns(s, (h, shape), scales) for h in HEATING], axis=1)

    def example(self, scales: Scales, k_n_per_m: float) -> tuple[Any, np.ndarray]:
        """Viscous heating without a leak: 30 % of the stiffness (and of a damping of
        k x 10 ms) lost by the end of the longest record at its RMS velocity."""
        heat = scales.v_rms**2 * scales.duration_s  # theta at the end, m^2/s
        b_k = EXAMPLE_LOSS * k_n_per_m / heat
        return ("viscous", np.inf), np.array([b_k, EXAMPLE_DAMPING_S * b_k])

    def describe(self, shape: Any) -> str:
        if not isinstance(shape, tuple):  # the richest form: both heating laws
            return f"thermal (viscous and hysteretic heating, tau_th={shape:g} s)"
        return f"thermal ({shape[0]} heating, tau_th={shape[1]:g} s)"

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        return {
            "heating": shape[0],
            "time_constant_s": float(shape[1]),
            "stiffness_loss_n_per_m_per_heat": float(w[0]),
            "damping_loss_ns_per_m_per_heat": float(w[1]),
            "heat_unit": "m^2/s (integral of v^2 or |v| v_rms)",
        }

    def nuisance_parameters(self, shape: Any, scales: Scales, ws: list) -> dict[str, Any]:
        """Each record's stiffness and damping lost at its start (its own warm start)."""
        unit = warm_heat(shape[1], scales) if np.isfinite(shape[1]) else 0.0
        k = [float(w[0] * unit) for w in ws if len(w)]
        c = [float(w[1] * unit) for w in ws if len(w)]
        return {
            "stiffness_lost_at_start_n_per_m": float(np.mean(k)) if k else 0.0,
            "damping_lost_at_start_ns_per_m": float(np.mean(c)) if c else 0.0,
            "stiffness_lost_at_start_per_record_n_per_m": k,
        }
