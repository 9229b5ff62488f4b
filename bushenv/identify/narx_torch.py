"""The NARX network in torch for training: its free-run unroll and the numba kernels behind it.

``TorchNarx`` has the parameter layout of ``models.narx.NarxBushing`` (float64); ``unroll``
runs it free on its own outputs, either step by step in torch (the reference) or through the
compiled forward and exact backward passes below (``engine="numba"``, the same values and
gradients to rounding, tested). Torch only trains: the trained arrays go to the numpy model,
whose numba kernel does every free run in use.
"""

from __future__ import annotations

from collections.abc import Sequence

import numba as nb
import numpy as np
import torch

from bushenv.identify.data import IdentificationError
from bushenv.identify.narx_options import ENGINES
from bushenv.models.narx import NarxBushing

# ----- the free-run unroll with a hand-written backward pass (numba) ------------------------
# Training time is the unroll: L sequential steps of a 9-unit net, where torch spends ~10
# microseconds of dispatch per operation and autograd node. These two kernels do the same
# forward pass and its exact backward pass (backpropagation through time) in compiled loops;
# ``TorchNarx.unroll(..., engine="torch")`` stays the reference they are tested against.


@nb.njit(cache=True, nogil=True)
def _unroll_forward(zx, yh0, wy, w2, b2, w_out, b_out, h1s, h2s, ys):
    n_win, length, h1n = zx.shape
    nf = yh0.shape[1]
    h2n = w2.shape[0]
    yh = np.empty(nf)
    for w in range(n_win):
        for k in range(nf):
            yh[k] = yh0[w, k]
        for j in range(length):
            for u in range(h1n):
                acc = zx[w, j, u]
                for k in range(nf):
                    acc += wy[u, k] * yh[k]
                h1s[w, j, u] = np.tanh(acc)
            y = b_out
            if h2n > 0:
                for u2 in range(h2n):
                    acc = b2[u2]
                    for u in range(h1n):
                        acc += w2[u2, u] * h1s[w, j, u]
                    t = np.tanh(acc)
                    h2s[w, j, u2] = t
                    y += w_out[u2] * t
            else:
                for u in range(h1n):
                    y += w_out[u] * h1s[w, j, u]
            ys[w, j] = y
            for k in range(nf - 1, 0, -1):
                yh[k] = yh[k - 1]
            yh[0] = y


@nb.njit(cache=True, nogil=True)
def _unroll_backward(gys, yh0, wy, w2, w_out, h1s, h2s, ys, g_zx, g_wy, g_w2, g_b2, g_wout):
    """Gradients of sum(gys * ys) (ys from ``_unroll_forward``); accumulates into the g_*
    arrays (zeroed by the caller), returns the gradient of b_out."""
    n_win, length, h1n = h1s.shape
    nf = wy.shape[1]
    h2n = w2.shape[0]
    pending = np.empty(length)  # d loss / d y_j through the later steps that feed on y_j
    dh1 = np.empty(h1n)
    g_bout = 0.0
    for w in range(n_win):
        pending[:] = 0.0
        for j in range(length - 1, -1, -1):
            gy = gys[w, j] + pending[j]
            g_bout += gy
            if h2n > 0:
                dh1[:] = 0.0
                for u2 in range(h2n):
                    t = h2s[w, j, u2]
                    g_wout[u2] += gy * t
                    d = gy * w_out[u2] * (1.0 - t * t)
                    g_b2[u2] += d
                    for u in range(h1n):
                        g_w2[u2, u] += d * h1s[w, j, u]
                        dh1[u] += w2[u2, u] * d
            else:
                for u in range(h1n):
                    g_wout[u] += gy * h1s[w, j, u]
                    dh1[u] = gy * w_out[u]
            for u in range(h1n):
                t = h1s[w, j, u]
                dz = dh1[u] * (1.0 - t * t)
                g_zx[w, j, u] = dz
                for k in range(nf):
                    src = j - 1 - k  # the input y_{j-1-k}: an output of this window or history
                    if src >= 0:
                        g_wy[u, k] += dz * ys[w, src]
                        pending[src] += wy[u, k] * dz
                    else:
                        g_wy[u, k] += dz * yh0[w, k - j]
    return g_bout


def _np(t: torch.Tensor) -> np.ndarray:
    return np.ascontiguousarray(t.detach().cpu().numpy(), dtype=np.float64)


