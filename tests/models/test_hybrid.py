"""Hybrid model: the network part is bounded whatever the input (seed 000 §3's robustness)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bushenv.models.hybrid import HybridBushing
from bushenv.models.narx import NarxBushing


def random_hybrid(seed, weight_scale, hidden=(9,)):
    rng = np.random.default_rng(seed)
    m = HybridBushing.initialised(
        (-0.002, 0.003),
        (-150.0, 250.0),
        hidden=hidden,
        seed=seed,
        k_n_per_m=3.0e5,
        c_ns_per_m=1.0e3,
    )
    for name in ("w1", "b1", "w2", "b2", "w_out"):
        a = getattr(m, name)
        setattr(m, name, np.ascontiguousarray(rng.normal(size=a.shape) * weight_scale))
    m.b_out = float(rng.normal() * weight_scale)
    return m


def adversarial_inputs(seed, T=400):
    """Held extremes, alternating +-1e3 m, near-zero, huge velocities: NaN-free but wild."""
    rng = np.random.default_rng(seed)
    x = rng.choice([-1e3, 1e3, 0.0, 4e-3, -1e-9], size=T)
    x[100:200] = 4e-3  # a held step
    v = rng.choice([-1e5, 1e5, 0.0], size=T)
    return x, v


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    weight_scale=st.floats(0.1, 50.0),
    two_layers=st.booleans(),
)
def test_hybrid_network_force_stays_within_nn_bound_for_adversarial_inputs(
    seed, weight_scale, two_layers
):
    m = random_hybrid(seed, weight_scale, hidden=(10, 9) if two_layers else (9,))
    x, v = adversarial_inputs(seed)
    f = m.simulate(x, v)
    backbone = m.backbone_force(x, v)
    f_nn = f - backbone
    # subtracting a 3e8 N backbone costs a few ulps of it
    slack = 1e-12 * (np.abs(backbone) + np.abs(f)) + 1e-9 * m.nn_bound()
    assert np.all(np.isfinite(f))
    assert np.all(np.abs(f_nn) <= m.nn_bound() + slack)


def test_nn_bound_is_attained_when_every_unit_saturates_the_right_way():
    # w1 huge and aligned with the current input: each hidden unit saturates to sign(w_out).
    m = random_hybrid(0, 1.0)
    m.w1[:] = 0.0
    m.w1[:, 0] = 1e6 * np.sign(m.w_out)
    m.b1[:] = 0.0
    f = m.simulate(np.full(10, 1.0), np.zeros(10))
    f_nn = f - m.backbone_force(np.full(10, 1.0), 0.0)
    expected = m.f_offset_n + m.f_scale_n * (np.sum(np.abs(m.w_out)) + m.b_out)
    assert f_nn[-1] == pytest.approx(expected, rel=1e-12)
    assert abs(expected) <= m.nn_bound()


def test_pure_nn_force_is_bounded_by_the_same_argument():
    rng = np.random.default_rng(5)
    m = NarxBushing.initialised((-0.002, 0.002), (-900.0, 900.0), seed=5)
    m.w1 = np.ascontiguousarray(rng.normal(size=m.w1.shape) * 30)
    x = rng.choice([-1e12, 1e12, 0.0], size=500)
    f = m.simulate(x, np.zeros(500))
    assert np.max(np.abs(f)) <= m.nn_bound() * (1 + 1e-12)


def test_hybrid_with_zero_network_output_is_its_backbone():
    m = random_hybrid(1, 1.0)
    m.w_out[:] = 0.0
    m.b_out = -m.f_offset_n / m.f_scale_n
    x = np.linspace(0, 0.003, 50)
    v = np.full(50, 0.1)
    np.testing.assert_allclose(m.simulate(x, v), m.backbone_force(x, v), rtol=1e-12, atol=1e-9)
