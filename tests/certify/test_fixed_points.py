import numpy as np
import pytest

from bushenv.certify.fixed_points import fixed_points, folds, grid, spectral_radius
from bushenv.certify.network import CertifyError, diagonal, narx_net
from bushenv.models import MODELS
from bushenv.models.planar_narx import PlanarNarx

from .conftest import (
    SCALE3,
    X_SCALE_M,
    bistable,
    fold_nn,
    fold_roots,
    fold_u,
    random_narx,
    scalar_roots,
)


@pytest.mark.parametrize("g", [1.5, 2.0, 4.0])
def test_fixed_points_of_the_fold_network_match_the_closed_form(g):
    net = narx_net(fold_nn(g=g))
    u = np.linspace(-1.5, 1.5, 61) * fold_u(g)
    fp = fixed_points(net, u * X_SCALE_M)
    for i, ui in enumerate(u):
        want = fold_roots(g, ui)
        got = fp.y[fp.of_hold(i), 0]
        assert got.size == want.size, (ui, got, want)
        np.testing.assert_allclose(got, want, atol=1e-6)
    assert fp.unresolved.sum() == 0


@pytest.mark.parametrize("eps", [1e-3, 1e-6, 1e-9])
def test_both_roots_of_a_nearly_merged_pair_are_found_just_inside_a_fold(eps):
    g = 2.0
    u = fold_u(g) * (1 - eps)
    fp = fixed_points(narx_net(fold_nn(g=g)), np.array([u * X_SCALE_M]))
    want = fold_roots(g, u)
    assert fp.y.size == want.size == 3
    np.testing.assert_allclose(fp.y[:, 0], want, atol=1e-6)
    assert fp.unresolved.sum() == 0


@pytest.mark.parametrize("g", [1.5, 2.0, 4.0])
def test_folds_are_found_where_g_sech2_equals_one(g):
    net = narx_net(fold_nn(g=g))
    fp = fixed_points(net, np.linspace(-3e-3, 3e-3, 41))
    found = folds(net, fp)
    uf = fold_u(g)
    assert [f.x_m for f in found] == pytest.approx([-uf * X_SCALE_M, uf * X_SCALE_M], abs=2e-9)
    # the lower branch (rest) vanishes at +u_f: the pair exists below it
    assert [f.exists_above for f in found] == [True, False]
    yf = np.sqrt(1 - 1 / g)
    assert found[1].force_n == pytest.approx(float(net.force_n(found[1].x_m, -yf)), abs=1e-3)
    for f in found:  # at the fold the merging pair has the eigenvalue 1
        assert min(f.radii) == pytest.approx(1.0, abs=1e-3)


def test_single_lag_spectral_radius_is_g_sech2():
    g = 3.0
    net = narx_net(fold_nn(g=g, y_weights=(1.0,), x_weights=(1.0, 0.0)))
    fp = fixed_points(net, np.array([0.0, 0.2e-3, -0.5e-3]))
    u = fp.x_m[fp.hold] / X_SCALE_M
    want = g / np.cosh(g * fp.y[:, 0] + u) ** 2
    np.testing.assert_allclose(fp.spectral_radius, want, rtol=1e-10)
    assert list(fp.stable) == list(want < 1)


def test_spectral_radius_is_the_largest_root_of_the_characteristic_polynomial():
    rng = np.random.default_rng(0)
    a = rng.normal(0, 0.6, (50, 5))
    want = [np.max(np.abs(np.roots(np.r_[1.0, -row]))) for row in a]
    np.testing.assert_allclose(spectral_radius(a), want, rtol=1e-9)


@pytest.mark.parametrize(
    "hidden,n_past_x,n_past_f",
    [((6,), 3, 4), ((9,), 5, 5), ((5, 4), 2, 6), ((8, 6), 5, 5), ((3,), 0 + 1, 1), ((4, 7), 6, 2)],
)
def test_every_root_of_a_dense_brute_force_search_is_found_on_random_networks(
    hidden, n_past_x, n_past_f
):
    rng = np.random.default_rng(sum(hidden) * 100 + n_past_x * 10 + n_past_f)
    multi = 0
    for _ in range(8):
        net = narx_net(random_narx(rng, hidden, n_past_x, n_past_f, gain=rng.uniform(2, 5)))
        x = rng.uniform(-6e-3, 6e-3, 12)
        fp = fixed_points(net, x)
        lo, hi = net.y_range
        y = np.linspace(lo, hi, 20_001)
        c = net.held_preactivation(x)
        phi, _ = diagonal(net, c[:, None, :], y[None, :])
        for i in range(x.size):
            neg = phi[i] < 0
            k = np.flatnonzero(neg[:-1] != neg[1:])
            got = fp.y[fp.of_hold(i), 0]
            for yk in y[k]:  # every bracketed root has a match
                assert np.min(np.abs(got - yk)) <= (hi - lo) / 20_000 + 1e-9
            assert got.size >= k.size
            res, _ = diagonal(net, c[i][None, :], got)
            assert np.all(np.abs(res) < 1e-9)
            multi += got.size > 1
        assert fp.unresolved.sum() == 0
    assert multi > 0  # the generator does give several fixed points somewhere


