"""Linear single-track (bicycle) model and the quasi-static lateral load transfer on an axle.

Single-track model (Riekert & Schunck 1940; Rajamani 2012, *Vehicle Dynamics and Control*,
2nd ed., ch. 2, the bicycle model), constant speed V, small angles, linear tyres, ISO 8855
axes (x forward, y left, z up; a left turn has positive steer, yaw rate and lateral
acceleration)::

    m V (dbeta/dt + r) = F_yf + F_yr          F_yf = C_f (delta - beta - a r / V)
    I_z dr/dt = a F_yf - b F_yr               F_yr = C_r (-beta + b r / V)
    a_y = V (dbeta/dt + r) = (F_yf + F_yr) / m,   delta = delta_sw / i_s

with C_f, C_r the cornering stiffness of a whole axle (both tyres). ``single_track_response``
integrates it exactly for a steering-wheel angle that is linear between samples (first-order
hold: the matrix exponential of the system augmented with the input and its slope).
Steady state (Gillespie 1992, *Fundamentals of Vehicle Dynamics*, ch. 6, steady-state
cornering)::

    delta = L / R + K_us a_y,   K_us = m (b / C_f - a / C_r) / L        [rad per m/s^2]
    r / delta = V / (L + K_us V^2),   a_y / delta = V^2 / (L + K_us V^2)
    beta / delta = (b - m a V^2 / (L C_r)) / (L + K_us V^2)

Load transfer (Gillespie 1992, ch. 7-8, roll and lateral load transfer; Milliken & Milliken
1995, *Race Car Vehicle Dynamics*, ch. 18), the whole mass taken as sprung, a rigid body
rolling about the roll axis (height h_r under the CG, from the axles' roll-centre heights
h_rf, h_rr)::

    h_r = (b h_rf + a h_rr) / L,  h' = h - h_r
    phi = m a_y h' / (K_phi_f + K_phi_r - m g h')                 (steady roll angle)
    dF_zf = (K_phi_f phi + m a_y (b / L) h_rf) / t                (front axle)
    dF_zr = (K_phi_r phi + m a_y (a / L) h_rr) / t                (rear axle)

so that t (dF_zf + dF_zr) = m a_y h + m g h' phi (the overturning moment with the CG's roll
shift). A positive a_y (left turn) loads the right (outer) wheel: ``axle_wheel_loads_n``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import NamedTuple

import numpy as np
from scipy.linalg import expm

from bushenv.vehicle.checks import VehicleInputError, positive, signal_1d

__all__ = [
    "DEFAULT_VEHICLE",
    "GRAVITY_M_PER_S2",
    "SingleTrackResponse",
    "VehicleParams",
    "axle_wheel_loads_n",
    "discrete_single_track",
    "lateral_load_transfer_n",
    "roll_angle_rad",
    "single_track_response",
    "state_matrices",
    "steady_state_sideslip_gain",
    "steady_state_yaw_rate_gain_per_s",
    "steering_wheel_angle_for_lateral_acceleration_rad",
    "understeer_gradient_rad_per_m_per_s2",
]

GRAVITY_M_PER_S2 = 9.80665


@dataclass(frozen=True)
class VehicleParams:
    """A passenger car for the single-track model and the load transfer (SI units).

    Defaults: mass, yaw inertia, a, b and the cornering stiffnesses are Rajamani (2012),
    *Vehicle Dynamics and Control*, 2nd ed., the passenger car of its ch. 3 lane-keeping
    simulations (m 1573 kg, I_z 2873 kg m^2, l_f 1.1 m, l_r 1.58 m, C_alpha 80 000 N/rad per
    tyre, so 160 000 N/rad per axle). Track and total roll stiffness are Table 4 of "Adaptive
    coordinated path tracking control strategy for autonomous vehicles with direct yaw moment
    control", Chin. J. Mech. Eng. (2021), doi:10.1186/s10033-021-00666-0 (a 1610 kg car: track
    1.565 m, roll stiffness 145 330 N m/rad; the table swaps the stiffness and damping
    labels). Not in either source, our choice within Gillespie's (1992) passenger-car ranges:
    steering ratio 16, CG height 0.55 m, roll-centre heights 0.05 m front / 0.10 m rear, 60 %
    of the roll stiffness at the front, width 1.8 m.
    """

    mass_kg: float = 1573.0
    yaw_inertia_kg_m2: float = 2873.0
    a_m: float = 1.10  # CG to front axle
    b_m: float = 1.58  # CG to rear axle
    front_cornering_n_per_rad: float = 160_000.0  # both front tyres
    rear_cornering_n_per_rad: float = 160_000.0  # both rear tyres
    steering_ratio: float = 16.0  # steering-wheel angle / road-wheel angle
    track_m: float = 1.565  # both axles
    width_m: float = 1.80  # body width, for the ISO 3888-1 lanes
    cg_height_m: float = 0.55
    front_roll_centre_height_m: float = 0.05
    rear_roll_centre_height_m: float = 0.10
    roll_stiffness_n_m_per_rad: float = 145_330.0  # front + rear
    front_roll_stiffness_share: float = 0.60

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name.endswith("roll_centre_height_m"):
                if not (math.isfinite(value) and value < self.cg_height_m):
                    raise VehicleInputError(
                        f"{f.name}={value!r} must be finite and below cg_height_m="
                        f"{self.cg_height_m!r}"
                    )
            else:
                positive(f.name, value)
        if not self.front_roll_stiffness_share < 1:
            raise VehicleInputError(
                f"front_roll_stiffness_share={self.front_roll_stiffness_share!r} must be in (0, 1)"
            )

    @property
    def wheelbase_m(self) -> float:
        """L = a + b."""
        return self.a_m + self.b_m


DEFAULT_VEHICLE = VehicleParams()


class SingleTrackResponse(NamedTuple):
    """The single-track model's outputs, each (T,)."""

    lateral_acceleration_m_per_s2: np.ndarray
    yaw_rate_rad_per_s: np.ndarray
    sideslip_rad: np.ndarray
    front_lateral_force_n: np.ndarray  # both front tyres
    rear_lateral_force_n: np.ndarray  # both rear tyres


