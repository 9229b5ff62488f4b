import numpy as np
import pytest

from bushenv.certify.fixed_points import fixed_points, grid
from bushenv.certify.network import CertifyError, narx_net
from bushenv.certify.passivity import (
    SINE_FRACTION,
    amplitudes,
    loss_matrix,
    negative_bands,
    passivity,
)
from bushenv.certify.stiffness import dynamic_stiffness, sine_stiffness
from bushenv.divergence import cumulative_work
from bushenv.models import MODELS, get_model
from bushenv.models.hybrid import HybridBushing
from bushenv.models.linear import LinearBushing
from bushenv.models.planar_linear import PlanarLinear
from bushenv.models.planar_narx import PlanarNarx

from .conftest import bistable, fold_hybrid, old_nn, random_narx

FREQ = np.array([1.0, 7.0, 20.0, 33.0, 45.0, 60.0, 75.0, 95.0])


def _k_about(model, x0, freq, velocity="central"):
    net = narx_net(model)
    fp = fixed_points(net, np.array([x0]))
    p = np.flatnonzero(fp.stable)[0]  # the lowest: where a run from rest settles (tested below)
    if fp.y.size > 1:
        assert p == 0
    return dynamic_stiffness(net, fp.q[fp.hold[[p]]], fp.y[[p]], freq, velocity)[0, :, 0, 0]


@pytest.mark.parametrize("axis", ["axial", "radial"])
@pytest.mark.parametrize("name", ["nn", "hybrid"])
@pytest.mark.parametrize("x0", [0.0, 2e-3, -6e-3])
def test_linearised_k_matches_small_sines_of_the_shipped_models(name, axis, x0):
    model = get_model(name, axis=axis)
    k = _k_about(model, x0, FREQ)
    measured = sine_stiffness(model, x0, FREQ, 1e-7)[0, :, 0, 0]
    np.testing.assert_allclose(measured, k, rtol=1e-4)


@pytest.mark.parametrize("velocity", ["central", "backward"])
def test_both_velocity_conventions_match_sines_fed_that_velocity(velocity):
    model = fold_hybrid(c_ns_per_m=8.0e3)  # a large damper makes the convention visible
    k = _k_about(model, 0.0, FREQ, velocity)
    measured = sine_stiffness(model, 0.0, FREQ, 1e-7, velocity)[0, :, 0, 0]
    np.testing.assert_allclose(measured, k, rtol=1e-4)
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
    np.testing.assert_allclose(sine_stiffness(model, 1e-3, FREQ, 1e-7)[0, :, 0, 0], k, rtol=1e-4)


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


# ----- the matrix test, over three coordinates; C = 1 is Im K ------------------------------
DT = 1 / 204.8
D3 = amplitudes(("m", "m", "rad"))


def test_work_per_cycle_is_pi_times_the_loss_form():
    # integrate f . dq over one cycle of q = Re(X e^{jwt}), f = Re(K X e^{jwt}) numerically
    rng = np.random.default_rng(1)
    k = rng.normal(size=(3, 3)) + 1j * rng.normal(size=(3, 3))
    x = rng.normal(size=3) + 1j * rng.normal(size=3)
    t = np.linspace(0, 2 * np.pi, 200_001)  # w = 1
    e = np.exp(1j * t)
    f = np.real((k @ x)[:, None] * e)
    dq = np.real(1j * x[:, None] * e)
    work = np.trapezoid((f * dq).sum(axis=0), t)
    assert work == pytest.approx(np.pi * np.real(np.conj(x) @ loss_matrix(k) @ x), rel=1e-9)


@pytest.mark.parametrize("coords", [1, 3])
def test_a_linear_model_is_passive_and_its_loss_is_sin_wt_over_t_times_c(coords):
    model = LinearBushing.preset("axial") if coords == 1 else PlanarLinear.preset()
    f = np.array([1.0, 5.0, 20.0])
    rep = passivity(model, np.zeros((1, coords)), f)
    assert rep.method == "analytic" and rep.passive
    d = amplitudes(model.units)
    c = np.array([[model.c_ns_per_m]]) if coords == 1 else model.c_matrix
    want = np.sin(2 * np.pi * f * DT)[:, None] / DT * np.linalg.eigvalsh(d * c * d[:, None])
    np.testing.assert_allclose(rep.eig[0], want, rtol=1e-9)


def test_linear_with_a_negative_damping_direction_is_active_at_every_frequency():
    c = np.diag([4.4e3, 15e3, 30.0])
    c[0, 1] = c[1, 0] = 9e3  # eigenvalues of the axial-radial block: 4.4e3, 15e3 -> one < 0
    assert np.linalg.eigvalsh(c).min() < 0
    model = PlanarLinear(np.diag([3.8e5, 1.5e6, 3e3]), c)
    f = np.geomspace(0.5, 90, 15)
    rep = passivity(model, np.zeros((1, 3)), f)
    assert rep.active_bands() == [(0, [(f[0], f[-1])])]
    # analytic: H_I = sin(wT)/T C, scaled by D on both sides
    d = np.diag(D3)
    want = np.sin(2 * np.pi * f * DT) / DT * np.linalg.eigvalsh(d @ c @ d).min()
    np.testing.assert_allclose(rep.eig[0, :, 0], want, rtol=1e-9)


