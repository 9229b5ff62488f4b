import numpy as np
import pytest

from bushenv import excitation as ex
from bushenv.models.base import PAPER_DT

DT = PAPER_DT


def test_sine_has_requested_length_amplitude_and_frequency():
    x = ex.sine(10.0, 2e-3, 10.0, DT)
    assert x.shape == (2048,)
    assert np.max(np.abs(x)) == pytest.approx(2e-3, rel=1e-3)
    spectrum = np.abs(np.fft.rfft(x))
    assert np.fft.rfftfreq(x.size, DT)[np.argmax(spectrum)] == pytest.approx(10.0, abs=0.1)


def test_sine_offset_and_phase_shift_the_signal():
    x = ex.sine(1.0, 1e-3, 1.0, DT, phase=np.pi / 2, offset_m=5e-4)
    assert x[0] == pytest.approx(1.5e-3)


@pytest.mark.parametrize(
    ("family", "args"),
    [
        (ex.sine, (5.0, 3e-3, 2.0, DT)),
        (ex.chirp, (1.0, 20.0, 2e-3, 4.0, DT, "linear")),
        (ex.chirp, (1.0, 20.0, 2e-3, 4.0, DT, "logarithmic")),
        (ex.bump, (0.7, 5e-3, 30 / 3.6, DT)),
    ],
)
def test_analytic_velocity_matches_central_difference(family, args):
    x = family(*args)
    v = getattr(ex, family.__name__ + "_velocity")(*args)
    assert v.shape == x.shape
    inner = slice(5, -5)
    # central differences err by O((w dt)^2); 20 Hz at 204.8 Hz is ~15 %, so compare to 20 %.
    err = np.max(np.abs(np.gradient(x, DT)[inner] - v[inner]))
    assert err <= 0.2 * np.max(np.abs(v))


def test_log_chirp_sweeps_from_f0_to_f1():
    x = ex.chirp(2.0, 40.0, 1e-3, 8.0, 1 / 2048, method="logarithmic")
    half = x.size // 8
    f = np.fft.rfftfreq(half, 1 / 2048)
    start = f[np.argmax(np.abs(np.fft.rfft(x[:half])))]
    end = f[np.argmax(np.abs(np.fft.rfft(x[-half:])))]
    assert start < 4.0 and end > 25.0


def test_chirp_refuses_unknown_method():
    with pytest.raises(ex.ExcitationError, match="method"):
        ex.chirp(1.0, 2.0, 1e-3, 1.0, DT, method="cubic")


@pytest.mark.parametrize("n_index", [1.0, 1.5, 0.3])
def test_random_rpc_peak_is_n_times_2mm(n_index):
    x = ex.random_rpc(n_index, 40.0, DT, seed=3)
    assert x.shape == (8192,)
    assert np.max(np.abs(x)) == pytest.approx(n_index * 2e-3, rel=1e-12)


def test_random_rpc_is_deterministic_given_seed_and_index_only_scales():
    a = ex.random_rpc(1.0, 20.0, DT, seed=7)
    b = ex.random_rpc(1.0, 20.0, DT, seed=7)
    c = ex.random_rpc(1.0, 20.0, DT, seed=8)
    d = ex.random_rpc(1.5, 20.0, DT, seed=7)
    assert np.array_equal(a, b)
    assert not np.allclose(a, c)
    assert np.allclose(d, 1.5 * a, rtol=1e-12, atol=0)


def test_random_rpc_spectrum_lies_in_band_and_peaks_near_10_to_15_hz():
    x = ex.random_rpc(1.0, 200.0, DT, seed=0)
    f = np.fft.rfftfreq(x.size, DT)
    power = np.abs(np.fft.rfft(x)) ** 2
    assert power[f > 21.0].sum() < 1e-6 * power.sum()
    # smooth the periodogram over 1 Hz before locating the peak
    smooth = np.convolve(power, np.ones(200) / 200, mode="same")
    assert 9.0 <= f[np.argmax(smooth)] <= 16.0


def test_random_rpc_starts_and_ends_at_rest():
    x = ex.random_rpc(1.0, 20.0, DT, seed=1)
    assert x[0] == 0.0 and abs(x[-1]) < 1e-5
    assert np.max(np.abs(x[:20])) < 0.05 * np.max(np.abs(x))


def test_random_rpc_is_within_machine_limits_at_verification_index():
    ok, reason = ex.within_limits(ex.random_rpc(1.5, 40.0, DT, seed=0), DT)
    assert ok, reason


def test_random_ood_holds_offset_and_energy_beyond_training_band():
    x = ex.random_ood(40.0, DT, seed=0, band_hz=(30.0, 60.0), peak_m=1e-3, offset_m=3e-3)
    steady = x[int(2.0 / DT) : -int(2.0 / DT)]
    assert np.mean(steady) == pytest.approx(3e-3, abs=2e-4)
    f = np.fft.rfftfreq(steady.size, DT)
    power = np.abs(np.fft.rfft(steady - np.mean(steady))) ** 2
    assert power[f > 25.0].sum() > 0.9 * power.sum()
    assert x[0] == 0.0  # the offset ramps in, no jump at t = 0


