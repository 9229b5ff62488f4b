"""The NARX network of an ``nn`` or ``hybrid`` model, seen with the displacement held.

With x held, every lagged displacement equals x and the network's own-output recurrence
(``kernels.narx_kernel``; seed 000 §4.2, eqs. 4-6) is autonomous::

    y_t = N(xs, xs, ..., xs, y_{t-1}, ..., y_{t-n})       xs = (x - x_offset) / x_scale
    F_t = k x + c v + f_offset + f_scale y_t              (k = c = 0 for the pure NN)

Its fixed points y* = N(xs, ..., xs, y*, ..., y*) are the roots of the *diagonal* map
phi(y) = N(xs, .., y, .., y) - y. This module evaluates phi and its derivative in y on
arrays of holds and points, the bounds on phi's first and second derivatives that make the
root search of ``fixed_points.py`` exhaustive, and the partial derivatives of N with respect to
each lag (the linearised recurrence of ``fixed_points.spectral_radius`` and ``passivity``).

Shapes: ``c`` (..., H1) is the held part of the first layer's pre-activation,
b1 + sum over the displacement columns of w1 times xs; ``y`` (...) scaled outputs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.errors import BadInput
from bushenv.models.narx import NarxBushing

# max |d^2 tanh(a) / da^2| = max |2 tanh(a) (1 - tanh(a)^2)|, reached at tanh(a) = 1/sqrt(3)
TANH_CURVATURE = 4.0 / (3.0 * np.sqrt(3.0))


class CertifyError(BadInput):
    """Bad input to a certificate (a model that is not a NARX network, a bad option)."""


@dataclass(frozen=True, eq=False)
class NarxNet:
    """The arrays of a NARX model that its certificates need (see ``narx.NarxBushing``).

    ``w2`` has shape (0, H1) for one hidden layer. ``k_n_per_m``, ``c_ns_per_m``: the hybrid's
    backbone (0 for the pure NN). ``dt_s``: the model's sample time.
    """

    n_past_x: int
    n_past_f: int
    x_offset_m: float
    x_scale_m: float
    f_offset_n: float
    f_scale_n: float
    w1: np.ndarray
    b1: np.ndarray
    w2: np.ndarray
    b2: np.ndarray
    w_out: np.ndarray
    b_out: float
    k_n_per_m: float
    c_ns_per_m: float
    dt_s: float
    model_name: str

    @property
    def two_layers(self) -> bool:
        return self.w2.shape[0] > 0

    @property
    def x_columns(self) -> np.ndarray:
        """(H1, 1 + n_past_x): first-layer weights of x_t, x_{t-1}, ..."""
        return self.w1[:, : 1 + self.n_past_x]

    @property
    def y_columns(self) -> np.ndarray:
        """(H1, n_past_f): first-layer weights of y_{t-1}, ..., y_{t-n_past_f}."""
        return self.w1[:, 1 + self.n_past_x :]

    @property
    def y_range(self) -> tuple[float, float]:
        """Interval holding every output N can give: b_out -+ sum |w_out| (tanh in [-1, 1])."""
        half = float(np.sum(np.abs(self.w_out)))
        return self.b_out - half, self.b_out + half

    def scaled_x(self, x_m: np.ndarray) -> np.ndarray:
        return (np.asarray(x_m, dtype=np.float64) - self.x_offset_m) / self.x_scale_m

    def held_preactivation(self, x_m: np.ndarray) -> np.ndarray:
        """(..., H1) first-layer pre-activation from the bias and the held displacement."""
        xs = self.scaled_x(x_m)
        return self.b1 + xs[..., None] * self.x_columns.sum(axis=1)

    def force_n(self, x_m: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Static force of output ``y`` held at ``x_m``: k x + f_offset + f_scale y, N."""
        return self.k_n_per_m * np.asarray(x_m) + self.f_offset_n + self.f_scale_n * np.asarray(y)

    def output_of_force(self, x_m: np.ndarray, f_n: np.ndarray) -> np.ndarray:
        """Inverse of ``force_n`` in a hold (v = 0)."""
        return (np.asarray(f_n) - self.k_n_per_m * np.asarray(x_m) - self.f_offset_n) / (
            self.f_scale_n
        )


