"""ISO 8608 tracks, their coherence, and the pothole and bump generators (bushenv.vehicle.roads)."""

import numpy as np
import pytest
from scipy import signal
from scipy.integrate import quad

from bushenv.errors import BadInput
from bushenv.vehicle.roads import (
    ISO8608_BAND_CYCLES_PER_M,
    ISO8608_CLASSES,
    ISO8608_GD_N0_M3,
    bump_profile_m,
    bump_tracks,
    class_psd_m3,
    class_rms_m,
    generated_band_cycles_per_m,
    isotropic_coherence,
    pothole_profile_m,
    pothole_tracks,
    two_tracks,
)

SPEED, DT, LONG_S = 20.0, 0.01, 600.0  # 12 km of road at 72 km/h, 100 Hz: 60 000 samples


@pytest.fixture(scope="module")
def long_road():
    return two_tracks("C", SPEED, DT, LONG_S, np.random.default_rng(8608))


def test_class_table_is_the_standards_geometric_means():
    # ISO 8608:2016 Table C.2: A 16, B 64, ..., H 262144 (x 1e-6 m^3), each 4 x the one before
    expected = [16, 64, 256, 1024, 4096, 16384, 65536, 262144]
    assert [round(ISO8608_GD_N0_M3[c] * 1e6) for c in ISO8608_CLASSES] == expected
    assert class_psd_m3("D", 0.1) == pytest.approx(1024e-6, rel=1e-12)
    assert class_psd_m3("D", 0.2) == pytest.approx(256e-6, rel=1e-12)  # (n/n0)^-2


def test_class_rms_is_the_integral_of_the_psd():
    for c in ("A", "E", "H"):
        integral, _ = quad(lambda n, c=c: class_psd_m3(c, n), *ISO8608_BAND_CYCLES_PER_M, limit=200)
        assert class_rms_m(c) == pytest.approx(np.sqrt(integral), rel=1e-9)


@pytest.mark.parametrize("road_class", ISO8608_CLASSES)
def test_generated_rms_equals_the_standards_integral_over_the_band_generated(road_class):
    # Harmonics of the record length are orthogonal over it: the mean square is the sum of the
    # bins' PSD integrals, which is the band's integral. Tolerance: float rounding, not statistics.
    z = two_tracks(road_class, 25.0, 0.005, 30.0, np.random.default_rng(1))
    band = generated_band_cycles_per_m(25.0, 0.005, 30.0)
    assert band == ISO8608_BAND_CYCLES_PER_M  # 750 m at 5 mm spacing holds the whole band
    expected = class_rms_m(road_class, band)
    np.testing.assert_allclose(np.sqrt(np.mean(z**2, axis=0)), [expected, expected], rtol=1e-9)


def test_band_is_clipped_to_what_the_record_holds_and_the_rms_follows():
    # 30 km/h at 204.8 Hz for 4 s: 33 m of road (lowest bin edge 0.5/33 m), Nyquist 4.9 cycles/m
    speed, dt, dur = 30 / 3.6, 1 / 204.8, 4.0
    lo, hi = generated_band_cycles_per_m(speed, dt, dur)
    length = speed * round(dur / dt) * dt
    assert lo == pytest.approx(0.5 / length) and hi == ISO8608_BAND_CYCLES_PER_M[1]
    z = two_tracks("B", speed, dt, dur, np.random.default_rng(2))
    np.testing.assert_allclose(z.std(axis=0), class_rms_m("B", (lo, hi)), rtol=1e-9)
    # 40 m/s at 100 Hz: the standard's 2.83 cycles/m is 113 Hz, above Nyquist: clipped below 1.25
    lo, hi = generated_band_cycles_per_m(40.0, 0.01, 10.0)
    assert hi <= 40.0 / (2 * 0.01) / 40.0 and hi > 1.24


def test_each_class_has_twice_the_rms_of_the_one_before():
    # the standard's factor 4 in Gd(n0) is a factor 2 in RMS; same seed, same phases: exact
    rms = [two_tracks(c, 20.0, 0.01, 20.0, np.random.default_rng(5)).std() for c in ISO8608_CLASSES]
    np.testing.assert_allclose(np.array(rms[1:]) / rms[:-1], 2.0, rtol=1e-12)
    # and with different seeds the ordering holds too
    rms = [
        two_tracks(c, 20.0, 0.01, 20.0, np.random.default_rng(i)).std()
        for i, c in enumerate(ISO8608_CLASSES)
    ]
    np.testing.assert_allclose(np.array(rms[1:]) / rms[:-1], 2.0, rtol=1e-9)


def test_welch_psd_of_each_track_matches_the_class_spectrum(long_road):
    # Welch, 1024-sample Hann segments, 50 % overlap: ~116 segments, and each bin holds ~5
    # harmonics of fixed amplitude, so the estimate's scatter is a few %; octave means within 5 %
    f, p = signal.welch(long_road, fs=1 / DT, nperseg=1024, axis=0)
    n = f / SPEED
    for j in (0, 1):
        ratio_per_octave = []
        for lo in 0.02 * 2.0 ** np.arange(7):
            b = (n >= lo) & (n < 2 * lo)
            # the time PSD (m^2/Hz) times the speed is the spatial PSD (m^3)
            ratio_per_octave.append(np.mean(p[b, j] * SPEED / class_psd_m3("C", n[b])))
        np.testing.assert_allclose(ratio_per_octave, 1.0, atol=0.05)