def understeer_gradient_rad_per_m_per_s2(p: VehicleParams = DEFAULT_VEHICLE) -> float:
    """K_us = m (b / C_f - a / C_r) / L in rad of road-wheel angle per m/s^2 (> 0: understeer).

    Examples
    --------
    >>> round(math.degrees(understeer_gradient_rad_per_m_per_s2()) * 9.80665, 3)  # deg/g
    0.989
    """
    m, L = p.mass_kg, p.wheelbase_m
    return m * (p.b_m / p.front_cornering_n_per_rad - p.a_m / p.rear_cornering_n_per_rad) / L


def steady_state_yaw_rate_gain_per_s(
    speed_m_per_s: float, p: VehicleParams = DEFAULT_VEHICLE
) -> float:
    """r / delta_sw = V / ((L + K_us V^2) i_s): yaw rate per steering-wheel angle, 1/s."""
    v = positive("speed_m_per_s", speed_m_per_s)
    k = understeer_gradient_rad_per_m_per_s2(p)
    return v / ((p.wheelbase_m + k * v * v) * p.steering_ratio)


def steady_state_sideslip_gain(speed_m_per_s: float, p: VehicleParams = DEFAULT_VEHICLE) -> float:
    """beta / delta_sw = (b - m a V^2 / (L C_r)) / ((L + K_us V^2) i_s), dimensionless."""
    v = positive("speed_m_per_s", speed_m_per_s)
    k = understeer_gradient_rad_per_m_per_s2(p)
    L = p.wheelbase_m
    num = p.b_m - p.mass_kg * p.a_m * v * v / (L * p.rear_cornering_n_per_rad)
    return num / ((L + k * v * v) * p.steering_ratio)