def test_random_band_refuses_band_above_nyquist():
    with pytest.raises(ex.ExcitationError, match="Nyquist"):
        ex.random_band(1.0, DT, 0, band_hz=(150.0, 200.0))


def test_step_hold_is_the_papers_4mm_step_held_10s():
    x = ex.step_hold(4e-3, 10.0, DT, pre_s=0.5)
    t = np.arange(x.size) * DT
    assert x.size == round(10.5 / DT)
    assert np.all(x[t < 0.5 - 1e-12] == 0.0)
    assert np.all(x[t >= 0.5] == 4e-3)
    assert ex.within_limits(x, DT)[0]


def test_step_hold_with_rise_is_smooth_and_monotone():
    x = ex.step_hold(8e-3, 1.0, DT, pre_s=0.2, rise_s=0.05)
    assert np.all(np.diff(x) >= 0)
    assert x[-1] == 8e-3
    assert np.max(np.diff(x)) < 8e-3 / 4


def test_ramp_moves_linearly_then_holds():
    x = ex.ramp(5e-3, 1.0, 1 / 100, pre_s=0.5, hold_s=0.5)
    assert x.shape == (200,)
    assert x[:51].max() == 0.0
    assert np.allclose(np.diff(x[51:150]), 5e-3 / 100)
    assert np.all(x[150:] == 5e-3)


def test_pulse_returns_to_rest():
    x = ex.pulse(3e-3, 0.2, 1 / 1000, pre_s=0.1, post_s=0.3)
    assert x.shape == (600,)
    assert x[0] == 0.0 and x[-1] == 0.0
    assert np.count_nonzero(x == 3e-3) == 200
    smooth = ex.pulse(3e-3, 0.2, 1 / 1000, pre_s=0.1, post_s=0.3, edge_s=0.05)
    assert smooth.max() == pytest.approx(3e-3) and np.max(np.abs(np.diff(smooth))) < 3e-4


@pytest.mark.parametrize("length_m", ex.PAPER_BUMP_LENGTHS_M)
def test_bump_lasts_length_over_speed_and_peaks_at_height(length_m):
    speed = 30 / 3.6
    dt = 1 / 2048
    x = ex.bump(length_m, 10e-3, speed, dt, pre_s=0.1, post_s=0.2)
    assert x.shape == (round((0.3 + length_m / speed) / dt),)
    on = np.nonzero(x > 0)[0]
    assert (on[-1] - on[0] + 2) * dt == pytest.approx(length_m / speed, abs=2 * dt)
    assert x.max() == pytest.approx(10e-3, rel=1e-4)


def test_pothole_drops_to_depth_and_recovers():
    x = ex.pothole(0.5, 20e-3, 30 / 3.6, 1 / 2048, edge_m=0.05)
    assert x.min() == pytest.approx(-20e-3)
    assert x[0] == 0.0 and x[-1] == 0.0


def test_sequence_concatenates_segments_in_order():
    a = ex.step_hold(1e-3, 0.1, DT)
    b = ex.ramp(0.0, 0.1, DT, start_m=1e-3)
    s = ex.sequence(a, b)
    assert np.array_equal(s, np.concatenate([a, b]))
    with pytest.raises(ex.ExcitationError, match="segment 1"):
        ex.sequence(a, np.zeros((3, 2)))


def test_max_velocity_is_80hz_sine_at_a_tenth_of_the_stroke():
    assert ex.MAX_VELOCITY_M_PER_S == pytest.approx(2 * np.pi * 80 * 2.5e-3)
    assert ex.MAX_DISPLACEMENT_M == 12.5e-3


def test_within_limits_accepts_papers_programme_and_refuses_overstroke_and_overspeed():
    for f in (1, 5, 10, 15, 20):
        for a in (0.5e-3, 1e-3, 2e-3, 3e-3, 4e-3):
            assert ex.within_limits(ex.sine(f, a, 10.0, DT), DT) == (True, "")
    ok, reason = ex.within_limits(ex.sine(1.0, 13e-3, 2.0, DT), DT)
    assert not ok and "stroke" in reason and "12.59 mm" in reason
    ok, reason = ex.within_limits(ex.step_hold(10e-3, 1.0, DT), DT)
    assert not ok and "velocity" in reason
    ok, reason = ex.within_limits(np.array([0.0, np.nan]), DT)
    assert not ok and "nan" in reason


def test_clip_to_limits_makes_any_signal_drivable_and_leaves_good_ones_alone():
    rng = np.random.default_rng(0)
    wild = rng.normal(scale=0.05, size=(500, 3))
    clipped = ex.clip_to_limits(wild, DT)
    assert clipped.shape == wild.shape
    assert ex.within_limits(clipped, DT)[0]
    good = ex.random_rpc(1.0, 5.0, DT, seed=0)
    assert np.array_equal(ex.clip_to_limits(good, DT), good)
