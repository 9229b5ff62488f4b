"""Torch training of the NARX network bushings ("nn", seed 000 §4.2; "hybrid", seed 000 §3).

Torch trains; it never runs per step in use: the result is exported to the numpy parameters of
``NarxBushing`` / ``HybridBushing``, whose numba kernel does the free run.

Procedure (``fit_narx``), all seeded:

1. Split the record: the first (1 - ``val_fraction``) trains, the last part validates.
2. Hybrid only: backbone k, c by least squares on the training part (seed 000 §4.1); the
   network's target is the residual F - k x - c v. Pure NN: the target is F.
3. Scale displacement and target to [-1, 1] over the training part (seed 000 §4.2).
4. One-step-ahead (teacher forcing) training: the past forces fed to the net are the measured
   ones. Full-batch Adam.
5. Multi-step (free-run) fine-tuning: windows of the training record, the net started from
   the measured history at the window start and then fed ITS OWN outputs for L samples
   (truncated unrolled simulation, L grows over ``window_lengths``, 0.1 s to 7.8 s); loss on
   every sample. Stages whose windows exceed a quarter of the training part are skipped.
6. Validation: after the teacher stage and every ``eval_every`` fine-tuning iterations, a free
   run over the whole validation part (started from the measured history before it); the
   weights with the lowest validation free-run RMS ratio are kept. After ``patience``
   evaluations without improvement the stage ends (``early_stop="stage"``: the next, longer
   windows take over) or the whole training does (``"training"``).

Why step 5: a net trained one step ahead on measured past forces, then run on its own, can
self-oscillate on data like its training data (DESIGN-NOTES); then its later divergence on a
step would say nothing about NARX models. Iteration counts, not the clock, decide when to stop,
so a seed reproduces the weights; ``time_budget_s`` is only a safety cap (reported if hit).

What the defaults buy (radial and axial reference, 40 s at n = 1, 2 record seeds x 2 training
seeds, free-run RMS ratio on the 8 s validation split; an unseen 20 s n = 1 record gives
0.1-0.5 points less): 5.7-6.7 % radial and 5.0-6.1 % axial with the earlier defaults (lag
basis, torch unroll, windows up to 400 samples, 450 iterations, learning rate 3e-3); 3.0-3.6 %
radial and 2.6-2.9 % axial now, in 9-30 s instead of 15-17 s (2 shared cores). Three changes
made it:

- the ``"numba"`` engine: the unroll and its exact backward pass as compiled loops (torch
  spends ~10 us of dispatch per step and operation; 400-sample windows cost 2.6 ms instead of
  50 ms per iteration), so the free run trains for thousands of iterations and on windows up
  to 1600 samples within seconds; ``"torch"`` is the reference it is tested against;
- ``input_basis="differences"``: the first layer trains on [x_t, dx_t, ..., y_{t-1}, dy_{t-1},
  ...] (differences scaled to the signal's spread), an invertible change of variables folded
  back into w1 at export. The damper force (half the RMS force) is a difference of nearly
  equal lagged inputs; in this basis it is one input, and training no longer depends on the
  seed by a point or more;
- ``early_stop="stage"``: the short windows can worsen the free run before the long ones
  mend it; an early stop there ended the whole training.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numba as nb
import numpy as np
import torch

from bushenv.identify.linear import IdentificationError, check_record, least_squares_kc
from bushenv.metrics import rms_ratio
from bushenv.models.base import PAPER_DT
from bushenv.models.hybrid import HybridBushing
from bushenv.models.narx import HIDDEN, N_PAST_F, N_PAST_X, NarxBushing, scaling_of

INPUT_BASES = ("lags", "differences")
EARLY_STOPS = ("training", "stage")
ENGINES = ("numba", "torch")


@dataclass
class NarxTrainingOptions:
    hidden: tuple[int, ...] = HIDDEN
    n_past_x: int = N_PAST_X
    n_past_f: int = N_PAST_F
    val_fraction: float = 0.2
    teacher_steps: int = 2000
    teacher_lr: float = 1e-2
    window_lengths: tuple[int, ...] = (20, 100, 400, 800, 1600)  # 0.1 to 7.8 s at 204.8 Hz
    iters_per_length: tuple[int, ...] = (1200, 1200, 1200, 1200, 1200)
    batch_windows: int = 16
    free_run_lr: float = 1e-2
    free_run_lr_final: float = 1.0  # cosine decay to free_run_lr * this over all iterations
    input_basis: str = "differences"  # or "lags": the variables the first layer trains in
    engine: str = "numba"  # the free-run unroll in training: "numba" (fast) or "torch"
    grad_clip: float = 1.0
    weight_decay: float = 0.0
    eval_every: int = 25
    patience: int = 8
    early_stop: str = "stage"  # patience ends: "stage" (one window length) or "training"
    threads: int = 1
    time_budget_s: float = 120.0
    progress_every_s: float = 3.0
    extra: dict[str, Any] = field(default_factory=dict)

    def check(self) -> None:
        if len(self.window_lengths) != len(self.iters_per_length):
            raise IdentificationError(
                f"window_lengths {self.window_lengths} and iters_per_length "
                f"{self.iters_per_length} must have the same length"
            )
        if not 0.0 < self.val_fraction < 0.9:
            raise IdentificationError(f"val_fraction must be in (0, 0.9), got {self.val_fraction}")
        if self.early_stop not in EARLY_STOPS:
            raise IdentificationError(
                f"early_stop must be one of {EARLY_STOPS}, got {self.early_stop!r}"
            )
        if self.engine not in ENGINES:
            raise IdentificationError(f"engine must be one of {ENGINES}, got {self.engine!r}")
        if self.input_basis not in INPUT_BASES:
            raise IdentificationError(
                f"input_basis must be one of {INPUT_BASES}, got {self.input_basis!r}"
            )
        if min(self.window_lengths, default=1) < 1:
            raise IdentificationError(f"window_lengths must be >= 1, got {self.window_lengths}")


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


def difference_basis(n_past_x: int, n_past_f: int, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """Basis of [x_t, gx dx_t, ..., gx dx_{t-nx+1}, y_{t-1}, gy dy_{t-1}, ...] over the lagged
    input [x_t, ..., x_{t-nx}, y_{t-1}, ..., y_{t-nf}] (dx_t = x_t - x_{t-1}); gx, gy scale
    the differences to the spread of the signal itself on the training part (xs, ys scaled)."""

    def gain(s: np.ndarray) -> float:
        d = np.std(np.diff(s))
        return float(np.std(s) / d) if d > 0 else 1.0

    n = 1 + n_past_x + n_past_f
    b = np.zeros((n, n))
    for first, count, g in ((0, 1 + n_past_x, gain(xs)), (1 + n_past_x, n_past_f, gain(ys))):
        b[first, first] = 1.0
        for j in range(1, count):
            b[first + j, first + j - 1] = g
            b[first + j, first + j] = -g
    return b


def _x_windows(xs_p: np.ndarray, starts: np.ndarray, length: int, n_past_x: int) -> np.ndarray:
    """(W, L, 1 + n_past_x) lagged displacement inputs for predictions at starts..starts+L-1."""
    lags = np.arange(n_past_x + 1)
    idx = starts[:, None, None] + np.arange(length)[None, :, None] - lags[None, None, :]
    return xs_p[idx]


def _y_history(ys_p: np.ndarray, starts: np.ndarray, n_past_f: int) -> np.ndarray:
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
    x_in = _x_windows(xs_p, np.array([pad]), len(x), model.n_past_x)
    y_hist = np.full((1, model.n_past_f), model._rest_output_scaled())
    with torch.no_grad():
        ys = net.unroll(torch.from_numpy(x_in), torch.from_numpy(y_hist), model.n_past_x)
    k, c = model._backbone()
    return k * x + c * v + (model.f_offset_n + model.f_scale_n * ys[0].numpy())


def fit_nn(x, f, dt: float = PAPER_DT, **kwargs: Any) -> NarxBushing:
    """Identify the pure NARX network (``fit_narx`` with kind "nn")."""
    return fit_narx("nn", x, f, dt, **kwargs)


def fit_hybrid(x, f, dt: float = PAPER_DT, **kwargs: Any) -> HybridBushing:
    """Identify the hybrid: least-squares backbone + NARX residual (``fit_narx``)."""
    return fit_narx("hybrid", x, f, dt, **kwargs)


def fit_narx(
    kind: str,
    x,
    f,
    dt: float = PAPER_DT,
    v=None,
    seed: int = 0,
    progress: bool = True,
    **options: Any,
) -> NarxBushing:
    """Identify a "nn" (NarxBushing) or "hybrid" (HybridBushing) model from one record.

    ``options`` are fields of ``NarxTrainingOptions``. The returned model carries a ``training``
    dict (losses, validation RMS ratios, times) as an attribute; it is not saved in the file.
    """
    if kind not in ("nn", "hybrid"):
        raise IdentificationError(f"fit_narx: kind must be 'nn' or 'hybrid', got {kind!r}")
    unknown = set(options) - set(NarxTrainingOptions.__dataclass_fields__)
    if unknown:
        raise IdentificationError(f"fit_narx: unknown options {sorted(unknown)}")
    if "hidden" in options:
        options["hidden"] = tuple(int(h) for h in options["hidden"])
    opt = NarxTrainingOptions(**options)
    opt.check()
    x, f, v = check_record(x, f, dt, v)
    T = len(x)
    t_train = int(round(T * (1.0 - opt.val_fraction)))
    nx, nf = opt.n_past_x, opt.n_past_f
    if t_train < 4 * min(opt.window_lengths) or T - t_train < 10:
        raise IdentificationError(
            f"record of {T} samples too short for windows of {min(opt.window_lengths)} samples "
            f"and a {opt.val_fraction:.0%} validation split"
        )
    stages = [
        (length, n_iter)
        for length, n_iter in zip(opt.window_lengths, opt.iters_per_length, strict=True)
        if 4 * length <= t_train
    ]
    skipped = [length for length in opt.window_lengths if 4 * length > t_train]

    k = c = 0.0
    if kind == "hybrid":
        k, c = least_squares_kc(x[:t_train], f[:t_train], v[:t_train])
    backbone = k * x + c * v
    target = f - backbone

    x_off, x_sc = scaling_of(x[:t_train].min(), x[:t_train].max())
    f_off, f_sc = scaling_of(target[:t_train].min(), target[:t_train].max())
    pad = max(nx, nf)
    xs_p = np.concatenate([np.full(pad, (0.0 - x_off) / x_sc), (x - x_off) / x_sc])
    ys_p = np.concatenate([np.full(pad, (0.0 - f_off) / f_sc), (target - f_off) / f_sc])

    old_threads = torch.get_num_threads()
    torch.set_num_threads(max(1, int(opt.threads)))
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    last_print = [t0]

    def say(msg: str, force: bool = False) -> None:
        now = time.perf_counter()
        if progress and (force or now - last_print[0] >= opt.progress_every_s):
            print(f"[{kind} {now - t0:6.1f} s] {msg}", flush=True)
            last_print[0] = now

    try:
        basis = None
        if opt.input_basis == "differences":
            basis = difference_basis(nx, nf, xs_p[pad : pad + t_train], ys_p[pad : pad + t_train])
        net = TorchNarx(1 + nx + nf, opt.hidden, basis)

        # --- validation: free run over the held-out part from the measured history -------
        v_start = np.array([t_train + pad])
        v_x_in = torch.from_numpy(_x_windows(xs_p, v_start, T - t_train, nx))
        v_y_hist = torch.from_numpy(_y_history(ys_p, v_start, nf))
        f_val = f[t_train:]
        backbone_val = backbone[t_train:]

        def validate() -> float:
            with torch.no_grad():
                ys = net.unroll(v_x_in, v_y_hist, nx, opt.engine)[0].numpy()
            pred = backbone_val + f_off + f_sc * ys
            if not np.all(np.isfinite(pred)):
                return float("inf")
            return rms_ratio(f_val, pred)

        def penalty() -> torch.Tensor:
            # L2 on the hidden-layer weights keeps units near tanh's linear part, so the net
            # extrapolates to larger amplitudes like a linear filter rather than saturating
            return opt.weight_decay * (torch.sum(net.w1_eff() ** 2) + torch.sum(net.w2**2))

        # --- stage 1: one step ahead on measured past outputs ------------------------------
        starts = np.arange(pad, t_train + pad)
        inp = np.concatenate(
            [_x_windows(xs_p, starts, 1, nx)[:, 0, :], _y_history(ys_p, starts, nf)], axis=1
        )
        inp_t = torch.from_numpy(inp)
        tgt_t = torch.from_numpy(ys_p[starts])
        adam = torch.optim.Adam(net.parameters(), lr=opt.teacher_lr)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(adam, max(1, opt.teacher_steps))
        teacher_losses = []
        for i in range(opt.teacher_steps):
            adam.zero_grad()
            loss = torch.mean((net(inp_t) - tgt_t) ** 2)
            (loss + penalty()).backward()
            adam.step()
            sched.step()
            teacher_losses.append(loss.item())
            say(f"teacher step {i + 1}/{opt.teacher_steps}: one-step MSE {loss.item():.3e}")
        val_after_teacher = validate()
        say(
            f"teacher forcing done: one-step MSE {teacher_losses[-1]:.3e} (scaled), "
            f"validation free-run RMS ratio {val_after_teacher:.4f}",
            force=True,
        )

        # --- stage 2: multi-step free-run fine-tuning ---------------------------------------
        best_val = val_after_teacher
        best_state = {k_: t.detach().clone() for k_, t in net.state_dict().items()}
        history = [(0, val_after_teacher)]
        free_losses = []
        adam = torch.optim.Adam(net.parameters(), lr=opt.free_run_lr)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(
            adam, max(1, sum(n for _, n in stages)), eta_min=opt.free_run_lr * opt.free_run_lr_final
        )
        it = 0
        stale = 0
        stopped = "iterations done"
        stage_stops = []
        if skipped:
            say(f"windows {skipped} skipped: longer than a quarter of {t_train} samples", True)
        for length, n_iter in stages:
            if opt.early_stop == "stage":
                stale = 0
            for _ in range(n_iter):
                it += 1
                s = rng.integers(pad, t_train + pad - length + 1, size=opt.batch_windows)
                x_in = torch.from_numpy(_x_windows(xs_p, s, length, nx))
                y_hist = torch.from_numpy(_y_history(ys_p, s, nf))
                tgt = torch.from_numpy(ys_p[s[:, None] + np.arange(length)[None, :]])
                adam.zero_grad()
                loss = torch.mean((net.unroll(x_in, y_hist, nx, opt.engine) - tgt) ** 2)
                (loss + penalty()).backward()
                torch.nn.utils.clip_grad_norm_(net.parameters(), opt.grad_clip)
                adam.step()
                sched.step()
                free_losses.append(loss.item())
                if it % opt.eval_every == 0:
                    val = validate()
                    history.append((it, val))
                    if val < best_val:
                        best_val = val
                        best_state = {k_: t.detach().clone() for k_, t in net.state_dict().items()}
                        stale = 0
                    else:
                        stale += 1
                    say(
                        f"free-run iter {it} (window {length}): loss {loss.item():.3e}, "
                        f"validation RMS ratio {val:.4f} (best {best_val:.4f})"
                    )
                    if stale >= opt.patience and opt.early_stop == "stage":
                        stage_stops.append((length, it))
                        say(f"window {length}: patience {opt.patience} ran out at {it}", True)
                        break
                    if stale >= opt.patience:
                        stopped = f"early stop at iteration {it} (patience {opt.patience})"
                        break
                if time.perf_counter() - t0 > opt.time_budget_s:
                    stopped = f"time budget {opt.time_budget_s} s hit at iteration {it}"
                    break
            else:
                continue
            if stopped != "iterations done":
                break
        net.load_state_dict(best_state)
        elapsed = time.perf_counter() - t0
        say(
            f"done in {elapsed:.1f} s ({stopped}); best validation free-run RMS ratio "
            f"{best_val:.4f}",
            force=True,
        )
    finally:
        torch.set_num_threads(old_threads)

    arrays = net.arrays()
    common = dict(
        x_offset_m=x_off,
        x_scale_m=x_sc,
        f_offset_n=f_off,
        f_scale_n=f_sc,
        w1=arrays["w1"],
        b1=arrays["b1"],
        w2=arrays["w2"],
        b2=arrays["b2"],
        w_out=arrays["w_out"],
        b_out=float(arrays["b_out"]),
        n_past_x=nx,
        n_past_f=nf,
        dt=dt,
    )
    if kind == "hybrid":
        model: NarxBushing = HybridBushing(k_n_per_m=k, c_ns_per_m=c, **common)
    else:
        model = NarxBushing(**common)
    model.training = {
        "options": asdict(opt),
        "teacher_losses": teacher_losses,
        "free_run_losses": free_losses,
        "validation_rms_ratio": history,
        "best_validation_rms_ratio": best_val,
        "validation_after_teacher": val_after_teacher,
        "stopped": stopped,
        "stage_stops": stage_stops,
        "skipped_windows": skipped,
        "seconds": elapsed,
    }
    return model