def steering_wheel_angle_for_lateral_acceleration_rad(
    lateral_acceleration_m_per_s2: float,
    speed_m_per_s: float,
    p: VehicleParams = DEFAULT_VEHICLE,
) -> float:
    """Steady-state steering-wheel angle for a lateral acceleration at a speed, in rad.

    ``delta_sw = i_s (L + K_us V^2) a_y / V^2``: how ISO 7401 (4 m/s^2) and the NHTSA
    fishhook (0.3 g) set their amplitudes, here from the linear model instead of a test.
    """
    v = positive("speed_m_per_s", speed_m_per_s)
    k = understeer_gradient_rad_per_m_per_s2(p)
    return p.steering_ratio * (p.wheelbase_m + k * v * v) * lateral_acceleration_m_per_s2 / v**2


def state_matrices(
    speed_m_per_s: float, p: VehicleParams = DEFAULT_VEHICLE
) -> tuple[np.ndarray, np.ndarray]:
    """Continuous ``dx/dt = A x + B delta_sw`` for x = (beta, r); A (2, 2), B (2,) per rad."""
    v = positive("speed_m_per_s", speed_m_per_s)
    m, iz, a, b = p.mass_kg, p.yaw_inertia_kg_m2, p.a_m, p.b_m
    cf, cr = p.front_cornering_n_per_rad, p.rear_cornering_n_per_rad
    A = np.array(
        [
            [-(cf + cr) / (m * v), (b * cr - a * cf) / (m * v * v) - 1.0],
            [(b * cr - a * cf) / iz, -(a * a * cf + b * b * cr) / (iz * v)],
        ]
    )
    B = np.array([cf / (m * v), a * cf / iz]) / p.steering_ratio  # per steering-wheel rad
    return A, B


