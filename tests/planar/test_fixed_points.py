"""Planar fixed-point certificates: every fixed point at a hold, its stability, fold surfaces."""

import numpy as np
import pytest

from bushenv.models import MODELS
from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_narx import N_IN, PlanarNarx, PlanarNarxPerAxis
from bushenv.planar.fixed_points import HeldNetwork, fixed_points, fold_crossings, grid

SCALE = np.array([2e-3, 2e-3, 0.05])


def bistable(gain_q=0.5, out=2.0):
    """Three single-axis networks, each y = out tanh(2 y + gain_q qs); out = 2: three roots per
    axis at rest (+-1.998651 stable, 0 unstable), one beyond a fold."""
    h = 27
    w1, w_out = np.zeros((h, N_IN)), np.zeros((3, h))
    for ax in range(3):
        u = 9 * ax
        w1[u, 18 + ax :: 3] = 0.4  # own output, lags 1..5: sum 2
        w1[u, ax] = gain_q  # own coordinate, lag 0
        w_out[ax, u] = out
    return PlanarNarxPerAxis(
        q_offset=np.zeros(3), q_scale=SCALE, f_offset=np.zeros(3),
        f_scale=np.array([100.0, 100.0, 10.0]), w1=w1, b1=np.zeros(h), w_out=w_out,
        b_out=np.zeros(3),
    )  # fmt: skip


def scalar_roots(c):
    """Roots of 2 tanh(2 y + c) - y by a fine scan and bisection (independent of the boxes)."""
    g = lambda y: 2 * np.tanh(2 * y + c) - y  # noqa: E731
    ys = np.linspace(-2.5, 2.5, 200_000)  # even: no grid point on a root at 0
    v = g(ys)
    roots = []
    for i in np.flatnonzero(np.sign(v[:-1]) != np.sign(v[1:])):
        a, b = ys[i], ys[i + 1]
        for _ in range(80):
            m = 0.5 * (a + b)
            a, b = (m, b) if np.sign(g(m)) == np.sign(g(a)) else (a, m)
        roots.append(0.5 * (a + b))
    return np.array(roots)


def test_bistable_axes_give_the_product_of_their_roots_and_the_stable_ones():
    fp = fixed_points(bistable(), np.zeros((1, 3)))
    r = scalar_roots(0.0)
    assert len(r) == 3 and fp.count[0] == 27 and fp.unresolved[0] == 0
    assert fp.stable_count[0] == 8  # the stable root on every axis: 2 x 2 x 2
    for ax in range(3):
        assert np.abs(fp.y[:, ax][:, None] - r[None, :]).min(axis=1).max() < 1e-12
    outer = np.all(np.abs(fp.y) > 1.0, axis=1)
    np.testing.assert_array_equal(fp.stable, outer)


def test_fold_surface_crossing_is_where_the_pair_of_roots_meets():
    # fold of y = 2 tanh(2y + c): 4 sech^2 = 1 -> u = atanh(sqrt(3)/2), y = sqrt(3), c = u - 2y
    c_fold = np.arctanh(np.sqrt(3) / 2) - 2 * np.sqrt(3)
    q_fold = abs(c_fold) / 0.5 * SCALE[0]  # c = 0.5 qs, qs = q / 2 mm
    axial = np.linspace(-0.012, 0.012, 5)
    folds = fold_crossings(bistable(), axial, [0.0], [0.0])
    assert len(folds) == 2
    # located to FOLD_TOLERANCE (1e-4) of the 6 mm edge: 0.6 um, 7e-5 of 8.59 mm
    assert sorted(abs(f.q[0]) for f in folds) == pytest.approx([q_fold, q_fold], rel=1e-4)
    assert {(f.count_from, f.count_to) for f in folds} == {(9, 27), (27, 9)}


def test_mimo_fixed_points_are_roots_and_a_held_run_ends_on_a_stable_one():
    model = PlanarNarx.untrained(seed=0)
    q0 = np.array([0.0, 0.0, 0.0])
    fp = fixed_points(model, q0[None])
    net = HeldNetwork.of(model)
    phi, _ = net.phi(net.held(q0[None])[[0] * fp.count[0]], fp.y)
    assert np.abs(phi).max() < 1e-12
    assert fp.stable_count[0] >= 1
    f = model.simulate(np.zeros((3000, 3)))
    gap = np.abs(fp.force[fp.stable] - f[-1]).max(axis=1)
    assert gap.min() < 1e-6 * np.abs(f[-1]).max()


def test_spectral_radius_decides_what_a_perturbed_hold_does():
    model = bistable()
    fp = fixed_points(model, np.zeros((1, 3)))
    assert fp.spectral_radius[fp.stable].max() < 1 < fp.spectral_radius[~fp.stable].min()


def test_grid_orders_rotation_fastest():
    g = grid([0.0, 1.0], [0.0], [0.0, 0.1])
    np.testing.assert_array_equal(g, [[0, 0, 0], [0, 0, 0.1], [1, 0, 0], [1, 0, 0.1]])


def test_a_model_that_is_not_a_network_is_refused_by_name():
    with pytest.raises(PlanarModelError, match="linear"):
        fixed_points(MODELS["linear"].model_class(3).preset(), np.zeros((1, 3)))