def test_stable_fixed_points_attract_and_unstable_ones_repel_in_the_model_kernel():
    """Independent of the Jacobian: start the model's own kernel next to each fixed point."""
    rng = np.random.default_rng(11)
    checked = {True: 0, False: 0}
    for _ in range(30):
        model = random_narx(rng, (6,), 3, 4, gain=rng.uniform(1.5, 3.5))
        net = narx_net(model)
        x = float(rng.uniform(-3e-3, 3e-3))
        fp = fixed_points(net, np.array([x]))
        for p in range(fp.y.size):
            if abs(fp.spectral_radius[p] - 1) < 0.05:
                continue  # too slow either way to tell in a short run
            model.reset(1)
            xs = (x - net.x_offset_m) / net.x_scale_m
            model.state[1 : 1 + 3] = xs
            model.state[1 + 3 :, 0] = fp.y[p, 0] + 1e-7 * rng.normal(size=4)
            out = np.array([model.step(x, 0.0) for _ in range(1500)])  # step keeps the state
            y = (out - net.f_offset_n) / net.f_scale_n
            moved = np.max(np.abs(y[-50:] - fp.y[p, 0]))
            if fp.stable[p]:
                assert moved < 1e-6
            else:
                assert moved > 1e-4
            checked[bool(fp.stable[p])] += 1
    assert checked[True] > 5 and checked[False] > 2


# ----- over three coordinates: boxes ---------------------------------------------------------
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
    q_fold = abs(c_fold) / 0.5 * SCALE3[0]  # c = 0.5 qs, qs = q / 2 mm
    axial = np.linspace(-0.012, 0.012, 5)
    found = folds(bistable(), axes=[axial, [0.0], [0.0]])
    assert len(found) == 2
    # located to a nanometre along the 6 mm edge (finer than FOLD_TOLERANCE of it)
    assert sorted(abs(f.q[0]) for f in found) == pytest.approx([q_fold, q_fold], abs=2e-9)
    assert {(f.count_from, f.count_to) for f in found} == {(9, 27), (27, 9)}
    for f in found:  # at the fold the merging pair has the eigenvalue 1
        assert min(f.radii) == pytest.approx(1.0, abs=1e-3)


def test_mimo_fixed_points_are_roots_and_a_held_run_ends_on_a_stable_one():
    model = PlanarNarx.untrained(seed=0)
    q0 = np.array([0.0, 0.0, 0.0])
    fp = fixed_points(model, q0[None])
    net = narx_net(model)
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


def test_block_companion_of_one_coordinate_is_the_scalar_companion():
    rng = np.random.default_rng(4)
    a = rng.normal(0, 0.6, (20, 5))
    np.testing.assert_allclose(spectral_radius(a[:, :, None, None]), spectral_radius(a))


def test_grid_orders_the_last_coordinate_fastest():
    g = grid([0.0, 1.0], [0.0], [0.0, 0.1])
    np.testing.assert_array_equal(g, [[0, 0, 0], [0, 0, 0.1], [1, 0, 0], [1, 0, 0.1]])


@pytest.mark.parametrize("coords", [1, 3])
def test_a_model_that_is_not_a_network_is_refused_by_name(coords):
    with pytest.raises(CertifyError, match="linear"):
        fixed_points(MODELS["linear"].model_class(coords).preset(), np.zeros((1, coords)))


@pytest.mark.parametrize("coords", [1, 3])
def test_holds_of_the_wrong_width_are_refused(coords):
    model = fold_nn() if coords == 1 else bistable()
    with pytest.raises(CertifyError, match=f"finite \\(M, {coords}\\)"):
        fixed_points(model, np.zeros((2, coords + 1)))
