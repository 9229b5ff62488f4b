import numpy as np
import pytest

from bushenv.certify.fixed_points import fixed_points
from bushenv.certify.network import CertifyError, narx_net
from bushenv.certify.passivity import dynamic_stiffness, negative_bands, sine_stiffness
from bushenv.divergence import cumulative_work
from bushenv.models import get_model
from bushenv.models.hybrid import HybridBushing

from .conftest import fold_hybrid, old_nn, random_narx

FREQ = np.array([1.0, 7.0, 20.0, 33.0, 45.0, 60.0, 75.0, 95.0])


def _k_about(model, x0, freq, velocity="central"):
    net = narx_net(model)
    fp = fixed_points(net, np.array([x0]))
    p = np.flatnonzero(fp.stable)[0]  # the lowest: where a run from rest settles (tested below)
    if fp.y.size > 1:
        assert p == 0
    return dynamic_stiffness(net, fp.point_x_m[[p]], fp.y[[p]], freq, velocity)[0]


@pytest.mark.parametrize("axis", ["axial", "radial"])
@pytest.mark.parametrize("name", ["nn", "hybrid"])
@pytest.mark.parametrize("x0", [0.0, 2e-3, -6e-3])
def test_linearised_k_matches_small_sines_of_the_shipped_models(name, axis, x0):
    model = get_model(name, axis=axis)
    k = _k_about(model, x0, FREQ)
    measured = sine_stiffness(model, x0, FREQ, 1e-7)
    np.testing.assert_allclose(measured, k, rtol=1e-4)


@pytest.mark.parametrize("velocity", ["central", "backward"])
def test_both_velocity_conventions_match_sines_fed_that_velocity(velocity):
    model = fold_hybrid(c_ns_per_m=8.0e3)  # a large damper makes the convention visible
    k = _k_about(model, 0.0, FREQ, velocity)
    np.testing.assert_allclose(sine_stiffness(model, 0.0, FREQ, 1e-7, velocity), k, rtol=1e-4)
    other = "backward" if velocity == "central" else "central"
    k_other = _k_about(model, 0.0, FREQ, other)
    assert np.max(np.abs(k_other.real - k.real) / np.abs(k)) > 1e-2  # Re K differs ...
    np.testing.assert_allclose(k_other.imag, k.imag, rtol=1e-12)  # ... Im K does not


def test_a_random_two_layer_network_with_long_lags_matches_its_sines():
    rng = np.random.default_rng(2)
    for _ in range(20):
        model = random_narx(rng, hidden=(5, 4), n_past_x=6, n_past_f=3, gain=0.6)
        fp = fixed_points(narx_net(model), np.array([1e-3]))
        if fp.y.size == 1 and fp.spectral_radius[0] < 0.9:
            break
    k = _k_about(model, 1e-3, FREQ)
    np.testing.assert_allclose(sine_stiffness(model, 1e-3, FREQ, 1e-7), k, rtol=1e-4)


def test_a_hybrid_with_a_silent_network_is_kelvin_voigt():
    base = fold_hybrid()
    p = {k: np.array(v) for k, v in base.params.items()}
    p["w_out"] = np.zeros_like(p["w_out"])
    model = HybridBushing(**p, n_past_x=base.n_past_x, n_past_f=base.n_past_f)
    k = _k_about(model, 0.0, FREQ)
    wt = 2 * np.pi * FREQ * model.dt
    want = model.k_n_per_m + 1j * model.c_ns_per_m * np.sin(wt) / model.dt
    np.testing.assert_allclose(k, want, rtol=1e-12)
    # and with dt -> 0 that is k + j w c (seed 000 eq. 1)
    assert k[0].imag == pytest.approx(model.c_ns_per_m * 2 * np.pi * FREQ[0], rel=1e-3)


def test_work_per_cycle_is_pi_a2_im_k_times_sinc_and_negative_in_the_band():
    model = get_model(old_nn("axial"), axis="axial")
    freq = np.array([12.8, 51.2])  # 16 and 4 samples per cycle at 204.8 Hz
    k = _k_about(model, 0.0, freq)
    assert k[0].imag > 0 > k[1].imag  # this NN: passive at 12.8 Hz, not at 51.2 Hz
    amp = 1e-7
    dt = model.dt
    for fr, kk in zip(freq, k, strict=True):
        settle, cycles = int(round(5.0 / dt)), int(8 * fr)  # 8 s of sine
        t = np.arange(int(round(cycles / fr / dt)) + 1) * dt
        x = np.concatenate([np.zeros(settle), amp * np.sin(2 * np.pi * fr * t)])
        f = model.copy().simulate(x)
        # the judge's trapezoidal work over the last 20 whole cycles (start-up transient gone)
        w = cumulative_work(x[:, None], f[:, None])[:, 0]
        n20 = int(round(20 / fr / dt))
        assert abs(n20 * dt * fr - 20) < 1e-9  # whole cycles in whole samples
        work = (w[-2] - w[-2 - n20]) / 20
        wt = 2 * np.pi * fr * dt
        want = np.pi * amp**2 * kk.imag * np.sin(wt) / wt
        assert work == pytest.approx(want, rel=0.01)


def test_negative_bands_finds_every_interval_with_interpolated_edges():
    f = np.linspace(0, 10, 101)
    v = np.sin(f)  # negative on (pi, 2 pi) and (3 pi, 10]
    bands = negative_bands(f, v)
    assert len(bands) == 2
    assert bands[0] == pytest.approx((np.pi, 2 * np.pi), abs=2e-3)
    assert bands[1][0] == pytest.approx(3 * np.pi, abs=2e-3) and bands[1][1] == 10.0
    assert negative_bands(f, np.ones_like(f)) == []


def test_an_unknown_velocity_convention_is_refused():
    net = narx_net(fold_hybrid())
    with pytest.raises(CertifyError, match="velocity must be one of"):
        dynamic_stiffness(net, np.zeros(1), np.zeros(1), FREQ, velocity="forward")
