"""Planar passivity: the loss matrix H_I = (K - K^H) / (2j) and where it is not PSD."""

import numpy as np
import pytest

from bushenv.models import MODELS
from bushenv.models.planar_linear import PlanarLinear
from bushenv.models.planar_narx import PlanarNarx
from bushenv.planar.fixed_points import fixed_points, grid
from bushenv.planar.passivity import (
    AMPLITUDES,
    loss_matrix,
    network_stiffness,
    passivity,
    sine_stiffness,
)

from .test_fixed_points import bistable

DT = 1 / 204.8


def test_work_per_cycle_is_pi_times_the_loss_form():
    # integrate f . dq over one cycle of q = Re(X e^{jwt}), f = Re(K X e^{jwt}) numerically
    rng = np.random.default_rng(1)
    k = rng.normal(size=(3, 3)) + 1j * rng.normal(size=(3, 3))
    x = rng.normal(size=3) + 1j * rng.normal(size=3)
    t = np.linspace(0, 2 * np.pi, 200_001)  # w = 1
    e = np.exp(1j * t)
    q = np.real(x[:, None] * e)
    f = np.real((k @ x)[:, None] * e)
    dq = np.real(1j * x[:, None] * e)
    work = np.trapezoid((f * dq).sum(axis=0), t)
    assert work == pytest.approx(np.pi * np.real(np.conj(x) @ loss_matrix(k) @ x), rel=1e-9)
    assert q.shape == f.shape


def test_linear_with_a_negative_damping_direction_is_active_at_every_frequency():
    c = np.diag([4.4e3, 15e3, 30.0])
    c[0, 1] = c[1, 0] = 9e3  # eigenvalues of the axial-radial block: 4.4e3, 15e3 -> one < 0
    assert np.linalg.eigvalsh(c).min() < 0
    model = PlanarLinear(np.diag([3.8e5, 1.5e6, 3e3]), c)
    f = np.geomspace(0.5, 90, 15)
    rep = passivity(model, np.zeros((1, 3)), f)
    assert rep.active_bands() == [(0, [(f[0], f[-1])])]
    # analytic: H_I = sin(wT)/T C, scaled by D on both sides
    d = np.diag(AMPLITUDES)
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
    k = sine_stiffness(model, np.array([[1e-3, -2e-3, 0.05]]), f)
    want = model.k_matrix + (1j * np.sin(2 * np.pi * f * DT) / DT)[:, None, None] * model.c_matrix
    np.testing.assert_allclose(k[0], want, rtol=1e-9, atol=1e-6 * np.abs(want).max())


def test_coupled_reference_is_passive_at_preloads_and_rotations():
    ref = MODELS["reference"].model_class(3).preset(measurement=False)
    holds = grid([0.0], [0.0, 2e-3, 4e-3], [0.0, 0.05, 0.10])
    rep = passivity(ref, holds, np.array([0.5, 2.0, 10.0, 40.0]))
    assert rep.method == "sines" and rep.passive
    assert rep.min_eig > 0


def test_network_linearisation_equals_sines_at_its_stable_fixed_point():
    model = PlanarNarx.untrained(seed=0)
    q0 = np.zeros((1, 3))
    fp = fixed_points(model, q0)
    rest = model.simulate(np.zeros((3000, 3)))[-1]  # the stable fixed point a run from rest ends on
    i = np.flatnonzero(fp.stable)[np.argmin(np.abs(fp.force[fp.stable] - rest).max(axis=1))]
    f = np.array([1.0, 5.0, 25.0])
    lin = network_stiffness(model, fp.q[fp.hold[i]], fp.y[i], f)[0]
    meas = sine_stiffness(model, q0, f)[0]
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
