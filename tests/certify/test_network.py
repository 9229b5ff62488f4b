import numpy as np
import pytest

from bushenv.certify.network import (
    CertifyError,
    derivative_bounds,
    diagonal,
    lag_gradients,
    narx_net,
)
from bushenv.models import get_model
from bushenv.models.boucwen import BoucWenBushing  # noqa: F401 - registers the class
from bushenv.models.linear import LinearBushing
from bushenv.reference.rubber import RubberBushing

from .conftest import fold_hybrid, random_narx


def _kernel_output(model, xs: float, ys_lags: np.ndarray, xs_lags: np.ndarray) -> float:
    """One step of the model's own kernel from a hand-set state: the scaled network output."""
    model.reset(1)
    s = model.state
    s[0, 0] = 0.0  # counter 0: lag j sits in ring slot (-j) mod n
    nx, nf = model.n_past_x, model.n_past_f
    for j in range(1, nx + 1):
        s[1 + (-j) % nx, 0] = xs_lags[j - 1]
    for j in range(1, nf + 1):
        s[1 + nx + (-j) % nf, 0] = ys_lags[j - 1]
    x = xs * model.x_scale_m + model.x_offset_m
    f = model.step(float(x), 0.0)
    return (f - getattr(model, "k_n_per_m", 0.0) * x - model.f_offset_n) / model.f_scale_n


@pytest.mark.parametrize("which", ["one_layer", "two_layers", "hybrid"])
def test_lag_gradients_match_finite_differences_of_the_model_kernel(which):
    rng = np.random.default_rng(3)
    if which == "hybrid":
        model = fold_hybrid()
    else:
        hidden = (5,) if which == "one_layer" else (5, 4)
        model = random_narx(rng, hidden=hidden, n_past_x=3, n_past_f=4)
    net = narx_net(model)
    xs, y = 0.37, 0.21
    x = xs * net.x_scale_m + net.x_offset_m
    a, b = lag_gradients(net, net.held_preactivation(np.array([x])), np.array([y]))
    h = 1e-6
    ylags = np.full(net.n_past_f, y)
    xlags = np.full(net.n_past_x, xs)
    for j in range(net.n_past_f):
        up, dn = ylags.copy(), ylags.copy()
        up[j] += h
        dn[j] -= h
        fd = (_kernel_output(model, xs, up, xlags) - _kernel_output(model, xs, dn, xlags)) / (2 * h)
        assert a[0, j] == pytest.approx(fd, abs=1e-7)
    fd0 = (
        _kernel_output(model, xs + h, ylags, xlags) - _kernel_output(model, xs - h, ylags, xlags)
    ) / (2 * h)
    assert b[0, 0] == pytest.approx(fd0, abs=1e-7)
    for j in range(net.n_past_x):
        up, dn = xlags.copy(), xlags.copy()
        up[j] += h
        dn[j] -= h
        fd = (_kernel_output(model, xs, ylags, up) - _kernel_output(model, xs, ylags, dn)) / (2 * h)
        assert b[0, j + 1] == pytest.approx(fd, abs=1e-7)


def test_diagonal_is_the_kernel_on_the_diagonal_and_its_derivative_is_sum_a_minus_one():
    rng = np.random.default_rng(5)
    model = random_narx(rng, hidden=(7, 3), n_past_x=2, n_past_f=6)
    net = narx_net(model)
    for xs, y in [(-0.8, 0.3), (0.1, -1.2), (1.5, 0.0)]:
        x = np.array([xs * net.x_scale_m])
        c = net.held_preactivation(x)
        phi, dphi = diagonal(net, c, np.array([y]))
        out = _kernel_output(model, xs, np.full(6, y), np.full(2, xs))
        assert phi[0] == pytest.approx(out - y, abs=1e-12)
        a, _ = lag_gradients(net, c, np.array([y]))
        assert dphi[0] == pytest.approx(a.sum() - 1.0, abs=1e-12)


@pytest.mark.parametrize("hidden", [(4,), (6, 5), (9,), (3, 8)])
def test_derivative_bounds_hold_on_dense_grids_of_random_networks(hidden):
    rng = np.random.default_rng(hash(hidden) % 2**32)
    for _ in range(5):
        net = narx_net(random_narx(rng, hidden=hidden, gain=2.5))
        bound_1, bound_2 = derivative_bounds(net)
        x = rng.uniform(-6e-3, 6e-3, 40)
        y = np.linspace(-6, 6, 4001)
        c = net.held_preactivation(x)
        _, d = diagonal(net, c[:, None, :], y[None, :])
        slope = d + 1.0
        assert np.max(np.abs(slope)) <= bound_1 + 1e-12
        curvature = np.diff(slope, axis=1) / np.diff(y)
        assert np.max(np.abs(curvature)) <= bound_2 * (1 + 1e-6)


@pytest.mark.parametrize(
    "model",
    [
        LinearBushing.preset("axial"),
        RubberBushing.preset("axial"),
        get_model("boucwen", axis="radial"),
    ],
    ids=["linear", "rubber", "boucwen"],
)
def test_non_narx_models_are_refused_naming_their_class(model):
    with pytest.raises(CertifyError, match=rf"NARX models \(nn, hybrid\).*{type(model).__name__}"):
        narx_net(model)
