"""Training the planar networks in torch: teacher forcing, then short free-run fine-tuning.

The recipe of ``bushenv.identify``'s NARX training, in three coordinates: inputs and outputs
scaled to [-1, 1] over the training records (seed 000 §4.2), full-batch Adam one step ahead on
measured force lags, then Adam on free-run windows (the network fed with its own outputs from a
measured start), keeping the weights with the lowest free-run error on a held-out tail. Torch
only trains; the arrays go to ``narx.PlanarNarx`` whose numpy loop does every run in use.

The hybrid's accurate recipe (``train_options.NOISY_FEEDBACK_TRAINING``, ``--training
noisy-feedback``, docs/planar_fit_unseen.md) trains differently one step ahead: mini-batches
instead of the full batch (many more, cheaper Adam steps), Gaussian noise on the fed-back past
outputs, so the network leans on the displacement inputs rather than on its own last output,
and 54 units, 6000 steps at a lower rate. It is 3x as accurate on unseen records and has more
than one fixed point at some holds of its training range, so it is not the default.

``certified="on"`` adds the certified-hold term (``certified.py``) to both stages' loss, and the
weights kept are the best admitted ones (``PlanarCertifiedHolds.admits`` on its fixed grid,
checked at every validation), or the best of all when none was admitted; the returned model's
``training`` attribute says which, with the check of the weights kept. ``structure`` other than
"free" trains a network whose weights are tied by construction (``structure.py``: mirror-
symmetric, displacement increments, or both).
"""

from __future__ import annotations

import numpy as np
import torch

from bushenv.models.base import velocity_of
from bushenv.planar.base import PlanarModelError
from bushenv.planar.linear import fit_linear
from bushenv.planar.narx import KINDS, N_PAST_F, N_PAST_Q, PlanarNarx, axis_masks
from bushenv.planar.structure import (
    StructuredNet,
    fit_diagonal_linear,
    increment_gain,
    is_mirror,
    symmetric_scale,
)
from bushenv.planar.train_options import PlanarNetworkOptions as TrainOptions
from bushenv.planar.train_options import default_options
from bushenv.progress import Progress

TEACHER_CHECK_EVERY = 50  # certified: teacher steps between two checks (they pick hard holds)


def _lags(a: np.ndarray, n: int, t0: int) -> np.ndarray:
    """(T - t0, 3 n): a[t-1], ..., a[t-n] for t = t0 .. T-1, lag by lag."""
    return np.hstack([a[t0 - k : a.shape[0] - k] for k in range(1, n + 1)])


class _Net(torch.nn.Module):
    def __init__(self, hidden: int, per_axis: bool, gen: torch.Generator) -> None:
        super().__init__()
        n_in = 3 * (N_PAST_Q + 1 + N_PAST_F)
        bound = 1.0 / np.sqrt(n_in)
        self.w1 = torch.nn.Parameter(
            (torch.rand(hidden, n_in, generator=gen, dtype=torch.float64) * 2 - 1) * bound
        )
        self.b1 = torch.nn.Parameter(torch.zeros(hidden, dtype=torch.float64))
        self.w_out = torch.nn.Parameter(
            (torch.rand(3, hidden, generator=gen, dtype=torch.float64) * 2 - 1) / np.sqrt(hidden)
        )
        self.b_out = torch.nn.Parameter(torch.zeros(3, dtype=torch.float64))
        m1, mo = axis_masks(hidden) if per_axis else (np.ones((hidden, n_in)), np.ones((3, hidden)))
        self.m1 = torch.tensor(m1)
        self.mo = torch.tensor(mo)

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        h = torch.tanh(z @ (self.w1 * self.m1).T + self.b1)
        return h @ (self.w_out * self.mo).T + self.b_out

    def unroll(self, qz: torch.Tensor, y0: torch.Tensor) -> torch.Tensor:
        """Free run: qz (W, L, 3 (N_PAST_Q + 1)) measured displacement inputs, y0 (W, 3 N_PAST_F)
        measured past outputs -> (W, L, 3) own outputs."""
        ys, hist = [], y0
        for j in range(qz.shape[1]):
            y = self.forward(torch.cat([qz[:, j], hist], dim=1))
            ys.append(y)
            hist = torch.cat([y, hist[:, :-3]], dim=1)
        return torch.stack(ys, dim=1)

    def arrays(self) -> dict[str, np.ndarray]:
        with torch.no_grad():
            return {
                "w1": (self.w1 * self.m1).numpy().copy(),
                "b1": self.b1.numpy().copy(),
                "w_out": (self.w_out * self.mo).numpy().copy(),
                "b_out": self.b_out.numpy().copy(),
            }


