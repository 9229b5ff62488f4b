"""The NARX network of a bushing model over C coordinates, seen with the deflection held.

With the deflection vector q held, every lagged coordinate equals q and the network's own-output
recurrence (``kernels.narx_kernel`` for C = 1, seed 000 §4.2, eqs. 4-6; ``planar_kernels`` for
C = 3) is autonomous in its scaled outputs y (C,)::

    y_t = N(qs, qs, ..., qs, y_{t-1}, ..., y_{t-n})       qs = (q - q_offset) / q_scale
    F_t = K q + C v + f_offset + f_scale y_t              (K = C = 0 for a pure network)

Its fixed points y* = N(qs, ..., qs, y*, ..., y*) are the roots of the *diagonal* map
phi(y) = N(qs, .., y, .., y) - y. :class:`NarxNet` evaluates phi and its Jacobian on arrays of
holds and points (:meth:`NarxNet.phi`) and the lag matrices of the linearised recurrence
(:meth:`NarxNet.lag_matrices`: the spectral radius of ``fixed_points`` and the dynamic
stiffness of ``passivity``), for one or two tanh layers. The one-coordinate root search of
``fixed_points`` also needs a bound on phi'' (:func:`derivative_bounds`); :func:`diagonal` and
:func:`lag_gradients` are phi and the lag matrices of a one-coordinate network as scalars.

Shapes: ``c`` (..., H1) is the held part of the first layer's pre-activation,
b1 + sum over the lags of the coordinates' columns of w1 times qs (:meth:`NarxNet.held`);
``y`` (..., C) scaled outputs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.errors import BadInput

# max |d^2 tanh(a) / da^2| = max |2 tanh(a) (1 - tanh(a)^2)|, reached at tanh(a) = 1/sqrt(3)
TANH_CURVATURE = 4.0 / (3.0 * np.sqrt(3.0))


class CertifyError(BadInput):
    """Bad input to a certificate (a model that is not a NARX network, a bad option)."""


@dataclass(frozen=True, eq=False)
class NarxNet:
    """The arrays of a NARX model over C coordinates that its certificates need.

    ``w1`` (H1, C (1 + n_past_x) + C n_past_f): first-layer weights, lag by lag (x_t, x_{t-1},
    ..., then y_{t-1}, ...), coordinate by coordinate within a lag, as the models' kernels read
    them; ``w2`` (H2, H1), or (0, H1) for one hidden layer; ``w_out`` (C, H_last); ``b_out``,
    ``q_offset``, ``q_scale``, ``f_offset``, ``f_scale`` (C,); ``k``, ``c`` (C, C) the hybrid's
    backbone (zeros for a pure network); ``dt_s`` the model's sample time; ``units`` of the
    coordinates ("m" or "rad").
    """

    n_past_x: int
    n_past_f: int
    q_offset: np.ndarray
    q_scale: np.ndarray
    f_offset: np.ndarray
    f_scale: np.ndarray
    w1: np.ndarray
    b1: np.ndarray
    w2: np.ndarray
    b2: np.ndarray
    w_out: np.ndarray
    b_out: np.ndarray
    k: np.ndarray
    c: np.ndarray
    dt_s: float
    model_name: str
    units: tuple[str, ...] = ("m",)
    coords: tuple[str, ...] = ("deflection",)

    @property
    def n_coords(self) -> int:
        return int(self.b_out.size)

    @property
    def two_layers(self) -> bool:
        return self.w2.shape[0] > 0

    @property
    def wq(self) -> np.ndarray:
        """(1 + n_past_x, H1, C) first-layer weights of the scaled coordinates at lags 0.."""
        nq = self.n_coords * (1 + self.n_past_x)
        return self.w1[:, :nq].reshape(-1, 1 + self.n_past_x, self.n_coords).transpose(1, 0, 2)

    @property
    def wy(self) -> np.ndarray:
        """(n_past_f, H1, C) first-layer weights of the own output at lags 1.."""
        nq = self.n_coords * (1 + self.n_past_x)
        return self.w1[:, nq:].reshape(-1, self.n_past_f, self.n_coords).transpose(1, 0, 2)

    @property
    def s(self) -> np.ndarray:
        """(H1, C) the own-output weights summed over the lags: the diagonal's S."""
        nq = self.n_coords * (1 + self.n_past_x)
        return self.w1[:, nq:].reshape(-1, self.n_past_f, self.n_coords).sum(axis=1)

    @property
    def y_box(self) -> tuple[np.ndarray, np.ndarray]:
        """(C,), (C,) centre and half-width of a box holding every output N can give
        (b_out +- sum |w_out|, every tanh in [-1, 1]), slightly widened."""
        return self.b_out.copy(), np.abs(self.w_out).sum(axis=1) * (1 + 1e-9) + 1e-12

    def held(self, q: np.ndarray) -> np.ndarray:
        """(..., H1) first-layer pre-activation from the bias and the held deflection ``q``
        (..., C)."""
        qs = (np.asarray(q, dtype=np.float64) - self.q_offset) / self.q_scale
        nq = self.n_coords * (1 + self.n_past_x)
        wq_sum = self.w1[:, :nq].reshape(-1, 1 + self.n_past_x, self.n_coords).sum(axis=1)
        return self.b1 + np.sum(qs[..., None, :] * wq_sum, axis=-1)

    def force(self, q: np.ndarray, y: np.ndarray) -> np.ndarray:
        """(..., C) static force of outputs ``y`` held at ``q`` (each (..., C)): K q + f_offset
        + f_scale y (N, or N m for a rotation)."""
        q = np.asarray(q, dtype=np.float64)
        return np.sum(q[..., None, :] * self.k, axis=-1) + self.f_offset + self.f_scale * y

    def _layers(self, c: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Output N (..., C) and G = dN / d(first pre-activation) (..., C, H1) at (c, y)."""
        h1 = np.tanh(c + y @ self.s.T)
        g1 = 1.0 - h1 * h1
        if self.two_layers:
            h2 = np.tanh(h1 @ self.w2.T + self.b2)
            g = ((self.w_out * (1.0 - h2 * h2)[..., None, :]) @ self.w2) * g1[..., None, :]
            return h2 @ self.w_out.T + self.b_out, g
        return h1 @ self.w_out.T + self.b_out, self.w_out * g1[..., None, :]

    def phi(self, c: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """phi (..., C) and its Jacobian (..., C, C) at pre-activations ``c`` (..., H1) and
        points ``y`` (..., C)."""
        out, g = self._layers(c, y)
        return out - y, g @ self.s - np.eye(self.n_coords)

    def lag_matrices(self, c: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A (..., n_past_f, C, C): dN/dy_{t-l}, l = 1..; B (..., 1 + n_past_x, C, C):
        dN/dqs_{t-l}, l = 0.. (scaled coordinates), of the recurrence linearised about (c, y).
        sum_l A_l - I is phi's Jacobian."""
        _, g = self._layers(c, y)
        g = g[..., None, :, :]
        return g @ self.wy, g @ self.wq

    # ----- one coordinate, as scalars -------------------------------------------------------
    @property
    def x_offset_m(self) -> float:
        return float(self.q_offset[0])

    @property
    def x_scale_m(self) -> float:
        return float(self.q_scale[0])

    @property
    def f_offset_n(self) -> float:
        return float(self.f_offset[0])

    @property
    def f_scale_n(self) -> float:
        return float(self.f_scale[0])

    @property
    def k_n_per_m(self) -> float:
        return float(self.k[0, 0])

    @property
    def c_ns_per_m(self) -> float:
        return float(self.c[0, 0])

    @property
    def x_columns(self) -> np.ndarray:
        """(H1, 1 + n_past_x): first-layer weights of x_t, x_{t-1}, ... (one coordinate)."""
        return self.w1[:, : 1 + self.n_past_x]

    @property
    def y_columns(self) -> np.ndarray:
        """(H1, n_past_f): first-layer weights of y_{t-1}, ... (one coordinate)."""
        return self.w1[:, 1 + self.n_past_x :]

    @property
    def y_range(self) -> tuple[float, float]:
        """Interval holding every output N can give: b_out -+ sum |w_out| (one coordinate)."""
        half = float(np.sum(np.abs(self.w_out)))
        return float(self.b_out[0]) - half, float(self.b_out[0]) + half

    def held_preactivation(self, x_m: np.ndarray) -> np.ndarray:
        """(..., H1) :meth:`held` of one-coordinate holds ``x_m`` (...)."""
        return self.held(np.asarray(x_m, dtype=np.float64)[..., None])

    def force_n(self, x_m: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Static force of one-coordinate output ``y`` held at ``x_m``: k x + f_offset +
        f_scale y, N."""
        return self.k_n_per_m * np.asarray(x_m) + self.f_offset_n + self.f_scale_n * np.asarray(y)

    def output_of_force(self, x_m: np.ndarray, f_n: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`force_n` in a hold (v = 0)."""
        return (np.asarray(f_n) - self.k_n_per_m * np.asarray(x_m) - self.f_offset_n) / (
            self.f_scale_n
        )


def narx_net(model) -> NarxNet:
    """The certificate's view of ``model`` (a NARX network of any number of coordinates: nn,
    hybrid, nn-axis); ``CertifyError`` for any other kind."""
    from bushenv.models.narx import NarxBushing
    from bushenv.models.planar_narx import N_PAST_F, N_PAST_Q, PlanarHybrid, PlanarNarx

    if isinstance(model, NarxBushing):
        one = np.ones(1)
        k = float(getattr(model, "k_n_per_m", 0.0))
        c = float(getattr(model, "c_ns_per_m", 0.0))
        return NarxNet(
            n_past_x=model.n_past_x,
            n_past_f=model.n_past_f,
            q_offset=model.x_offset_m * one,
            q_scale=model.x_scale_m * one,
            f_offset=model.f_offset_n * one,
            f_scale=model.f_scale_n * one,
            w1=np.array(model.w1),
            b1=np.array(model.b1),
            w2=np.array(model.w2),
            b2=np.array(model.b2),
            w_out=np.array(model.w_out).reshape(1, -1),
            b_out=float(model.b_out) * one,
            k=np.array([[k]]),
            c=np.array([[c]]),
            dt_s=float(model.dt),
            model_name=model.name,
            units=tuple(model.units),
            coords=tuple(model.coords),
        )
    if isinstance(model, PlanarNarx):
        # the linear backbone of a matrix hybrid; a pure network has none, and the vector
        # Bouc-Wen backbone of hybrid-bw is not part of the held recurrence (as before the merge)
        zero = np.zeros((model.n_coords, model.n_coords))
        linear = isinstance(model, PlanarHybrid)
        k, c = (model.k_matrix, model.c_matrix) if linear else (zero, zero)
        hidden = model.w1.shape[0]
        return NarxNet(
            n_past_x=N_PAST_Q,
            n_past_f=N_PAST_F,
            q_offset=np.array(model.q_offset),
            q_scale=np.array(model.q_scale),
            f_offset=np.array(model.f_offset),
            f_scale=np.array(model.f_scale),
            w1=np.array(model.w1),
            b1=np.array(model.b1),
            w2=np.zeros((0, hidden)),
            b2=np.zeros(0),
            w_out=np.array(model.w_out),
            b_out=np.array(model.b_out),
            k=np.array(k),
            c=np.array(c),
            dt_s=float(model.dt),
            model_name=model.name,
            units=tuple(model.units),
            coords=tuple(model.coords),
        )
    name = getattr(model, "name", "?")
    raise CertifyError(
        f"certificates are for NARX models (nn, hybrid), over several coordinates also nn-axis; "
        f"got a {type(model).__name__} ({name!r} model), which holds by construction"
    )


def diagonal(net: NarxNet, c: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """phi(y) and dphi/dy of a one-coordinate network, each of y's shape; ``c`` (..., H1)
    broadcasts against ``y[..., None]``."""
    phi, jac = net.phi(c, np.asarray(y, dtype=np.float64)[..., None])
    return phi[..., 0], jac[..., 0, 0]


def derivative_bounds(net: NarxNet) -> tuple[float, float]:
    """(L, M): |dN/dy| <= L and |d^2 N / dy^2| <= M along the diagonal of a one-coordinate
    network, for every held x.

    With s = the row sums of the y-columns of w1 and kappa = ``TANH_CURVATURE``:
    one layer, N = w_out . tanh(c + s y): L = sum |w_out s|, M = kappa sum |w_out| s^2.
    Two layers, N = w_out . tanh(W2 tanh(c + s y) + b2): with r_k = sum_i |W2_ki s_i|,
    L = sum_k |w_out_k| r_k and M = kappa sum_k |w_out_k| (r_k^2 + sum_i |W2_ki| s_i^2)
    (chain rule; every tanh' is in [0, 1] and every |tanh''| <= kappa).
    """
    s = net.s[:, 0]
    w = np.abs(net.w_out[0])
    if not net.two_layers:
        return float(np.sum(w * np.abs(s))), float(TANH_CURVATURE * np.sum(w * s * s))
    a2 = np.abs(net.w2)
    r = a2 @ np.abs(s)
    m = TANH_CURVATURE * np.sum(w * (r * r + a2 @ (s * s)))
    return float(np.sum(w * r)), float(m)


def lag_gradients(net: NarxNet, c: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The lag matrices of a one-coordinate network as scalars: (a, b).

    ``a`` (..., n_past_f): dN/dy_{t-j}, j = 1..n_past_f; ``b`` (..., 1 + n_past_x):
    dN/dxs_{t-j}, j = 0..n_past_x (scaled displacement). sum(a) - 1 = dphi/dy.
    """
    a, b = net.lag_matrices(c, np.asarray(y, dtype=np.float64)[..., None])
    return a[..., 0, 0], b[..., 0, 0]


def describe(net: NarxNet) -> dict:
    """What a certificate records of the network it certifies (its shape, rate and backbone),
    so a certificate can be matched to a model later."""
    one = net.n_coords == 1
    return {
        "name": net.model_name,
        "hidden": [int(net.w1.shape[0])] + ([int(net.w2.shape[0])] if net.two_layers else []),
        "n_past_x": net.n_past_x,
        "n_past_f": net.n_past_f,
        "dt_s": net.dt_s,
        "k_n_per_m": net.k_n_per_m if one else net.k.tolist(),
        "c_ns_per_m": net.c_ns_per_m if one else net.c.tolist(),
    }