def narx_net(model) -> NarxNet:
    """The certificate's view of ``model``; ``CertifyError`` for anything but nn / hybrid."""
    if not isinstance(model, NarxBushing):
        name = getattr(model, "name", "?")
        raise CertifyError(
            f"certificates are for NARX models (nn, hybrid); got a {type(model).__name__} "
            f"({name!r} model)"
        )
    return NarxNet(
        n_past_x=model.n_past_x,
        n_past_f=model.n_past_f,
        x_offset_m=model.x_offset_m,
        x_scale_m=model.x_scale_m,
        f_offset_n=model.f_offset_n,
        f_scale_n=model.f_scale_n,
        w1=np.array(model.w1),
        b1=np.array(model.b1),
        w2=np.array(model.w2),
        b2=np.array(model.b2),
        w_out=np.array(model.w_out),
        b_out=float(model.b_out),
        k_n_per_m=float(getattr(model, "k_n_per_m", 0.0)),
        c_ns_per_m=float(getattr(model, "c_ns_per_m", 0.0)),
        dt_s=float(model.dt),
        model_name=model.name,
    )


def diagonal(net: NarxNet, c: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """phi(y) = N(held x, y, ..., y) - y and dphi/dy, each of y's shape.

    ``c`` (..., H1) broadcasts against ``y[..., None]``.
    """
    s = net.y_columns.sum(axis=1)
    h1 = np.tanh(c + y[..., None] * s)
    dh = (1.0 - h1 * h1) * s
    if net.two_layers:
        h2 = np.tanh(h1 @ net.w2.T + net.b2)
        dh = (1.0 - h2 * h2) * (dh @ net.w2.T)
        h1 = h2
    out = h1 @ net.w_out + net.b_out
    return out - y, dh @ net.w_out - 1.0


def derivative_bounds(net: NarxNet) -> tuple[float, float]:
    """(L, M): |dN/dy| <= L and |d^2 N / dy^2| <= M along the diagonal, for every held x.

    With s = the row sums of the y-columns of w1 and kappa = ``TANH_CURVATURE``:
    one layer, N = w_out . tanh(c + s y): L = sum |w_out s|, M = kappa sum |w_out| s^2.
    Two layers, N = w_out . tanh(W2 tanh(c + s y) + b2): with r_k = sum_i |W2_ki s_i|,
    L = sum_k |w_out_k| r_k and M = kappa sum_k |w_out_k| (r_k^2 + sum_i |W2_ki| s_i^2)
    (chain rule; every tanh' is in [0, 1] and every |tanh''| <= kappa).
    """
    s = net.y_columns.sum(axis=1)
    w = np.abs(net.w_out)
    if not net.two_layers:
        return float(np.sum(w * np.abs(s))), float(TANH_CURVATURE * np.sum(w * s * s))
    a2 = np.abs(net.w2)
    r = a2 @ np.abs(s)
    m = TANH_CURVATURE * np.sum(w * (r * r + a2 @ (s * s)))
    return float(np.sum(w * r)), float(m)


def lag_gradients(net: NarxNet, c: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Partial derivatives of N at the diagonal point (held x, y): (a, b).

    ``a`` (..., n_past_f): dN/dy_{t-j}, j = 1..n_past_f; ``b`` (..., 1 + n_past_x):
    dN/dxs_{t-j}, j = 0..n_past_x (scaled displacement). sum(a) - 1 = dphi/dy.
    """
    s = net.y_columns.sum(axis=1)
    h1 = np.tanh(c + y[..., None] * s)
    g = 1.0 - h1 * h1
    if net.two_layers:
        h2 = np.tanh(h1 @ net.w2.T + net.b2)
        g = ((net.w_out * (1.0 - h2 * h2)) @ net.w2) * g
    else:
        g = net.w_out * g
    return g @ net.y_columns, g @ net.x_columns


def describe(net: NarxNet) -> dict:
    """What a certificate records of the network it certifies (its shape, rate and backbone),
    so a certificate can be matched to a model later."""
    return {
        "name": net.model_name,
        "hidden": [int(net.w1.shape[0])] + ([int(net.w2.shape[0])] if net.two_layers else []),
        "n_past_x": net.n_past_x,
        "n_past_f": net.n_past_f,
        "dt_s": net.dt_s,
        "k_n_per_m": net.k_n_per_m,
        "c_ns_per_m": net.c_ns_per_m,
    }