def discrete_single_track(
    speed_m_per_s: float, dt_s: float, p: VehicleParams = DEFAULT_VEHICLE
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact first-order-hold discretisation of the state x = (beta, r).

    Returns ``(Phi, G0, G1)`` with ``x[k+1] = Phi x[k] + G0 u[k] + G1 (u[k+1] - u[k])`` for a
    steering-wheel angle u (rad) linear between samples: ``expm`` of the system augmented with
    u and its slope (Franklin, Powell & Workman, *Digital Control of Dynamic Systems*, §6.3).
    """
    v = positive("speed_m_per_s", speed_m_per_s)
    dt_s = positive("dt_s", dt_s)
    A, B = state_matrices(v, p)
    M = np.zeros((4, 4))
    M[:2, :2], M[:2, 2], M[2, 3] = A, B, 1.0 / dt_s
    E = expm(M * dt_s)
    return E[:2, :2], E[:2, 2], E[:2, 3]


def single_track_response(
    steering_wheel_angle_rad: np.ndarray,
    dt_s: float,
    speed_m_per_s: float,
    p: VehicleParams = DEFAULT_VEHICLE,
) -> SingleTrackResponse:
    """Lateral acceleration, yaw rate, sideslip and axle forces for a steering history.

    Parameters
    ----------
    steering_wheel_angle_rad : ndarray
        (T,) steering-wheel angle, linear between samples, starting from straight running
        (beta = r = 0 at sample 0).
    dt_s : float
        Sample time.
    speed_m_per_s : float
        Constant forward speed.
    p : VehicleParams

    Returns
    -------
    SingleTrackResponse
        Each field (T,), in the units its name gives.
    """
    u = signal_1d("steering_wheel_angle_rad", steering_wheel_angle_rad)
    v = positive("speed_m_per_s", speed_m_per_s)
    phi, g0, g1 = discrete_single_track(v, dt_s, p)
    x = np.zeros((u.size, 2))
    p00, p01, p10, p11 = phi.ravel().tolist()
    a0, a1, b0, b1 = g0[0] - g1[0], g0[1] - g1[1], g1[0], g1[1]
    beta = r = 0.0
    for k in range(u.size - 1):  # 2 x 2: plain floats are faster than numpy here
        beta, r = (
            p00 * beta + p01 * r + a0 * u[k] + b0 * u[k + 1],
            p10 * beta + p11 * r + a1 * u[k] + b1 * u[k + 1],
        )
        x[k + 1] = beta, r
    beta_all, r_all = x[:, 0], x[:, 1]
    delta = u / p.steering_ratio
    fyf = p.front_cornering_n_per_rad * (delta - beta_all - p.a_m * r_all / v)
    fyr = p.rear_cornering_n_per_rad * (-beta_all + p.b_m * r_all / v)
    return SingleTrackResponse((fyf + fyr) / p.mass_kg, r_all, beta_all, fyf, fyr)


def roll_angle_rad(lateral_acceleration_m_per_s2, p: VehicleParams = DEFAULT_VEHICLE):
    """Steady roll angle phi = m a_y h' / (K_phi - m g h'), rad (positive: right side down)."""
    a_y = np.asarray(lateral_acceleration_m_per_s2, dtype=float)
    h_arm = p.cg_height_m - _roll_axis_height_m(p)
    k_net = p.roll_stiffness_n_m_per_rad - p.mass_kg * GRAVITY_M_PER_S2 * h_arm
    if k_net <= 0:
        raise VehicleInputError(
            f"roll_stiffness_n_m_per_rad={p.roll_stiffness_n_m_per_rad!r} does not exceed "
            f"m g h' = {p.mass_kg * GRAVITY_M_PER_S2 * h_arm:.6g}: the body would roll over"
        )
    return p.mass_kg * a_y * h_arm / k_net


def _roll_axis_height_m(p: VehicleParams) -> float:
    return (p.b_m * p.front_roll_centre_height_m + p.a_m * p.rear_roll_centre_height_m) / (
        p.wheelbase_m
    )


def lateral_load_transfer_n(
    lateral_acceleration_m_per_s2, p: VehicleParams = DEFAULT_VEHICLE, axle: str = "front"
):
    """Quasi-static load moved from the left to the right wheel of one axle, in N.

    ``dF_z = (K_phi_axle phi + m a_y (other axle's lever / L) h_r_axle) / t`` (module doc):
    the elastic part through the axle's roll stiffness and the geometric part through its roll
    centre. Same shape as the lateral acceleration (m/s^2).
    """
    a_y = np.asarray(lateral_acceleration_m_per_s2, dtype=float)
    phi = roll_angle_rad(a_y, p)
    share = p.front_roll_stiffness_share
    if axle == "front":
        k, lever, h_rc = share, p.b_m, p.front_roll_centre_height_m
    elif axle == "rear":
        k, lever, h_rc = 1.0 - share, p.a_m, p.rear_roll_centre_height_m
    else:
        raise VehicleInputError(f"axle={axle!r}: use 'front' or 'rear'")
    elastic = k * p.roll_stiffness_n_m_per_rad * phi
    geometric = p.mass_kg * a_y * lever / p.wheelbase_m * h_rc
    return (elastic + geometric) / p.track_m


def axle_wheel_loads_n(
    lateral_acceleration_m_per_s2, p: VehicleParams = DEFAULT_VEHICLE, axle: str = "front"
) -> np.ndarray:
    """Vertical loads on the axle's left and right wheels, (..., 2) in N (column 0 left).

    Static share of the weight (``m g b / L`` on the front axle) split evenly, minus the
    transfer on the left and plus it on the right. Not clipped at zero: a negative load is a
    wheel the quasi-static formula would lift (the half car decides lift-off itself).
    """
    transfer = lateral_load_transfer_n(lateral_acceleration_m_per_s2, p, axle)
    lever = p.b_m if axle == "front" else p.a_m
    static = 0.5 * p.mass_kg * GRAVITY_M_PER_S2 * lever / p.wheelbase_m
    return np.stack([static - transfer, static + transfer], axis=-1)
