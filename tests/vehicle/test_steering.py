"""Steering inputs: ISO 7401 step and pulse, the NHTSA fishhook, ISO 3888-1 (vehicle.steering)."""

import math

import numpy as np
import pytest

from bushenv.errors import BadInput
from bushenv.vehicle.single_track import (
    DEFAULT_VEHICLE,
    GRAVITY_M_PER_S2,
    single_track_response,
)
from bushenv.vehicle.steering import (
    FISHHOOK_RATE_DEG_PER_S,
    ISO7401_MAX_RISE_S,
    ISO7401_SPEED_M_PER_S,
    fishhook_rad,
    fishhook_reference_angle_deg,
    iso3888_1_gates,
    iso3888_1_lane_change,
    iso7401_amplitude_deg,
    pulse_steer_rad,
    step_steer_rad,
)

DT = 0.001


def test_step_steer_ramps_at_its_rate_to_the_amplitude_that_gives_4_m_per_s2():
    u = step_steer_rad(DT, 8.0)
    amp = math.radians(iso7401_amplitude_deg())
    assert u[: int(1.0 / DT) + 1].max() == 0.0 and u[-1] == pytest.approx(amp)
    slope = np.diff(u) / DT
    assert math.degrees(slope.max()) == pytest.approx(500.0, rel=1e-9)
    # 10-90 % rise within ISO 7401's 0.15 s
    t10, t90 = (np.argmax(u >= f * amp) * DT for f in (0.1, 0.9))
    assert t90 - t10 == pytest.approx(0.8 * iso7401_amplitude_deg() / 500.0, abs=2 * DT)
    assert t90 - t10 <= ISO7401_MAX_RISE_S
    # the default car then settles at ISO 7401's 4 m/s^2 at 80 km/h
    out = single_track_response(u, DT, ISO7401_SPEED_M_PER_S)
    assert out.lateral_acceleration_m_per_s2[-1] == pytest.approx(4.0, rel=1e-4)


def test_pulse_steer_is_a_triangle_of_its_width_and_amplitude():
    u = pulse_steer_rad(DT, 4.0, amplitude_deg=30.0, width_s=0.4, start_s=1.0)
    t = np.arange(u.size) * DT
    assert math.degrees(u.max()) == pytest.approx(30.0)
    assert t[np.argmax(u)] == pytest.approx(1.2, abs=DT)
    assert np.all(u[(t <= 1.0) | (t >= 1.4)] == 0)
    assert np.sum(u) * DT == pytest.approx(math.radians(30.0) * 0.4 / 2, rel=1e-3)


def test_fishhook_follows_nhtsa_shape_rate_dwell_and_hold():
    a = 20.0
    u = np.degrees(fishhook_rad(DT, 10.0, reference_angle_deg=a, dwell_s=0.25))
    t = np.arange(u.size) * DT
    assert u.max() == pytest.approx(6.5 * a) and u.min() == pytest.approx(-6.5 * a)
    assert np.abs(np.diff(u) / DT).max() == pytest.approx(FISHHOOK_RATE_DEG_PER_S, rel=1e-9)
    at_peak = t[np.isclose(u, 6.5 * a)]
    assert at_peak[-1] - at_peak[0] == pytest.approx(0.25, abs=2 * DT)
    at_counter = t[np.isclose(u, -6.5 * a)]
    assert at_counter[-1] - at_counter[0] == pytest.approx(3.0, abs=2 * DT)
    assert u[-1] == 0.0  # returned to zero (0.5 + 0.18 + 0.25 + 0.36 + 3 + 2 s < 10 s)
    right_first = np.degrees(fishhook_rad(DT, 10.0, reference_angle_deg=a, direction=-1))
    np.testing.assert_allclose(right_first, -u)


def test_fishhook_reference_angle_gives_0_3_g_at_50_mph_on_the_model():
    a = fishhook_reference_angle_deg()
    assert a == pytest.approx(19.22, abs=0.01)
    speed = 50 * 0.44704
    held = step_steer_rad(0.005, 15.0, amplitude_deg=a, start_s=0.5)
    out = single_track_response(held, 0.005, speed)
    assert out.lateral_acceleration_m_per_s2[-1] == pytest.approx(0.3 * GRAVITY_M_PER_S2, rel=1e-4)


def test_iso3888_lanes_have_the_standards_lengths_and_widths():
    g1, g3, g5 = iso3888_1_gates(width_m=1.8)
    assert (g1.x_end_m - g1.x_start_m, g3.x_start_m - g1.x_end_m) == (15.0, 30.0)
    assert (g3.x_end_m - g3.x_start_m, g5.x_start_m - g3.x_end_m) == (25.0, 25.0)
    assert g5.x_end_m - g5.x_start_m == 15.0
    widths = [g.y_left_m - g.y_right_m for g in (g1, g3, g5)]
    np.testing.assert_allclose(widths, [1.1 * 1.8 + 0.25, 1.2 * 1.8 + 0.25, 1.3 * 1.8 + 0.25])
    assert g3.y_right_m - g1.y_right_m == pytest.approx(3.5) and g5.y_right_m == g1.y_right_m


def test_generated_lane_change_keeps_the_car_inside_every_lane_at_80_kmh():
    run = iso3888_1_lane_change(0.01)
    half = DEFAULT_VEHICLE.width_m / 2
    clearance = []
    for g in run.gates:
        inside = (run.x_m >= g.x_start_m) & (run.x_m <= g.x_end_m)
        y = run.y_m[inside]
        clearance.append(min((y - half - g.y_right_m).min(), (g.y_left_m - y - half).min()))
    assert min(clearance) > 0.05  # measured 0.12 m with the 0.5 s preview
    assert np.abs(run.y_m - run.path_y_m).max() < 0.4
    u = run.steering_wheel_angle_rad
    assert u[0] == 0.0 and abs(math.degrees(u[-1])) < 0.5
    # the open-loop steering through the model: a severe but linear-range manoeuvre
    out = single_track_response(u, 0.01, 80 / 3.6)
    peak = np.abs(out.lateral_acceleration_m_per_s2).max()
    assert 4.0 < peak < 8.0
    again = iso3888_1_lane_change(0.01)
    np.testing.assert_array_equal(again.steering_wheel_angle_rad, u)


@pytest.mark.parametrize(
    "call, needle",
    [
        (lambda: step_steer_rad(0.0, 1.0), "dt_s"),
        (lambda: step_steer_rad(0.01, 1.0, rate_deg_per_s=-5.0), "rate_deg_per_s"),
        (lambda: pulse_steer_rad(0.01, 1.0, width_s=0.0), "width_s"),
        (lambda: fishhook_rad(0.01, 1.0, direction=2), "direction=2"),
        (lambda: fishhook_rad(0.01, 1.0, reference_angle_deg=float("nan")), "reference_angle"),
        (lambda: iso3888_1_lane_change(0.01, speed_m_per_s=0.0), "speed_m_per_s"),
        (lambda: iso3888_1_gates(width_m=-1.0), "width_m"),
    ],
)
def test_bad_arguments_are_refused_naming_the_value(call, needle):
    with pytest.raises(BadInput) as info:
        call()
    assert needle in str(info.value)