class _NumbaUnroll(torch.autograd.Function):
    """ys = unroll(zx, yh0; wy, w2, b2, w_out, b_out), forward and backward in numba."""

    @staticmethod
    def forward(ctx, zx, yh0, wy, w2, b2, w_out, b_out):
        zx_, yh0_, wy_, w2_, wout_ = _np(zx), _np(yh0), _np(wy), _np(w2), _np(w_out)
        n_win, length, h1n = zx_.shape
        h1s = np.empty((n_win, length, h1n))
        h2s = np.empty((n_win, length, w2_.shape[0]))
        ys = np.empty((n_win, length))
        _unroll_forward(zx_, yh0_, wy_, w2_, _np(b2), wout_, float(b_out), h1s, h2s, ys)
        ctx.saved = (yh0_, wy_, w2_, wout_, h1s, h2s, ys)
        return torch.from_numpy(ys)

    @staticmethod
    def backward(ctx, gys):
        yh0_, wy_, w2_, wout_, h1s, h2s, ys = ctx.saved
        g_zx = np.empty_like(h1s)
        g_wy = np.zeros_like(wy_)
        g_w2 = np.zeros_like(w2_)
        g_b2 = np.zeros(w2_.shape[0])
        g_wout = np.zeros_like(wout_)
        g_bout = _unroll_backward(
            _np(gys), yh0_, wy_, w2_, wout_, h1s, h2s, ys, g_zx, g_wy, g_w2, g_b2, g_wout
        )
        t = torch.from_numpy
        return (
            t(g_zx),
            None,
            t(g_wy),
            t(g_w2),
            t(g_b2),
            t(g_wout),
            torch.tensor(g_bout, dtype=torch.float64),
        )


class TorchNarx(torch.nn.Module):
    """The NARX net with the numpy model's parameter layout (float64).

    ``basis`` (n_in, n_in), identity by default: the first layer's trained weights act on
    ``basis @ u`` for the lagged input u, so the model's weights are ``w1 @ basis``
    (``w1_eff``, what ``arrays`` exports). A change of variables for the optimiser only.
    """

    def __init__(self, n_in: int, hidden: tuple[int, ...], basis: np.ndarray | None = None):
        super().__init__()
        b = np.eye(n_in) if basis is None else np.asarray(basis, dtype=np.float64)
        if b.shape != (n_in, n_in):
            raise IdentificationError(f"basis must be ({n_in}, {n_in}), got {b.shape}")
        self.register_buffer("basis", torch.from_numpy(b.copy()))
        h1 = hidden[0]
        h2 = hidden[1] if len(hidden) == 2 else 0
        lin1 = torch.nn.Linear(n_in, h1).double()
        self.w1 = torch.nn.Parameter(lin1.weight.detach().clone())
        self.b1 = torch.nn.Parameter(lin1.bias.detach().clone())
        if h2:
            lin2 = torch.nn.Linear(h1, h2).double()
            self.w2 = torch.nn.Parameter(lin2.weight.detach().clone())
            self.b2 = torch.nn.Parameter(lin2.bias.detach().clone())
        else:
            self.w2 = torch.nn.Parameter(torch.zeros(0, h1, dtype=torch.float64))
            self.b2 = torch.nn.Parameter(torch.zeros(0, dtype=torch.float64))
        last = h2 or h1
        lin3 = torch.nn.Linear(last, 1).double()
        self.w_out = torch.nn.Parameter(lin3.weight.detach().clone()[0])
        self.b_out = torch.nn.Parameter(lin3.bias.detach().clone()[0])

    def head(self, z1: torch.Tensor) -> torch.Tensor:
        """From first-layer pre-activations (..., H1) to the scaled output (...)."""
        h = torch.tanh(z1)
        if self.w2.shape[0]:
            h = torch.tanh(h @ self.w2.T + self.b2)
        return h @ self.w_out + self.b_out

    def w1_eff(self) -> torch.Tensor:
        """The first layer's weights on the lagged inputs (the model's w1)."""
        return self.w1 @ self.basis

    def forward(self, inp: torch.Tensor) -> torch.Tensor:
        return self.head(inp @ self.w1_eff().T + self.b1)

    def unroll(
        self, x_in: torch.Tensor, y_hist: torch.Tensor, n_past_x: int, engine: str = "torch"
    ) -> torch.Tensor:
        """Free run: x_in (W, L, 1 + n_past_x) = [x_t, x_{t-1}, ...]; y_hist (W, n_past_f) =
        [y_{t-1}, y_{t-2}, ...] at the first step. Returns (W, L) scaled outputs.

        ``engine="numba"``: the same values (to rounding) and gradients from the compiled
        kernels above; ``"torch"``: step by step in torch (the reference)."""
        nx1 = 1 + n_past_x
        w1 = self.w1_eff()
        zx = x_in @ w1[:, :nx1].T + self.b1  # the x part of layer 1 for every step at once
        wy = w1[:, nx1:]
        if engine == "numba":
            return _NumbaUnroll.apply(zx, y_hist, wy, self.w2, self.b2, self.w_out, self.b_out)
        if engine != "torch":
            raise IdentificationError(f"unroll engine must be one of {ENGINES}, got {engine!r}")
        outs = []
        for j in range(x_in.shape[1]):
            y = self.head(zx[:, j] + y_hist @ wy.T)
            outs.append(y)
            y_hist = torch.cat([y[:, None], y_hist[:, :-1]], dim=1)
        return torch.stack(outs, dim=1)

    def load_from(self, model: NarxBushing) -> TorchNarx:
        with torch.no_grad():
            self.basis.copy_(torch.eye(self.basis.shape[0], dtype=torch.float64))
            for name in ("w1", "b1", "w2", "b2", "w_out"):
                getattr(self, name).copy_(torch.from_numpy(np.asarray(getattr(model, name))))
            self.b_out.fill_(float(model.b_out))
        return self

    def arrays(self) -> dict[str, np.ndarray]:
        out = {k: v.detach().cpu().numpy().copy() for k, v in self.named_parameters()}
        out["w1"] = self.w1_eff().detach().cpu().numpy().copy()
        return out


