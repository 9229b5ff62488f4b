"""Bouc-Wen model (seed 002 eqs. 1-5): Table 3 preset sizes, stability, integration accuracy."""

import numpy as np
import pytest

from bushenv.models.boucwen import TABLE3_N_MM, BoucWenBushing, BoucWenError, n_mm_to_si
from bushenv.models.linear import TABLE1

DT = 1 / 204.8


def random_2mm(seed=0, duration_s=20.0):
    from scipy.signal import butter, sosfiltfilt

    rng = np.random.default_rng(seed)
    T = int(duration_s / DT)
    sos = butter(4, [0.5, 20.0], btype="band", fs=204.8, output="sos")
    x = sosfiltfilt(sos, rng.normal(size=T))
    return x * (0.002 / np.max(np.abs(x)))


def test_table3_read_in_n_mm_s_gives_forces_near_table1_radial_stiffness():
    x = random_2mm()
    f = BoucWenBushing.preset("radial").simulate(x)
    f_lin = TABLE1["radial"]["k_n_per_m"] * x  # 1519 N/mm
    ratio = np.max(np.abs(f)) / np.max(np.abs(f_lin))
    assert 0.5 < ratio < 2.0  # measured ~0.97: same size as the radial bushing of seed 000
    # secant stiffness by least squares on [x, v]: same order as Table 1
    v = np.gradient(x, DT)
    k, c = np.linalg.lstsq(np.c_[x, v], f, rcond=None)[0]
    assert 0.5e6 < k < 3e6


def test_si_conversion_leaves_time_constants_and_exponents_alone():
    si = n_mm_to_si(TABLE3_N_MM)
    assert si["k0"] / si["c1"] == pytest.approx(TABLE3_N_MM["k0"] / TABLE3_N_MM["c1"])
    assert si["n1"] == TABLE3_N_MM["n1"] and si["A1"] == TABLE3_N_MM["A1"]
    assert si["beta2"] == pytest.approx(TABLE3_N_MM["beta2"] * 1000 ** TABLE3_N_MM["n2"])


def test_preset_is_radial_only():
    with pytest.raises(ValueError, match="radial direction only"):
        BoucWenBushing.preset("axial")


def test_preset_settles_after_a_held_4mm_step():
    x = np.zeros(int(10 / DT))
    x[20:] = 0.004
    f = BoucWenBushing.preset().simulate(x)
    assert np.all(np.isfinite(f))
    tail = f[-int(2 / DT) :]
    assert np.ptp(tail) < 0.01 * np.max(np.abs(f))  # settled, not drifting or ringing
    assert 0.5 * 1518.73 * 4 < tail[-1] < 3 * 1518.73 * 4  # N; the size a 4 mm hold should give


@pytest.mark.parametrize("freq_hz", [0.1, 20.0, 80.0])
def test_preset_stays_finite_and_bounded_at_machine_extremes(freq_hz):
    # seed 002 Table 1: 25 mm dynamic stroke (+-12.5 mm), 0.1-80 Hz
    t = np.arange(int(max(2.0, 2 / freq_hz) / DT)) * DT
    x = 0.0125 * np.sin(2 * np.pi * freq_hz * t)
    v = 0.0125 * 2 * np.pi * freq_hz * np.cos(2 * np.pi * freq_hz * t)
    m = BoucWenBushing.preset()
    f = m.simulate(x, v)
    assert np.all(np.isfinite(f))
    # bounded: below what the linearised model with z1 saturating at twice its reach would give
    assert np.max(np.abs(f)) < 1e6


def reference_solution(m, x, v, dt):
    """Eqs. 1-5 with scipy's Radau at tight tolerance, same piecewise-linear x and x'."""
    from scipy.integrate import solve_ivp

    p = m.params

    def rhs(tau, s, x0, x1, u0, u1):
        y, w, z1, z2 = s
        xx = x0 + tau / dt * (x1 - x0)
        u = u0 + tau / dt * (u1 - u0)
        dy = (p["c1"] * u + p["k1"] * (xx - y) - p["k0"] * y + p["a1"] * z1) / p["c1"]
        dw = (p["c2"] * u + p["k2"] * (xx - w) + p["a2"] * z2) / (p["c0"] + p["c2"])
        d1, d2 = u - dy, u - dw
        g1 = p["gamma1"] + p["beta1"] * np.sign(d1) * np.sign(z1)
        g2 = p["gamma2"] + p["beta2"] * np.sign(d2) * np.sign(z2)
        dz1 = d1 * (p["A1"] - g1 * abs(z1) ** p["n1"])
        dz2 = d2 * (p["A2"] - g2 * abs(z2) ** p["n2"])
        return [dy, dw, dz1, dz2]

    s = np.zeros(4)
    xp = up = 0.0
    out = np.empty(len(x))
    for t in range(len(x)):
        sol = solve_ivp(
            rhs, (0, dt), s, method="Radau", rtol=1e-10, atol=1e-12, args=(xp, x[t], up, v[t])
        )
        s = sol.y[:, -1]
        dw = (p["c2"] * v[t] + p["k2"] * (x[t] - s[1]) + p["a2"] * s[3]) / (p["c0"] + p["c2"])
        out[t] = p["k0"] * s[0] + p["c0"] * dw
        xp, up = x[t], v[t]
    return out


def test_free_run_matches_a_tight_implicit_solver_and_converges_to_it():
    x = random_2mm(seed=1, duration_s=20.0)[:40]
    v = np.gradient(x, DT)
    ref = None
    for rtol, bound in ((7e-4, 2e-3), (1e-9, 1e-6)):
        m = BoucWenBushing(rtol=rtol, **BoucWenBushing.preset().params)
        f = m.simulate(x, v)
        if ref is None:
            ref = reference_solution(m, x, v, DT)
        assert np.max(np.abs(f - ref)) < bound * np.max(np.abs(ref))


@pytest.mark.parametrize(
    "change, why",
    [
        # c1 -> 0: eq. 3 is algebraic to 1e-8 of a sample; its form here would lose its digits
        ({"c1": 1e-9}, "below 1e-8 of a sample"),
        ({"A1": 0.0}, "A = 0 must be > 0"),
        ({"n2": -0.5}, "n = -0.5 must be > 0"),
        ({"beta1": -500.0, "gamma1": 0.0}, "runs away on unloading"),
    ],
)
def test_parameters_the_kernel_cannot_integrate_are_refused_with_the_reason(change, why):
    p = BoucWenBushing.preset().params
    with pytest.raises(BoucWenError, match=why):
        BoucWenBushing(**{**p, **change})


def test_a_runaway_history_raises_instead_of_clamping():
    # hardening with n > 1 (beta1 + gamma1 < 0) fed back with a1 < 0: z1 reaches infinity at
    # finite travel, and the travel keeps growing
    p = {**BoucWenBushing.preset().params, "beta1": 0.0, "gamma1": -1e6, "n1": 1.5, "A1": 1.0}
    p["a1"] = -612.5
    m = BoucWenBushing(**p)
    with pytest.raises(BoucWenError, match="could not be integrated"):
        m.simulate(random_2mm(duration_s=1.0))