def _scale(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    lo, hi = a.min(axis=0), a.max(axis=0)
    return 0.5 * (hi + lo), np.maximum(0.5 * (hi - lo), 1e-12)


def fit_planar_network(
    q: np.ndarray,
    f: np.ndarray,
    dt: float,
    kind: str = "nn",
    options: TrainOptions | None = None,
    seed: int = 0,
    quiet: bool = True,
) -> PlanarNarx:
    """Identify a planar network from one record ``q`` (T, 3) m/rad, ``f`` (T, 3) N/N m.

    ``kind``: "nn" (MIMO), "nn-axis" (three single-axis networks) or "hybrid" (3x3 linear
    backbone by least squares, then the MIMO network on the residual). Deterministic given
    ``seed``. The last ``val_fraction`` of the record selects the weights (free-run error).
    """
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # these nets are tiny: threads only add contention (15 s vs 0.2 s)
    try:
        return _fit(q, f, dt, kind, options, seed, quiet)
    finally:
        torch.set_num_threads(threads)


def _fit(q, f, dt, kind, options, seed, quiet) -> PlanarNarx:
    if kind not in KINDS:
        raise PlanarModelError(f"unknown planar network kind {kind!r}; known: {list(KINDS)}")
    opt = options or default_options(kind)
    if opt.structure != "free" and kind == "nn-axis":
        raise PlanarModelError(
            f"structure {opt.structure!r} ties the MIMO network's weights; nn-axis takes "
            "structure 'free' only (use nn or hybrid)"
        )
    q = np.asarray(q, dtype=np.float64)
    f = np.asarray(f, dtype=np.float64)
    if q.shape != f.shape or q.ndim != 2 or q.shape[1] != 3 or q.shape[0] < 20 * opt.window:
        raise PlanarModelError(
            f"fit_planar_network: q and f must be equal (T, 3) arrays with T >= {20 * opt.window}, "
            f"got {q.shape} and {f.shape}"
        )
    extra, f_total = {}, f
    mirror = is_mirror(opt.structure)  # mirror-symmetric: diagonal backbone, scaled about 0
    if kind == "hybrid":
        lin = fit_diagonal_linear(q, f, dt) if mirror else fit_linear(q, velocity_of(q, dt), f, dt)
        extra = {"k_matrix": lin.k_matrix, "c_matrix": lin.c_matrix}
        f = f - lin.simulate(q)
    q_off, q_sc = symmetric_scale(q) if mirror else _scale(q)
    f_off, f_sc = symmetric_scale(f) if mirror else _scale(f)
    qs, ys = (q - q_off) / q_sc, (f - f_off) / f_sc
    n_val = int(opt.val_fraction * q.shape[0])
    t0 = max(N_PAST_Q, N_PAST_F)
    qz_all = np.hstack([qs[t0:], _lags(qs, N_PAST_Q, t0)])  # (T - t0, 18)
    yl_all = _lags(ys, N_PAST_F, t0)  # (T - t0, 15)
    tgt_all = ys[t0:]
    n_tr = qz_all.shape[0] - n_val
    gen = torch.Generator().manual_seed(seed)
    if opt.structure == "free":
        net = _Net(opt.hidden, kind == "nn-axis", gen)
    else:
        net = StructuredNet(opt.structure, opt.hidden, gen, increment_gain(qs))
    term = opt.certified_term()
    if term is not None:
        from bushenv.planar.certified import PlanarProblem
        from bushenv.planar.static_estimate import planar_static_estimate

        n_fit = q.shape[0] - n_val  # the static estimate from the training part, total force
        estimate = planar_static_estimate([(q[:n_fit], f_total[:n_fit])], dt)
        k = extra.get("k_matrix", np.zeros((3, 3)))
        problem = PlanarProblem(q_off, q_sc, f_off, f_sc, k, dt, estimate)

    def extra_loss(stage: str) -> torch.Tensor | float:
        return term(net, problem) if term is not None and stage in term.stages else 0.0

    rng = np.random.default_rng(seed)
    progress = Progress(opt.teacher_steps + opt.free_run_steps, quiet=quiet, label=f"planar {kind}")

    z = torch.tensor(np.hstack([qz_all[:n_tr], yl_all[:n_tr]]))
    n_q = qz_all.shape[1]  # z's displacement columns; the fed-back outputs follow
    noise = torch.Generator().manual_seed(seed + 1)
    tgt = torch.tensor(tgt_all[:n_tr])
    adam = torch.optim.Adam(net.parameters(), lr=opt.teacher_lr)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(adam, opt.teacher_steps)

    def build() -> PlanarNarx:
        return KINDS[kind](
            q_offset=q_off,
            q_scale=q_sc,
            f_offset=f_off,
            f_scale=f_sc,
            dt=dt,
            **net.arrays(),
            **extra,
        )

    for i in range(opt.teacher_steps):
        zi, ti = z, tgt
        if opt.teacher_batch:
            pick = torch.from_numpy(rng.integers(0, z.shape[0], size=opt.teacher_batch))
            zi, ti = z[pick], tgt[pick]
        if opt.feedback_noise > 0:
            shape = (zi.shape[0], zi.shape[1] - n_q)
            jolt = opt.feedback_noise * torch.randn(shape, generator=noise, dtype=torch.float64)
            zi = torch.cat([zi[:, :n_q], zi[:, n_q:] + jolt], dim=1)
        adam.zero_grad()
        loss = torch.mean((net(zi) - ti) ** 2)
        (loss + extra_loss("teacher")).backward()
        adam.step()
        sched.step()
        progress.update(i + 1, f"teacher forcing, one-step MSE {loss.item():.3e}")
        if term is not None and (i + 1) % TEACHER_CHECK_EVERY == 0:
            term.check(build(), problem.estimate)  # the grid's failing holds join the term

    def val_error() -> float:
        """Sum over the axes of the free-run RMS ratio on the held-out tail (total force)."""
        pred = build().simulate(q_val)
        return float(np.sum(np.sqrt(np.mean((pred - f_val_total) ** 2, axis=0)) / f_val_rms))

    q_val, f_val_total = q[-n_val:], f_total[-n_val:]
    f_val_rms = np.maximum(np.sqrt(np.mean(f_val_total**2, axis=0)), 1e-12)

    def judged() -> tuple[bool, float]:
        """(not admitted, validation error): the order the kept weights win by."""
        admitted = term is None or term.admits(build(), problem.estimate)
        return (not admitted, val_error())

    best, best_state = judged(), {k: v.detach().clone() for k, v in net.state_dict().items()}
    qz_t, yl_t, tgt_t = (torch.tensor(a[:n_tr]) for a in (qz_all, yl_all, tgt_all))
    adam = torch.optim.Adam(net.parameters(), lr=opt.free_run_lr)
    L = opt.window
    for it in range(opt.free_run_steps):
        starts = rng.integers(0, n_tr - L, size=opt.windows)
        idx = torch.tensor(starts[:, None] + np.arange(L)[None, :])
        adam.zero_grad()
        pred = net.unroll(qz_t[idx], yl_t[torch.tensor(starts)])
        loss = torch.mean((pred - tgt_t[idx]) ** 2)
        (loss + extra_loss("free-run")).backward()
        adam.step()
        progress.update(opt.teacher_steps + it + 1, f"free run, best validation {best[1]:.4f}")
        if (it + 1) % opt.eval_every == 0 or it + 1 == opt.free_run_steps:
            err = judged()
            if err < best:
                best, best_state = err, {k: v.detach().clone() for k, v in net.state_dict().items()}
    net.load_state_dict(best_state)
    progress.update(None, f"done, validation sum of RMS ratios {best[1]:.4f}", force=True)
    model = build()
    if term is not None:
        model.training = {
            "certified": term.check(model, problem.estimate),
            "static_estimate": problem.estimate.as_dict(),
        }
    return model
