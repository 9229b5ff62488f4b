"""The linear single-track model and the quasi-static load transfer (vehicle.single_track)."""

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import signal
from scipy.integrate import solve_ivp

from bushenv.errors import BadInput
from bushenv.vehicle.single_track import (
    DEFAULT_VEHICLE,
    GRAVITY_M_PER_S2,
    VehicleParams,
    axle_wheel_loads_n,
    discrete_single_track,
    lateral_load_transfer_n,
    roll_angle_rad,
    single_track_response,
    steady_state_sideslip_gain,
    steady_state_yaw_rate_gain_per_s,
    steering_wheel_angle_for_lateral_acceleration_rad,
    understeer_gradient_rad_per_m_per_s2,
)

P = DEFAULT_VEHICLE


def _held_step(amplitude_rad, dt, duration_s):
    u = np.full(round(duration_s / dt), amplitude_rad)
    u[0] = 0.0
    return u


@pytest.mark.parametrize("speed_kmh", [30, 80, 120])
def test_steady_state_yaw_rate_sideslip_and_acceleration_match_the_analytic_gains(speed_kmh):
    v = speed_kmh / 3.6
    out = single_track_response(_held_step(0.3, 0.01, 20.0), 0.01, v)
    assert out.yaw_rate_rad_per_s[-1] == pytest.approx(
        0.3 * steady_state_yaw_rate_gain_per_s(v), rel=1e-9
    )
    assert out.sideslip_rad[-1] == pytest.approx(0.3 * steady_state_sideslip_gain(v), rel=1e-9)
    # circular motion: a_y = V r
    assert out.lateral_acceleration_m_per_s2[-1] == pytest.approx(
        v * out.yaw_rate_rad_per_s[-1], rel=1e-9
    )
    # and steady yaw moment balance: a F_yf = b F_yr
    assert P.a_m * out.front_lateral_force_n[-1] == pytest.approx(
        P.b_m * out.rear_lateral_force_n[-1], rel=1e-9
    )


def test_understeer_gradient_from_simulated_steady_states_equals_the_formula():
    # delta = L / R + K_us a_y with R = V / r: K_us from two simulated steady states
    k_formula = understeer_gradient_rad_per_m_per_s2(P)
    assert k_formula == pytest.approx(1573 * (1.58 - 1.1) / 160_000 / 2.68, rel=1e-12)
    for v in (15.0, 35.0):
        out = single_track_response(_held_step(0.2, 0.01, 20.0), 0.01, v)
        r, a_y = out.yaw_rate_rad_per_s[-1], out.lateral_acceleration_m_per_s2[-1]
        delta = 0.2 / P.steering_ratio
        assert (delta - P.wheelbase_m * r / v) / a_y == pytest.approx(k_formula, rel=1e-8)


def test_yaw_gain_peaks_at_the_characteristic_speed_and_oversteer_is_negative():
    v = np.linspace(5, 60, 5501)
    gains = [steady_state_yaw_rate_gain_per_s(x) for x in v]
    v_char = math.sqrt(P.wheelbase_m / understeer_gradient_rad_per_m_per_s2(P))
    assert v[int(np.argmax(gains))] == pytest.approx(v_char, abs=0.01)
    oversteer = replace(P, front_cornering_n_per_rad=160_000.0, rear_cornering_n_per_rad=90_000.0)
    assert understeer_gradient_rad_per_m_per_s2(oversteer) < 0


def test_amplitude_for_a_lateral_acceleration_inverts_the_steady_gain():
    v = 80 / 3.6
    sw = steering_wheel_angle_for_lateral_acceleration_rad(4.0, v)
    out = single_track_response(_held_step(sw, 0.01, 15.0), 0.01, v)
    assert out.lateral_acceleration_m_per_s2[-1] == pytest.approx(4.0, rel=1e-9)
    assert math.degrees(sw) == pytest.approx(26.36, abs=0.01)  # the default car at 80 km/h


def test_discretisation_is_exact_for_a_piecewise_linear_steer():
    # first-order hold is exact for inputs linear between samples: the same ramp sampled at
    # 10 ms and at 1 ms gives the same states at the common instants
    v = 25.0
    coarse_t = np.arange(0, 3, 0.01)
    fine_t = np.arange(0, 3, 0.001)
    ramp = lambda t: np.interp(t, [0, 0.2, 0.5, 3], [0, 0.0, 0.4, 0.4])  # noqa: E731
    coarse = single_track_response(ramp(coarse_t), 0.01, v)
    fine = single_track_response(ramp(fine_t), 0.001, v)
    np.testing.assert_allclose(coarse.yaw_rate_rad_per_s, fine.yaw_rate_rad_per_s[::10], atol=1e-12)
    np.testing.assert_allclose(coarse.sideslip_rad, fine.sideslip_rad[::10], atol=1e-12)