def test_linear_with_a_circulatory_stiffness_is_active_below_the_analytic_frequency():
    s, cd = 2e4, 4.4e3  # skew stiffness N/m, damping N s/m in the axial-radial plane
    k = np.diag([3.8e5, 1.5e6, 3e3])
    k[0, 1], k[1, 0] = k[0, 1] + s, k[1, 0] - s
    model = PlanarLinear(k, np.diag([cd, cd, 30.0]))
    f = np.linspace(0.1, 20, 400)
    rep = passivity(model, np.zeros((1, 3)), f)
    # eigenvalues c sin(wT)/T +- s: negative while sin(wT)/T < s / c
    f_star = np.arcsin(s / cd * DT) / (2 * np.pi * DT)
    ((row, bands),) = rep.active_bands()
    assert len(bands) == 1 and bands[0][0] == f[0]
    assert bands[0][1] == pytest.approx(f_star, rel=1e-3)


def test_sines_measure_the_linear_stiffness_exactly():
    model = MODELS["linear"].model_class(3).preset()
    f = np.array([0.5, 3.0, 20.0])
    k = sine_stiffness(model, np.array([[1e-3, -2e-3, 0.05]]), f, SINE_FRACTION * D3)
    want = model.k_matrix + (1j * np.sin(2 * np.pi * f * DT) / DT)[:, None, None] * model.c_matrix
    np.testing.assert_allclose(k[0], want, rtol=1e-9, atol=1e-6 * np.abs(want).max())


def test_coupled_reference_is_passive_at_preloads_and_rotations():
    ref = MODELS["reference"].model_class(3).preset(measurement=False)
    holds = grid([0.0], [0.0, 2e-3, 4e-3], [0.0, 0.05, 0.10])
    rep = passivity(ref, holds, np.array([0.5, 2.0, 10.0, 40.0]))
    assert rep.method == "sines" and rep.passive
    assert rep.min_eig > 0


@pytest.mark.parametrize("coords", [1, 3])
def test_network_linearisation_equals_sines_at_its_stable_fixed_point(coords):
    model = get_model("nn", axis="axial") if coords == 1 else PlanarNarx.untrained(seed=0)
    net = narx_net(model)
    q0 = np.zeros((1, coords))
    fp = fixed_points(net, q0)
    rest = model.simulate(np.zeros((3000, coords)) if coords > 1 else np.zeros(3000))[-1]
    gap = np.abs(fp.force[fp.stable] - rest).max(axis=1)
    i = np.flatnonzero(fp.stable)[np.argmin(gap)]  # the stable point a run from rest ends on
    f = np.array([1.0, 5.0, 25.0])
    lin = dynamic_stiffness(net, fp.q[fp.hold[[i]]], fp.y[[i]], f)[0]
    meas = sine_stiffness(model, q0, f, SINE_FRACTION * amplitudes(model.units))[0]
    assert np.abs(lin - meas).max() < 0.02 * np.abs(lin).max()


def test_network_report_names_holds_without_a_stable_fixed_point():
    # y = -6 tanh(2 y + qs / 2) per axis: one fixed point, loop gain -12 over the 5 lags
    model = bistable(out=-6.0)
    holds = grid([0.0], [-2e-3, 0.0, 2e-3], [0.0])
    fp = fixed_points(model, holds)
    assert np.all(fp.count == 1) and not fp.stable.any()
    rep = passivity(model, holds, np.array([1.0, 10.0]))
    assert len(rep.no_stable) == 3 and rep.eig.shape == (0, 2, 3)
    held = model.simulate(np.tile([0.0, 2e-3, 0.0], (2000, 1)))[-200:, 1]
    assert held.max() - held.min() > 10.0  # N: no steady state, it keeps oscillating


def test_script_prints_both_tables_and_refuses_an_unknown_name(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "scripts" / "planar_passivity.py"
    net = str(PlanarNarx.untrained(seed=0).save(tmp_path / "net.npz"))
    run = subprocess.run(
        [sys.executable, str(script), "--models", "linear-preset", net, "--quiet",
         "--png", str(tmp_path / "p.png")],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "| linear-preset | analytic |" in run.stdout and "| net.npz | linearised |" in run.stdout
    assert "| net.npz | 125 |" in run.stdout and (tmp_path / "p.png").stat().st_size > 0
    bad = subprocess.run(
        [sys.executable, str(script), "--models", "nope"], capture_output=True, text=True
    )
    assert bad.returncode == 2 and "unknown three-axis model" in bad.stderr
    assert "Traceback" not in bad.stderr
