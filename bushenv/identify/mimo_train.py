"""Training the MIMO networks in torch: teacher forcing, then short free-run fine-tuning.

The network of C outputs the three-axis bushing needs (``bushenv.models.planar_narx``: every
coordinate's displacement and force lags in, every force out) trains here; the one-axis network
(C = 1, ``narx_train.py``) trains by its own longer recipe (a chosen size, staged window
lengths, a difference basis, a compiled unroll), which this one does not share. The recipe
of ``bushenv.identify``'s NARX training, in C coordinates: inputs and outputs
scaled to [-1, 1] over the training records (seed 000 §4.2), full-batch Adam one step ahead on
measured force lags, then Adam on free-run windows (the network fed with its own outputs from a
measured start), keeping the weights with the lowest free-run error on a held-out tail. Torch
only trains; the arrays go to ``planar_narx.PlanarNarx`` whose numpy loop does every run in use.

The hybrid's accurate recipe (``mimo_options.NOISY_FEEDBACK_TRAINING``, ``--training
noisy-feedback``, studies/2026-11-planar-fit-unseen) trains differently one step ahead: mini-batches
instead of the full batch (many more, cheaper Adam steps), Gaussian noise on the fed-back past
outputs, so the network leans on the displacement inputs rather than on its own last output,
and 54 units, 6000 steps at a lower rate. It is 3x as accurate on unseen records and has more
than one fixed point at some holds of its training range, so it is not the default.

``certified="on"`` adds the certified-hold term (``mimo_certified.py``) to both stages' loss,
and the weights kept are the best admitted ones (``MimoCertifiedHolds.admits`` on its fixed grid,
checked at every validation), or the best of all when none was admitted; the returned model's
``training`` attribute says which, with the check of the weights kept. ``structure`` other than
"free" trains a network whose weights are tied by construction (``mimo_structure.py``: mirror-
symmetric, displacement increments, or both).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch

from bushenv.identify.mimo_options import MimoOptions, default_options, record_problem
from bushenv.identify.mimo_structure import (
    StructuredNet,
    fit_diagonal_linear,
    increment_gain,
    is_mirror,
    symmetric_scale,
)
from bushenv.models.base import velocity_of
from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_linear import fit_linear
from bushenv.models.planar_narx import KINDS, N_PAST_F, N_PAST_Q, PlanarNarx, axis_masks
from bushenv.progress import Progress, ProgressSpec

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


def fit_mimo(
    q: np.ndarray | Sequence[np.ndarray],
    f: np.ndarray | Sequence[np.ndarray],
    dt: float,
    kind: str = "nn",
    options: MimoOptions | None = None,
    seed: int = 0,
    progress: ProgressSpec = False,
    may_drop: bool = False,
) -> PlanarNarx:
    """Identify a MIMO network from a record ``q`` (T, 3) m/rad, ``f`` (T, 3) N/N m, or from
    several: equal-length lists of such arrays.

    ``kind``: "nn" (MIMO), "nn-axis" (three single-axis networks) or "hybrid" (3x3 linear
    backbone by least squares, then the MIMO network on the residual). Deterministic given
    ``seed``. Each record is split as in ``bushenv.identify.narx_data``: its first 1 -
    ``val_fraction`` trains, its last ``val_fraction`` selects the weights (free-run error over
    every record's tail), and no lag or free-run window reaches across two records.

    ``may_drop`` (a backbone's network: "hybrid", or a network on another backbone's residual
    ``f``): a network adding exactly zero is a candidate too, kept when its validation error is
    lower (the backbone alone is then the model); ``model.training["network"]`` says which.
    Not with the certified term, whose admission orders the candidates.
    """
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # these nets are tiny: threads only add contention (15 s vs 0.2 s)
    try:
        return _fit(_records(q, f), dt, kind, options, seed, progress, may_drop)
    finally:
        torch.set_num_threads(threads)


def _records(q, f) -> list[tuple[np.ndarray, np.ndarray]]:
    """[(q, f)] as float arrays: one record when given arrays, else the pairs of the lists."""
    single = isinstance(q, np.ndarray) or isinstance(f, np.ndarray)
    qs, fs = ([q], [f]) if single else (list(q), list(f))
    if len(qs) != len(fs) or not qs:
        raise PlanarModelError(
            f"fit_mimo: give one (q, f) pair of arrays or two lists of equal length, "
            f"got {len(qs)} and {len(fs)} records"
        )
    return [(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
            for a, b in zip(qs, fs, strict=True)]  # fmt: skip


def _split(records, opt) -> list[int]:
    """Validation-tail length of each record; refuses records that cannot be split."""
    t0 = max(N_PAST_Q, N_PAST_F)
    tails = []
    for k, (q, f) in enumerate(records):
        label = "the record" if len(records) == 1 else f"record {k + 1}"
        if q.shape != f.shape or q.ndim != 2 or q.shape[1] != 3:
            raise PlanarModelError(
                f"fit_mimo: {label}: q and f must be equal (T, 3) arrays, got "
                f"{q.shape} and {f.shape}"
            )
        problem = record_problem(q.shape[0], opt.val_fraction)
        if problem:
            raise PlanarModelError(f"fit_mimo: {label}: {problem}: give a longer record")
        n_val = int(opt.val_fraction * q.shape[0])
        tails.append(n_val)
    total = sum(q.shape[0] for q, _ in records)
    if total < 20 * opt.window or not any(
        q.shape[0] - n - t0 > opt.window for (q, _), n in zip(records, tails, strict=True)
    ):
        raise PlanarModelError(
            f"fit_mimo: {total} samples in {len(records)} record(s); training needs "
            f"T >= {20 * opt.window} in all and one training part longer than the free-run "
            f"window ({opt.window} samples)"
        )
    return tails


def _gate(model: PlanarNarx, val_error, with_network: float) -> PlanarNarx:
    """``model``, or the same network adding exactly zero when that validates better."""
    params = dict(model.params)
    params["w_out"] = np.zeros_like(params["w_out"])
    params["b_out"] = -np.asarray(params["f_offset"]) / np.asarray(params["f_scale"])
    null = type(model)(**params, **model.extra_meta(), dt=model.dt)
    alone = val_error(null)
    kept = null if alone < with_network else model
    kept.training = {"network": {"dropped": kept is null, "with_network": with_network,
                                 "backbone_alone": alone}}  # fmt: skip
    return kept


def _window_starts(lengths: list[int], window: int) -> np.ndarray:
    """The rows (in the training parts stacked) where a free-run window of ``window`` rows
    starts and stays inside one record's training part of ``lengths`` rows."""
    ends = np.cumsum(lengths)
    return np.concatenate(
        [np.arange(e - n, e - window) for n, e in zip(lengths, ends, strict=True)]
    ).astype(np.int64)


def _fit(records, dt, kind, options, seed, progress, may_drop=False) -> PlanarNarx:
    if kind not in KINDS:
        raise PlanarModelError(f"unknown MIMO network kind {kind!r}; known: {list(KINDS)}")
    opt = options or default_options(kind)
    if opt.structure != "free" and kind == "nn-axis":
        raise PlanarModelError(
            f"structure {opt.structure!r} ties the MIMO network's weights; nn-axis takes "
            "structure 'free' only (use nn or hybrid)"
        )
    tails = _split(records, opt)
    q = np.vstack([r[0] for r in records])  # scales and backbone over every record, as before
    f_total = np.vstack([r[1] for r in records])
    extra, targets = {}, [r[1] for r in records]
    mirror = is_mirror(opt.structure)  # mirror-symmetric: diagonal backbone, scaled about 0
    if kind == "hybrid":
        v = np.vstack([velocity_of(r[0], dt) for r in records])
        lin = fit_diagonal_linear(q, f_total, dt) if mirror else fit_linear(q, v, f_total, dt)
        extra = {"k_matrix": lin.k_matrix, "c_matrix": lin.c_matrix}
        targets = [r[1] - lin.simulate(r[0]) for r in records]
    f = np.vstack(targets)
    q_off, q_sc = symmetric_scale(q) if mirror else _scale(q)
    f_off, f_sc = symmetric_scale(f) if mirror else _scale(f)
    t0 = max(N_PAST_Q, N_PAST_F)
    parts = []  # per record: (displacement inputs, past outputs, targets) of its training part
    for (qr, _), fr, n_val in zip(records, targets, tails, strict=True):
        n = qr.shape[0] - n_val
        qs, ys = (qr[:n] - q_off) / q_sc, (fr[:n] - f_off) / f_sc
        parts.append((np.hstack([qs[t0:], _lags(qs, N_PAST_Q, t0)]), _lags(ys, N_PAST_F, t0),
                      ys[t0:]))  # fmt: skip
    qz_tr, yl_tr, tgt_tr = (np.vstack(a) for a in zip(*parts, strict=True))
    window_starts = _window_starts([len(p[0]) for p in parts], opt.window)
    gen = torch.Generator().manual_seed(seed)
    if opt.structure == "free":
        net = _Net(opt.hidden, kind == "nn-axis", gen)
    else:
        net = StructuredNet(opt.structure, opt.hidden, gen, increment_gain((q - q_off) / q_sc))
    term = opt.certified_term()
    if term is not None:
        from bushenv.identify.mimo_certified import MimoProblem
        from bushenv.identify.static_estimate import static_estimate
        from bushenv.models.planar_base import COORDS

        fitted = [(r[0][: len(r[0]) - n], r[1][: len(r[1]) - n])
                  for r, n in zip(records, tails, strict=True)]  # fmt: skip
        estimate = static_estimate(fitted, dt, COORDS)  # the training parts, total force
        k = extra.get("k_matrix", np.zeros((3, 3)))
        problem = MimoProblem(q_off, q_sc, f_off, f_sc, k, dt, estimate)

    def extra_loss(stage: str) -> torch.Tensor | float:
        return term(net, problem) if term is not None and stage in term.stages else 0.0

    rng = np.random.default_rng(seed)
    progress = Progress.of(
        progress, total=opt.teacher_steps + opt.free_run_steps, label=f"{len(q[0])}-axis {kind}"
    )

    z = torch.tensor(np.hstack([qz_tr, yl_tr]))
    n_q = qz_tr.shape[1]  # z's displacement columns; the fed-back outputs follow
    noise = torch.Generator().manual_seed(seed + 1)
    tgt = torch.tensor(tgt_tr)
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

    def val_error(model: PlanarNarx | None = None) -> float:
        """Sum over the axes of the free-run RMS ratio on every record's tail (total force),
        each tail run from rest."""
        model = model or build()
        pred = np.vstack([model.simulate(r[0][-n:]) for r, n in zip(records, tails, strict=True)])
        return float(np.sum(np.sqrt(np.mean((pred - f_val_total) ** 2, axis=0)) / f_val_rms))

    f_val_total = np.vstack([r[1][-n:] for r, n in zip(records, tails, strict=True)])
    f_val_rms = np.maximum(np.sqrt(np.mean(f_val_total**2, axis=0)), 1e-12)

    def judged() -> tuple[bool, float]:
        """(not admitted, validation error): the order the kept weights win by."""
        admitted = term is None or term.admits(build(), problem.estimate)
        return (not admitted, val_error())

    best, best_state = judged(), {k: v.detach().clone() for k, v in net.state_dict().items()}
    qz_t, yl_t, tgt_t = (torch.tensor(a) for a in (qz_tr, yl_tr, tgt_tr))
    adam = torch.optim.Adam(net.parameters(), lr=opt.free_run_lr)
    L = opt.window
    for it in range(opt.free_run_steps):
        starts = window_starts[rng.integers(0, len(window_starts), size=opt.windows)]
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
    if may_drop and term is None:
        model = _gate(model, val_error, best[1])
    if term is not None:
        model.training = {
            "certified": term.check(model, problem.estimate),
            "static_estimate": problem.estimate.as_dict(),
        }
        if may_drop:  # admission ordered the weights: the network is kept, and the card says so
            model.training["network"] = {"dropped": False, "gated": False}
    return model