def difference_basis(
    n_past_x: int,
    n_past_f: int,
    xs: np.ndarray | Sequence[np.ndarray],
    ys: np.ndarray | Sequence[np.ndarray],
) -> np.ndarray:
    """Basis of [x_t, gx dx_t, ..., gx dx_{t-nx+1}, y_{t-1}, gy dy_{t-1}, ...] over the lagged
    input [x_t, ..., x_{t-nx}, y_{t-1}, ..., y_{t-nf}] (dx_t = x_t - x_{t-1}); gx, gy scale
    the differences to the spread of the signal itself on the training part (xs, ys scaled;
    one array, or one per record: no difference spans two records)."""

    def gain(parts: np.ndarray | Sequence[np.ndarray]) -> float:
        parts = [parts] if isinstance(parts, np.ndarray) else list(parts)
        s = np.concatenate(parts)
        d = np.std(np.concatenate([np.diff(p) for p in parts]))
        return float(np.std(s) / d) if d > 0 else 1.0

    n = 1 + n_past_x + n_past_f
    b = np.zeros((n, n))
    for first, count, g in ((0, 1 + n_past_x, gain(xs)), (1 + n_past_x, n_past_f, gain(ys))):
        b[first, first] = 1.0
        for j in range(1, count):
            b[first + j, first + j - 1] = g
            b[first + j, first + j] = -g
    return b


def x_windows(xs_p: np.ndarray, starts: np.ndarray, length: int, n_past_x: int) -> np.ndarray:
    """(W, L, 1 + n_past_x) lagged displacement inputs for predictions at starts..starts+L-1."""
    lags = np.arange(n_past_x + 1)
    idx = starts[:, None, None] + np.arange(length)[None, :, None] - lags[None, None, :]
    return xs_p[idx]


def y_history(ys_p: np.ndarray, starts: np.ndarray, n_past_f: int) -> np.ndarray:
    """(W, n_past_f) measured outputs [y_{s-1}, ..., y_{s-n}] before each start s."""
    return ys_p[starts[:, None] - 1 - np.arange(n_past_f)[None, :]]


def torch_free_run(model: NarxBushing, x, v=None) -> np.ndarray:
    """Free run of a numpy NARX/hybrid model from rest done in torch (float64), (T,) -> (T,).

    The reference the numba kernel is tested against; also how training sees the model.
    """
    x = np.asarray(x, dtype=np.float64)
    v = np.gradient(x, model.dt) if v is None else np.asarray(v, dtype=np.float64)
    net = TorchNarx(model.n_inputs, model.hidden).load_from(model)
    pad = max(model.n_past_x, model.n_past_f)
    x_rest = (0.0 - model.x_offset_m) / model.x_scale_m
    xs_p = np.concatenate([np.full(pad, x_rest), (x - model.x_offset_m) / model.x_scale_m])
    x_in = x_windows(xs_p, np.array([pad]), len(x), model.n_past_x)
    y_hist = np.full((1, model.n_past_f), model._rest_output_scaled())
    with torch.no_grad():
        ys = net.unroll(torch.from_numpy(x_in), torch.from_numpy(y_hist), model.n_past_x)
    k, c = model._backbone()
    return k * x + c * v + (model.f_offset_n + model.f_scale_n * ys[0].numpy())