def test_welch_coherence_between_tracks_matches_the_isotropic_model(long_road):
    # Welch's magnitude-squared coherence with K ~ 116 segments (~100 independent) is biased
    # up by about (1 - gamma^2)^2 / K <= 0.01 and scatters per bin by about
    # sqrt(2 / K) gamma (1 - gamma^2) <= 0.06; an octave averages >= 8 bins (20 above
    # 0.08 cycles/m): bias + 3 SD of an octave mean < 0.04. Measured (5 seeds): max 0.0124.
    f, c = signal.coherence(long_road[:, 0], long_road[:, 1], fs=1 / DT, nperseg=1024)
    n = f / SPEED
    model = isotropic_coherence(n, 1.565) ** 2
    for lo in 0.02 * 2.0 ** np.arange(7):
        b = (n >= lo) & (n < 2 * lo)
        assert abs(np.mean(c[b]) - np.mean(model[b])) < 0.04, lo
    # the model spans the range: nearly coherent at long wavelengths, incoherent at short ones
    assert model[(n > 0.02) & (n < 0.03)].min() > 0.8 and model[n > 1.0].max() < 1e-3


def test_isotropic_coherence_closed_form_for_w2_is_x_k1_of_x():
    from scipy.special import k1

    n = np.array([0.0, 0.01, 0.1, 0.5, 2.0])
    x = 2 * np.pi * n * 1.5
    expected = np.where(x == 0, 1.0, x * k1(np.where(x == 0, 1.0, x)))
    np.testing.assert_allclose(isotropic_coherence(n, 1.5), expected, rtol=1e-12)
    assert np.all(np.diff(isotropic_coherence(np.linspace(0, 3, 50), 1.5)) <= 0)


def test_tracks_are_deterministic_by_seed_and_differ_between_seeds():
    a = two_tracks("D", 15.0, 0.005, 10.0, np.random.default_rng(42))
    b = two_tracks("D", 15.0, 0.005, 10.0, np.random.default_rng(42))
    c = two_tracks("D", 15.0, 0.005, 10.0, np.random.default_rng(43))
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a.shape == (2000, 2) and a.dtype == np.float64


def test_zero_track_width_gives_identical_tracks():
    z = two_tracks("C", 15.0, 0.005, 10.0, np.random.default_rng(0), track_m=1e-9)
    np.testing.assert_allclose(z[:, 0], z[:, 1], atol=1e-5 * z.std())


def test_bump_profiles_have_their_height_length_and_shape():
    s = np.linspace(-0.1, 0.5, 601)
    cos_bump = bump_profile_m(s, 0.4, 0.05)
    sine_bump = bump_profile_m(s, 0.4, 0.05, "half_sine")
    assert cos_bump.max() == pytest.approx(0.05) and sine_bump.max() == pytest.approx(0.05)
    assert s[np.argmax(cos_bump)] == pytest.approx(0.2, abs=1e-3)
    assert np.all(cos_bump[(s < 0) | (s > 0.4)] == 0)
    # areas: (1 - cos) bump h L / 2, half-sine 2 h L / pi
    ds = s[1] - s[0]
    assert np.sum(cos_bump) * ds == pytest.approx(0.05 * 0.4 / 2, rel=1e-3)
    assert np.sum(sine_bump) * ds == pytest.approx(2 * 0.05 * 0.4 / np.pi, rel=1e-3)


def test_bump_is_under_both_wheels_at_the_time_the_speed_gives():
    z = bump_tracks(30 / 3.6, 0.001, 2.0, length_m=0.7, height_m=0.03, start_m=5.0)
    np.testing.assert_array_equal(z[:, 0], z[:, 1])
    t_peak = np.argmax(z[:, 0]) * 0.001
    assert t_peak == pytest.approx((5.0 + 0.35) / (30 / 3.6), abs=0.001)
    assert z.max() == pytest.approx(0.03, rel=1e-4)


def test_pothole_is_under_one_wheel_with_its_depth_and_edges():
    s = np.linspace(0, 0.6, 6001)
    for edge in ("cosine", "linear"):
        z = pothole_profile_m(s, 0.6, 0.05, 0.1, edge)
        assert z.min() == pytest.approx(-0.05) and z[0] == 0 and z[-1] == pytest.approx(0)
        flat = (s >= 0.1) & (s <= 0.5)
        np.testing.assert_allclose(z[flat], -0.05)
    linear = pothole_profile_m(s, 0.6, 0.05, 0.1, "linear")
    assert linear[500] == pytest.approx(-0.025)  # halfway down the straight edge
    z = pothole_tracks(30 / 3.6, 0.001, 2.0, side="right")
    assert np.all(z[:, 0] == 0) and z[:, 1].min() == pytest.approx(-0.05, rel=1e-3)


@pytest.mark.parametrize(
    "call, needle",
    [
        (lambda: class_rms_m("I"), "road_class='I'"),
        (lambda: class_rms_m("A", (1.0, 0.5)), "0 < low < high"),
        (lambda: two_tracks("A", -1.0, 0.01, 1.0, np.random.default_rng(0)), "speed_m_per_s"),
        (lambda: two_tracks("A", 10.0, 0.01, 1.0, 0), "numpy.random.Generator"),
        (lambda: two_tracks("A", 10.0, 0.01, 1.0, np.random.default_rng(0), track_m=0), "track_m"),
        (lambda: two_tracks("A", 1.0, 0.1, 0.2, np.random.default_rng(0)), "no harmonic"),
        (lambda: pothole_profile_m(0.0, 0.1, 0.05, 0.06), "edge_m=0.06"),
        (lambda: pothole_tracks(10.0, 0.01, 1.0, side="middle"), "side='middle'"),
        (lambda: bump_profile_m(0.0, 0.4, 0.05, "square"), "shape='square'"),
    ],
)
def test_bad_arguments_are_refused_naming_the_value(call, needle):
    with pytest.raises(BadInput, match=None) as info:
        call()
    assert needle in str(info.value)
