import numpy as np
import pytest

from bushenv.diagnose.regimes import (
    held_after_step_mask,
    near_reversal_mask,
    where_analysis,
)


def test_near_reversal_mask_covers_the_start_of_each_stroke_of_a_triangle_wave():
    x = np.tile(np.concatenate([np.linspace(-1, 1, 100), np.linspace(1, -1, 100)]), 5) * 1e-3
    near = near_reversal_mask(x)
    # 15 % of a 2 mm stroke is 0.3 mm after each turn, i.e. ~15 of every 100 samples
    assert 0.1 < near[200:].mean() < 0.2
    assert near[305] and not near[350]


def test_held_mask_marks_the_hold_after_a_step_but_not_the_initial_rest():
    dt = 0.01
    x = np.zeros(600)
    x[100:110] = np.linspace(0, 4e-3, 10)
    x[110:] = 4e-3
    held = held_after_step_mask(x, dt)
    assert not held[:95].any()
    assert held[150:].all()


def test_where_puts_a_reversal_residual_near_reversals_and_shares_add_up():
    dt = 1 / 204.8
    t = np.arange(4096) * dt
    x = 2e-3 * np.sin(2 * np.pi * 1.0 * t) * (1 + 0.5 * np.sin(2 * np.pi * 0.05 * t))
    v = np.gradient(x, dt)
    r = np.exp(-np.abs(v) / (0.05 * np.abs(v).max()))  # a residual that lives where v ~ 0
    w = where_analysis([x], [r], [dt])
    regs = w["regimes"]
    for a, b in (("near_reversal", "in_travel"), ("small_amplitude", "large_amplitude")):
        assert abs(regs[a]["energy_share"] + regs[b]["energy_share"] - 1) < 1e-9
    assert regs["low_velocity"]["energy_share"] > 0.9
    assert regs["near_reversal"]["energy_share"] > 2 * regs["near_reversal"]["time_share"]
    assert abs(sum(b["energy_share"] for b in w["frequency"]["bands"]) - 1) < 0.05
    assert abs(sum(w["time"]["thirds"]) - 1) < 1e-9
    assert w["summary"]


def test_coherence_separates_a_linear_residual_from_independent_noise():
    from bushenv.diagnose.regimes import residual_spectrum

    rng = np.random.default_rng(0)
    dt = 1 / 204.8
    x = rng.normal(size=8192)
    lagged = np.convolve(x, [0.5, 0.3, 0.2])[: x.size]  # a linear filter of x
    _, _, coh_linear = residual_spectrum(lagged, x, dt)
    _, _, coh_noise = residual_spectrum(rng.normal(size=x.size), x, dt)
    assert np.median(coh_linear) > 0.95
    assert np.median(coh_noise) < 0.2


def test_noise_floor_cut_off_is_the_same_for_a_record_read_backwards():
    from bushenv.diagnose.design import noise_band_edge

    dt = 1 / 1024
    t = np.arange(int(50 / dt)) * dt
    # a sweep running low to high: its top lies in the last samples of the record
    x = 2e-3 * np.sin(2 * np.pi * (0.5 * t + (30.0 - 0.5) * t**2 / (2 * t[-1])))
    x = x + 1e-9 * np.random.default_rng(0).normal(size=t.size)
    forward, backward = noise_band_edge(x, dt), noise_band_edge(x[::-1], dt)
    assert forward is not None and forward == pytest.approx(backward, rel=1e-9)
    assert forward > 30.0  # the whole band is kept, up to the sweep's top