def test_response_matches_an_independent_ode_solution_of_the_equations():
    v, dt = 22.0, 0.005
    t = np.arange(0, 4, dt)
    u = 0.5 * np.sin(2 * np.pi * 0.7 * t) * (t < 2.5)
    m, iz, a, b = P.mass_kg, P.yaw_inertia_kg_m2, P.a_m, P.b_m
    cf, cr, i_s = P.front_cornering_n_per_rad, P.rear_cornering_n_per_rad, P.steering_ratio

    def rhs(time, x):
        delta = np.interp(time, t, u) / i_s
        fyf = cf * (delta - x[0] - a * x[1] / v)
        fyr = cr * (-x[0] + b * x[1] / v)
        return [(fyf + fyr) / (m * v) - x[1], (a * fyf - b * fyr) / iz]

    ref = solve_ivp(rhs, (0, t[-1]), [0, 0], t_eval=t, rtol=1e-10, atol=1e-12, max_step=dt / 4)
    out = single_track_response(u, dt, v)
    scale = np.abs(ref.y[1]).max()
    np.testing.assert_allclose(out.yaw_rate_rad_per_s, ref.y[1], atol=1e-6 * scale)
    # and scipy's lsim (linear interpolation of the input) agrees to rounding
    A = np.array([[-(cf + cr) / (m * v), (b * cr - a * cf) / (m * v * v) - 1],
                  [(b * cr - a * cf) / iz, -(a * a * cf + b * b * cr) / (iz * v)]])  # fmt: skip
    B = np.array([[cf / (m * v)], [a * cf / iz]]) / i_s
    _, y, _ = signal.lsim((A, B, np.eye(2), np.zeros((2, 1))), u, t)
    np.testing.assert_allclose(out.sideslip_rad, y[:, 0], atol=1e-12)


def test_discrete_matrices_are_stable_and_the_response_is_deterministic():
    phi, _, _ = discrete_single_track(30.0, 0.01)
    assert np.max(np.abs(np.linalg.eigvals(phi))) < 1
    u = np.sin(np.linspace(0, 10, 500))
    a = single_track_response(u, 0.01, 30.0)
    b = single_track_response(u, 0.01, 30.0)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)
    # m a_y = F_yf + F_yr at every sample
    np.testing.assert_allclose(
        P.mass_kg * a.lateral_acceleration_m_per_s2,
        a.front_lateral_force_n + a.rear_lateral_force_n,
        rtol=1e-12,
    )


def test_roll_angle_balances_the_roll_moment_about_the_roll_axis():
    a_y = np.array([-4.0, 0.0, 2.0, 6.0])
    phi = roll_angle_rad(a_y)
    h_r = (P.b_m * P.front_roll_centre_height_m + P.a_m * P.rear_roll_centre_height_m) / (
        P.wheelbase_m
    )
    h_arm = P.cg_height_m - h_r
    m, k = P.mass_kg, P.roll_stiffness_n_m_per_rad
    np.testing.assert_allclose(k * phi, m * a_y * h_arm + m * GRAVITY_M_PER_S2 * h_arm * phi)
    assert phi[2] > 0  # left turn: right side down
    # the default car: about 3 deg per g
    assert math.degrees(roll_angle_rad(GRAVITY_M_PER_S2)) == pytest.approx(3.07, abs=0.01)


def test_axle_transfers_add_up_to_the_overturning_moment():
    a_y = np.linspace(-6, 6, 7)
    front = lateral_load_transfer_n(a_y, P, "front")
    rear = lateral_load_transfer_n(a_y, P, "rear")
    h_r = (P.b_m * P.front_roll_centre_height_m + P.a_m * P.rear_roll_centre_height_m) / (
        P.wheelbase_m
    )
    moment = P.mass_kg * a_y * P.cg_height_m + P.mass_kg * GRAVITY_M_PER_S2 * (
        P.cg_height_m - h_r
    ) * roll_angle_rad(a_y)
    np.testing.assert_allclose(P.track_m * (front + rear), moment, rtol=1e-12, atol=1e-9)


def test_equal_roll_centres_and_a_stiffness_split_by_weight_give_the_axle_weight_share():
    p = replace(
        P,
        front_roll_centre_height_m=0.08,
        rear_roll_centre_height_m=0.08,
        front_roll_stiffness_share=P.b_m / P.wheelbase_m,
    )
    a_y = 5.0
    total = p.mass_kg * a_y * p.cg_height_m + p.mass_kg * GRAVITY_M_PER_S2 * (
        p.cg_height_m - 0.08
    ) * roll_angle_rad(a_y, p)
    assert lateral_load_transfer_n(a_y, p) == pytest.approx(
        p.b_m / p.wheelbase_m * total / p.track_m, rel=1e-12
    )


def test_wheel_loads_keep_the_axle_load_and_move_it_to_the_outer_wheel():
    loads = axle_wheel_loads_n(np.array([0.0, 4.0, -4.0]))
    assert loads.shape == (3, 2)
    static_axle = P.mass_kg * GRAVITY_M_PER_S2 * P.b_m / P.wheelbase_m
    np.testing.assert_allclose(loads.sum(axis=1), static_axle)
    assert loads[0, 0] == loads[0, 1]
    assert loads[1, 1] > loads[1, 0] and loads[2, 0] > loads[2, 1]


@pytest.mark.parametrize(
    "call, needle",
    [
        (lambda: VehicleParams(mass_kg=-1.0), "mass_kg"),
        (lambda: VehicleParams(front_roll_stiffness_share=1.2), "front_roll_stiffness_share"),
        (lambda: VehicleParams(front_roll_centre_height_m=0.9), "front_roll_centre_height_m"),
        (lambda: single_track_response(np.zeros(10), 0.01, 0.0), "speed_m_per_s"),
        (lambda: single_track_response(np.array([0.0, np.inf]), 0.01, 10.0), "[1]"),
        (lambda: lateral_load_transfer_n(1.0, P, "middle"), "axle='middle'"),
        (lambda: roll_angle_rad(1.0, replace(P, roll_stiffness_n_m_per_rad=100.0)), "roll over"),
    ],
)
def test_bad_arguments_are_refused_naming_the_value(call, needle):
    with pytest.raises(BadInput) as info:
        call()
    assert needle in str(info.value)
