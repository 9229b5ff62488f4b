"""ISO 2631-1 weightings Wk and Wd against the standard's table (bushenv.vehicle.comfort)."""

import numpy as np
import pytest
from scipy import signal

from bushenv.errors import BadInput
from bushenv.vehicle.comfort import (
    WEIGHTINGS,
    vibration_dose_value,
    weighted_acceleration,
    weighted_rms,
    weighting_response,
)

# ISO 2631-1:1997 Table 3, weighting factors x 1000 at nominal one-third-octave centres (Hz)
TABLE3 = {
    "Wk": {
        0.1: 31.2, 0.5: 418, 1.0: 482, 2.0: 531, 2.5: 631, 3.15: 804, 4.0: 967, 5.0: 1039,
        6.3: 1054, 8.0: 1036, 10.0: 988, 12.5: 902, 16.0: 768, 31.5: 405, 63.0: 186,
        100.0: 88.7,
    },
    "Wd": {
        0.1: 62.4, 0.5: 853, 1.0: 1011, 1.25: 1008, 2.0: 890, 4.0: 512, 8.0: 253, 16.0: 125,
        31.5: 63.2, 63.0: 29.5, 100.0: 14.1,
    },
}  # fmt: skip


@pytest.mark.parametrize("name", ["Wk", "Wd"])
def test_weighting_factors_match_the_standards_table_3(name):
    # the standard rounds to 3 figures and tabulates at nominal centres: 2 % covers both
    f = np.array(list(TABLE3[name]))
    table = np.array(list(TABLE3[name].values())) / 1000
    np.testing.assert_allclose(np.abs(weighting_response(f, name)), table, rtol=0.02)


def test_measured_agreement_with_table_3_is_within_half_a_percent():
    worst = max(
        abs(abs(weighting_response(f, name)) * 1000 / v - 1)
        for name in TABLE3
        for f, v in TABLE3[name].items()
    )
    assert worst < 0.005


def test_wd_has_no_upward_step_and_wk_steps_up_from_f5_squared_over_f6_squared_to_one():
    from dataclasses import replace

    wk = WEIGHTINGS["Wk"]
    assert wk.f5_hz == 2.37 and wk.f6_hz == 3.35 and np.isinf(WEIGHTINGS["Wd"].f5_hz)
    no_step = replace(wk, f5_hz=np.inf, f6_hz=np.inf)
    step = np.abs(
        weighting_response([0.05, 100.0], "Wk") / weighting_response([0.05, 100.0], no_step)
    )
    np.testing.assert_allclose(step, [(2.37 / 3.35) ** 2, 1.0], rtol=2e-3)


@pytest.mark.parametrize("name, f_hz", [("Wk", 5.0), ("Wk", 1.0), ("Wd", 1.0), ("Wd", 8.0)])
def test_a_sine_is_weighted_by_the_modulus_at_its_frequency(name, f_hz):
    dt = 0.001
    t = np.arange(0, 60, dt)
    a = np.sqrt(2) * np.sin(2 * np.pi * f_hz * t)  # RMS 1 m/s^2
    aw = weighted_acceleration(a, dt, name)
    steady = aw[t.size // 4 : 3 * t.size // 4]  # away from the 0.4 Hz high pass's start-up
    expected = abs(weighting_response(f_hz, name))
    assert np.sqrt(np.mean(steady**2)) == pytest.approx(expected, rel=1e-3)
    # over the whole record the start-up transient costs < 1 %
    assert weighted_rms(a, dt, name) == pytest.approx(expected, rel=0.01)


def _analogue_polynomials(name):
    p = WEIGHTINGS[name]
    w = [2 * np.pi * x for x in (p.f1_hz, p.f2_hz, p.f3_hz, p.f4_hz)]
    q1 = 1 / np.sqrt(2)
    num = np.polymul([1, 0, 0], [w[1] ** 2])
    den = np.polymul([1, w[0] / q1, w[0] ** 2], [1, w[1] / q1, w[1] ** 2])
    num = np.polymul(num, [1 / w[2], 1])
    den = np.polymul(den, [1 / w[3] ** 2, 1 / (p.q4 * w[3]), 1])
    if np.isfinite(p.f5_hz):
        w5, w6 = 2 * np.pi * p.f5_hz, 2 * np.pi * p.f6_hz
        num = np.polymul(num, [1, w5 / p.q5, w5**2])
        den = np.polymul(den, [1, w6 / p.q6, w6**2])
    return num, den


@pytest.mark.parametrize("name", ["Wk", "Wd"])
def test_filtering_equals_a_time_domain_simulation_of_the_analogue_filter(name):
    # independent route: the standard's transfer function as polynomials, simulated by lsim
    dt = 0.0005
    t = np.arange(0, 20, dt)
    rng = np.random.default_rng(2631)
    b, a = signal.butter(4, 30, fs=1 / dt)
    x = signal.lfilter(b, a, rng.standard_normal(t.size))  # content well below Nyquist
    num, den = _analogue_polynomials(name)
    _, y_ref, _ = signal.lsim((num, den), x, t)
    y = weighted_acceleration(x, dt, name)
    assert np.sqrt(np.mean((y - y_ref) ** 2)) < 0.01 * np.sqrt(np.mean(y_ref**2))


def test_batched_columns_equal_single_runs_and_vdv_of_a_sine():
    dt = 0.002
    t = np.arange(0, 30, dt)
    a = np.column_stack([np.sin(2 * np.pi * 4 * t), 0.5 * np.sin(2 * np.pi * 2 * t)])
    both = weighted_rms(a, dt, "Wk")
    assert both.shape == (2,)
    assert both[1] == pytest.approx(weighted_rms(a[:, 1], dt, "Wk"), rel=1e-12)
    # VDV of a steady sine of weighted amplitude A over T: A (3 T / 8)^(1/4)
    amp = abs(weighting_response(4.0, "Wk"))
    assert vibration_dose_value(a[:, 0], dt, "Wk") == pytest.approx(
        amp * (3 * 30 / 8) ** 0.25, rel=0.01
    )


@pytest.mark.parametrize(
    "call, needle",
    [
        (lambda: weighting_response(1.0, "Wz"), "weighting='Wz'"),
        (lambda: weighted_rms(np.ones(10), 0.0, "Wk"), "dt_s"),
        (lambda: weighted_rms(np.ones((2, 2, 2)), 0.01, "Wk"), "shape (2, 2, 2)"),
        (lambda: weighted_rms(np.array([0.0, np.nan, 1.0]), 0.01, "Wk"), "not finite"),
    ],
)
def test_bad_arguments_are_refused_naming_the_value(call, needle):
    with pytest.raises(BadInput) as info:
        call()
    assert needle in str(info.value)
