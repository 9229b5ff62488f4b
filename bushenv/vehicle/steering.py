"""Open-loop steering inputs: ISO 7401 step and pulse, the NHTSA fishhook, ISO 3888-1 lane change.

Every generator returns the steering-wheel angle (T,) in rad at ``t = i * dt_s``,
``T = round(duration_s / dt_s)``, positive to the left (ISO 8855); the standards' own units
(deg, deg/s) are the parameters' units. Amplitudes set by a lateral acceleration come from the
linear single-track model (``single_track.steering_wheel_angle_for_lateral_acceleration_rad``),
standing in for the standards' preliminary steady-state or slowly-increasing-steer tests.

| generator                 | standard                        | parameters (defaults)      |
|---------------------------|---------------------------------|----------------------------|
| ``step_steer_rad``        | ISO 7401:2011 step input        | amplitude, rate 500 deg/s  |
| ``pulse_steer_rad``       | ISO 7401:2011 pulse (triangle)  | amplitude, width 0.4 s     |
| ``fishhook_rad``          | NHTSA Roll Rate Feedback hook   | A, 6.5 A, 720 deg/s, dwell |
| ``iso3888_1_lane_change`` | ISO 3888-1 cones + a driver     | speed, width, preview time |

ISO 7401 (lateral transient response): 80 km/h (100 km/h optional), the steady-state lateral
acceleration of the step 4 m/s^2 (2 and 6 optional), the step applied as fast as possible (its
10-90 % rise within 0.15 s, ``ISO7401_MAX_RISE_S``: our reading of the text), the pulse a
triangle 0.3-0.5 s wide. Seed 000 §5.3.1 drives a pulse steer at 30 km/h (its shape only in
the missing Fig. 16).

NHTSA fishhook (49 CFR Part 575, NCAP rollover resistance, 68 FR 59250, Oct. 14 2003; the
manoeuvre from Forkenbrock et al. 2002, NHTSA DOT HS 809 513): A is the steering-wheel angle
giving 0.3 g in a slowly increasing steer at 50 mph; steer at 720 deg/s to 6.5 A, dwell, steer
at 720 deg/s to -6.5 A, hold 3 s, return to zero. In the Roll Rate Feedback version the dwell
ends when the roll rate falls below 1.5 deg/s; open loop, it is ``dwell_s`` here (the half car
can close that loop itself). Entry speeds 35-50 mph. Seed 000 §5.3.3 drives a fishhook too.

ISO 3888-1 (double lane change, severe manoeuvre): three lanes of cones, 15 m / 25 m / 15 m
long, separated by 30 m and 25 m, widths 1.1 b + 0.25, 1.2 b + 0.25 and 1.3 b + 0.25 m (b the
vehicle width); lane 3 offset 3.5 m to the left (``ISO3888_OFFSET_M``, taken here between the
right-hand cone lines of lanes 1 and 3; Project Chrono's ``demo_VEH_HMMWV_DoubleLaneChange``
measures it from lane 1's centre line instead), lane 5 sharing lane 1's right-hand line; 80
km/h. The standard has a driver steer; ``iso3888_1_lane_change`` generates the steering a
simple preview driver (pure pursuit, Coulter 1992, CMU-RI-TR-92-01, with the single-track
model's understeer in its gain) applies to follow the centre line at constant speed.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.linalg import expm

from bushenv.vehicle.checks import VehicleInputError, finite, nonnegative, positive, sample_count
from bushenv.vehicle.single_track import (
    DEFAULT_VEHICLE,
    GRAVITY_M_PER_S2,
    VehicleParams,
    state_matrices,
    steering_wheel_angle_for_lateral_acceleration_rad,
    understeer_gradient_rad_per_m_per_s2,
)

__all__ = [
    "FISHHOOK_FACTOR",
    "FISHHOOK_RATE_DEG_PER_S",
    "ISO3888_OFFSET_M",
    "ISO7401_MAX_RISE_S",
    "ISO7401_SPEED_M_PER_S",
    "Gate",
    "LaneChange",
    "fishhook_rad",
    "fishhook_reference_angle_deg",
    "iso3888_1_gates",
    "iso3888_1_lane_change",
    "iso7401_amplitude_deg",
    "pulse_steer_rad",
    "step_steer_rad",
]

ISO7401_SPEED_M_PER_S = 80 / 3.6
ISO7401_LATERAL_ACCELERATION_M_PER_S2 = 4.0
ISO7401_MAX_RISE_S = 0.15  # 10 % to 90 % of the step
FISHHOOK_RATE_DEG_PER_S = 720.0
FISHHOOK_FACTOR = 6.5
FISHHOOK_SIS_SPEED_M_PER_S = 50 * 0.44704  # 50 mph
ISO3888_OFFSET_M = 3.5
ISO3888_SPEED_M_PER_S = 80 / 3.6


def _time(dt_s: float, duration_s: float) -> np.ndarray:
    return np.arange(sample_count(duration_s, dt_s)) * dt_s


def iso7401_amplitude_deg(
    speed_m_per_s: float = ISO7401_SPEED_M_PER_S,
    lateral_acceleration_m_per_s2: float = ISO7401_LATERAL_ACCELERATION_M_PER_S2,
    p: VehicleParams = DEFAULT_VEHICLE,
) -> float:
    """Steering-wheel angle (deg) for ISO 7401's steady 4 m/s^2 at 80 km/h, by the linear model.

    Examples
    --------
    >>> round(iso7401_amplitude_deg(), 2)
    26.36
    """
    a = finite("lateral_acceleration_m_per_s2", lateral_acceleration_m_per_s2)
    return math.degrees(steering_wheel_angle_for_lateral_acceleration_rad(a, speed_m_per_s, p))


def fishhook_reference_angle_deg(p: VehicleParams = DEFAULT_VEHICLE) -> float:
    """A: the steering-wheel angle (deg) for 0.3 g at 50 mph, by the linear model (19.22 deg)."""
    return iso7401_amplitude_deg(FISHHOOK_SIS_SPEED_M_PER_S, 0.3 * GRAVITY_M_PER_S2, p)


def _ramps(t: np.ndarray, knots_s: list[float], values_deg: list[float]) -> np.ndarray:
    """Piecewise-linear angle through (knot, value) points, held after the last; rad."""
    return np.radians(np.interp(t, knots_s, values_deg))


def step_steer_rad(
    dt_s: float,
    duration_s: float,
    amplitude_deg: float | None = None,
    rate_deg_per_s: float = 500.0,
    start_s: float = 1.0,
) -> np.ndarray:
    """ISO 7401 step steer: 0 until ``start_s``, a ramp at ``rate_deg_per_s``, then held; rad.

    ``amplitude_deg`` None: ``iso7401_amplitude_deg()`` (4 m/s^2 at 80 km/h, default car).
    The 10-90 % rise is ``0.8 |amplitude| / rate``; ISO 7401 asks for at most 0.15 s.
    """
    amp = (
        iso7401_amplitude_deg() if amplitude_deg is None else finite("amplitude_deg", amplitude_deg)
    )
    rate = positive("rate_deg_per_s", rate_deg_per_s)
    start = nonnegative("start_s", start_s)
    t = _time(dt_s, duration_s)
    return _ramps(t, [start, start + abs(amp) / rate], [0.0, amp])


def pulse_steer_rad(
    dt_s: float,
    duration_s: float,
    amplitude_deg: float | None = None,
    width_s: float = 0.4,
    start_s: float = 1.0,
) -> np.ndarray:
    """ISO 7401 pulse steer: a triangle of base ``width_s`` peaking at ``amplitude_deg``; rad.

    Up over ``width_s / 2``, down over ``width_s / 2``, from ``start_s`` (ISO 7401: 0.3-0.5 s
    wide). ``amplitude_deg`` None: ``iso7401_amplitude_deg()``.
    """
    amp = (
        iso7401_amplitude_deg() if amplitude_deg is None else finite("amplitude_deg", amplitude_deg)
    )
    width = positive("width_s", width_s)
    start = nonnegative("start_s", start_s)
    t = _time(dt_s, duration_s)
    return _ramps(t, [start, start + width / 2, start + width], [0.0, amp, 0.0])


def fishhook_rad(
    dt_s: float,
    duration_s: float,
    reference_angle_deg: float | None = None,
    dwell_s: float = 0.25,
    rate_deg_per_s: float = FISHHOOK_RATE_DEG_PER_S,
    factor: float = FISHHOOK_FACTOR,
    hold_s: float = 3.0,
    unwind_s: float = 2.0,
    start_s: float = 0.5,
    direction: int = 1,
) -> np.ndarray:
    """NHTSA fishhook: to ``factor * A`` and back through zero to ``-factor * A``; rad.

    From ``start_s``: steer at ``rate_deg_per_s`` to ``direction * factor * A``, hold
    ``dwell_s`` (open-loop stand-in for the Roll Rate Feedback dwell), steer at the same rate
    to ``-direction * factor * A``, hold ``hold_s`` (3 s), return to zero over ``unwind_s`` (our
    choice: 2 s). ``reference_angle_deg`` None: ``fishhook_reference_angle_deg()``.
    ``direction`` +1 steers left first, -1 right first.
    """
    a = (
        fishhook_reference_angle_deg()
        if reference_angle_deg is None
        else positive("reference_angle_deg", reference_angle_deg)
    )
    if direction not in (1, -1):
        raise VehicleInputError(f"direction={direction!r}: use 1 (left first) or -1 (right first)")
    peak = direction * positive("factor", factor) * a
    rate = positive("rate_deg_per_s", rate_deg_per_s)
    t0 = nonnegative("start_s", start_s)
    t1 = t0 + abs(peak) / rate
    t2 = t1 + nonnegative("dwell_s", dwell_s)
    t3 = t2 + 2 * abs(peak) / rate
    t4 = t3 + nonnegative("hold_s", hold_s)
    t5 = t4 + positive("unwind_s", unwind_s)
    t = _time(dt_s, duration_s)
    return _ramps(t, [t0, t1, t2, t3, t4, t5], [0.0, peak, peak, -peak, -peak, 0.0])


class Gate(NamedTuple):
    """One lane of cones: from ``x_start_m`` to ``x_end_m`` between two cone lines (y, m)."""

    x_start_m: float
    x_end_m: float
    y_right_m: float
    y_left_m: float


class LaneChange(NamedTuple):
    """A generated ISO 3888-1 run: the steering and the path it drives, each (T,)."""

    steering_wheel_angle_rad: np.ndarray
    x_m: np.ndarray  # distance from lane 1's entry
    y_m: np.ndarray  # CG's lateral position, left positive
    path_y_m: np.ndarray  # the centre line the driver follows, at x_m
    gates: tuple[Gate, Gate, Gate]


def iso3888_1_gates(
    width_m: float = DEFAULT_VEHICLE.width_m, offset_m: float = ISO3888_OFFSET_M
) -> tuple[Gate, Gate, Gate]:
    """The three lanes of ISO 3888-1 for a vehicle ``width_m`` wide; lane 1 entry at x = 0."""
    b = positive("width_m", width_m)
    offset = positive("offset_m", offset_m)
    w1, w3, w5 = 1.1 * b + 0.25, 1.2 * b + 0.25, 1.3 * b + 0.25
    right = -w1 / 2  # lane 1 centred on y = 0; lanes 1 and 5 share their right-hand line
    return (
        Gate(0.0, 15.0, right, right + w1),
        Gate(45.0, 70.0, right + offset, right + offset + w3),
        Gate(95.0, 110.0, right, right + w5),
    )


def _centre_line_m(x: np.ndarray, gates: tuple[Gate, Gate, Gate]) -> np.ndarray:
    """Lane centres joined by half-cosine transitions over the gaps between lanes."""
    centres = [(g.y_right_m + g.y_left_m) / 2 for g in gates]
    y = np.full(x.shape, centres[0])
    for i in range(len(gates) - 1):
        g0, g1, c0, c1 = gates[i], gates[i + 1], centres[i], centres[i + 1]
        u = np.clip((x - g0.x_end_m) / (g1.x_start_m - g0.x_end_m), 0.0, 1.0)
        y = np.where(x >= g0.x_end_m, c0 + (c1 - c0) * 0.5 * (1 - np.cos(np.pi * u)), y)
    return y


def iso3888_1_lane_change(
    dt_s: float,
    speed_m_per_s: float = ISO3888_SPEED_M_PER_S,
    p: VehicleParams = DEFAULT_VEHICLE,
    preview_s: float = 0.5,
    approach_m: float = 30.0,
    exit_m: float = 30.0,
    offset_m: float = ISO3888_OFFSET_M,
) -> LaneChange:
    """Steering a preview driver applies to drive the ISO 3888-1 lanes on the single-track model.

    The car starts ``approach_m`` before lane 1, straight and centred, and drives at constant
    ``speed_m_per_s`` to ``exit_m`` past lane 5. At each sample the driver looks
    ``l = speed * preview_s`` ahead and steers (pure pursuit with the model's understeer, small
    angles) ``delta_sw = i_s * 2 (L + K_us V^2) e / l^2``, e the centre line's lateral offset
    from where the car's heading points at that distance; the state (beta, r, heading, y) then
    advances by the exact zero-order-hold discretisation of the single-track model.

    Returns
    -------
    LaneChange
        The steering-wheel angle (rad), the CG path (x, y in m), the centre line at x, and
        the gates (for checks: the car's body, ``y +- width / 2``, inside each lane).
    """
    v = positive("speed_m_per_s", speed_m_per_s)
    dt_s = positive("dt_s", dt_s)
    look_m = v * positive("preview_s", preview_s)
    gates = iso3888_1_gates(p.width_m, offset_m)
    x0 = -nonnegative("approach_m", approach_m)
    duration_s = (gates[-1].x_end_m + nonnegative("exit_m", exit_m) - x0) / v
    count = sample_count(duration_s, dt_s)
    x = x0 + v * dt_s * np.arange(count)
    ahead = _centre_line_m(x + look_m, gates)
    # state (beta, r, psi, y): psi' = r, y' = V (psi + beta); exact ZOH over one sample
    A2, B2 = state_matrices(v, p)
    M = np.zeros((5, 5))
    M[:2, :2], M[:2, 4] = A2, B2
    M[2, 1], M[3, 0], M[3, 2] = 1.0, v, v
    E = expm(M * dt_s)
    phi, gamma = E[:4, :4], E[:4, 4]
    gain = p.steering_ratio * 2.0 * (p.wheelbase_m + understeer_gradient_rad_per_m_per_s2(p) * v**2)
    gain /= look_m**2
    state = np.zeros(4)
    u = np.zeros(count)
    y = np.zeros(count)
    for k in range(count):
        y[k] = state[3]
        u[k] = gain * (ahead[k] - state[3] - look_m * state[2])
        state = phi @ state + gamma * u[k]
    return LaneChange(u, x, y, _centre_line_m(x, gates), gates)
