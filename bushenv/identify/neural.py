"""Training of the NARX network bushings ("nn", seed 000 §4.2; "hybrid", seed 000 §3).

Torch trains; it never runs per step in use: the result is exported to the numpy parameters of
``NarxBushing`` / ``HybridBushing``, whose numba kernel does the free run. All seeded.

1. Each record is split: the first (1 - ``val_fraction``) trains, the rest validates
   (``narx_data.py``; several records train together, each its own history).
2. Hybrid only: backbone k, c by least squares on the training parts (seed 000 §4.1); the
   network's target is the residual F - k x - c v. Pure NN: the target is F.
3. Displacement and target scaled to [-1, 1] over the training parts (seed 000 §4.2).
4. One-step-ahead (teacher forcing) training: the past forces fed to the net are the measured
   ones. Full-batch Adam.
5. ``recipe="teacher-forcing"`` (the papers' recipe) ends here: the weights with the lowest
   one-step validation error (checked every ``eval_every`` steps, ``patience`` checks without
   improvement stop it) are kept. ``recipe="free-run"`` goes on: windows of the training
   records, the net started from the measured history at the window start and then fed ITS
   OWN outputs for L samples (L grows over ``window_lengths``); loss on every sample; the
   weights with the lowest validation free-run RMS ratio are kept (patience per stage or for
   the whole training, ``early_stop``). Stages whose windows exceed a quarter of the longest
   training part are skipped.

Why step 5's free run: a net trained one step ahead on measured past forces, then run on its
own, can self-oscillate on data like its training data (DESIGN-NOTES). Iteration counts, not
the clock, decide when to stop, so a seed reproduces the weights; ``time_limit_s`` (off by
default) is an explicit wall-time limit, reported and logged (``time_limited``, ``budget_used``)
when it stops the training early. docs/fit.md explains each option and what the recipes give.

Extra loss terms plug in through ``loss_terms`` (objects with ``name``, ``stages`` and
``__call__(net, problem) -> tensor``, added to the data loss of the stages they name);
``weight_decay`` is one (``WeightDecay``), ``certified`` another (``certified.CertifiedHolds``:
held static force and spectral radius over the stroke). A term a flag turns on is a
``NarxOptions`` field (``narx_options.py``) that ``loss_terms_of`` reads; ``problem``
(``narx_data.NarxProblem``) gives it the scaling, the lags, the backbone and the records. A term
with an ``admits(net, problem) -> bool`` method also judges checkpoints: the trainer keeps the
best weights among those every such term admits (any weights if none is admitted), and a
``report(net, problem) -> dict`` goes into the training log.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Protocol

import numpy as np
import torch

from bushenv.identify.data import IdentificationError, TrainingSet
from bushenv.identify.linear import least_squares_kc
from bushenv.identify.narx_choice import choose_and_train
from bushenv.identify.narx_data import NarxProblem, narx_problem
from bushenv.identify.narx_options import NarxOptions
from bushenv.identify.narx_torch import TorchNarx
from bushenv.identify.narx_train import Trainer
from bushenv.metrics import rms_ratio
from bushenv.models.hybrid import HybridBushing
from bushenv.models.narx import NarxBushing
from bushenv.progress import ProgressSpec


class LossTerm(Protocol):
    """An extra training loss: ``term(net, problem)`` is a scalar tensor added to the data loss
    of each stage in ``stages`` ("teacher", "free-run")."""

    name: str
    stages: tuple[str, ...]

    def __call__(self, net: TorchNarx, problem: NarxProblem) -> torch.Tensor: ...


@dataclass(frozen=True)
class WeightDecay:
    """L2 on the hidden-layer weights: keeps units near tanh's linear part."""

    weight: float
    name: ClassVar[str] = "weight_decay"
    stages: ClassVar[tuple[str, ...]] = ("teacher", "free-run")

    def __call__(self, net: TorchNarx, problem: NarxProblem) -> torch.Tensor:
        return self.weight * (torch.sum(net.w1_eff() ** 2) + torch.sum(net.w2**2))


def loss_terms_of(opt: NarxOptions) -> list[LossTerm]:
    """The loss terms the options ask for."""
    terms: list[LossTerm] = [WeightDecay(opt.weight_decay)] if opt.weight_decay else []
    if opt.certified == "on":
        from bushenv.identify.certified import CertifiedHolds

        terms.append(
            CertifiedHolds(
                weight=opt.certified_weight,
                low=opt.certified_low,
                high=opt.certified_high,
                radius=opt.certified_radius,
                stroke_m=opt.certified_stroke_m,
                holds=opt.certified_holds,
            )
        )
    return terms


def fit_nn(
    data: TrainingSet,
    options: NarxOptions,
    seed: int = 0,
    progress: ProgressSpec = True,
    loss_terms: Sequence[LossTerm] = (),
) -> NarxBushing:
    """Identify the pure NARX network (``fit_narx`` with kind "nn")."""
    return fit_narx("nn", data, options, seed, progress, loss_terms)


def fit_hybrid(
    data: TrainingSet,
    options: NarxOptions,
    seed: int = 0,
    progress: ProgressSpec = True,
    loss_terms: Sequence[LossTerm] = (),
) -> HybridBushing:
    """Identify the hybrid: least-squares backbone + NARX residual (``fit_narx``)."""
    return fit_narx("hybrid", data, options, seed, progress, loss_terms)


def fit_narx(
    kind: str,
    data: TrainingSet,
    options: NarxOptions,
    seed: int = 0,
    progress: ProgressSpec = True,
    loss_terms: Sequence[LossTerm] = (),
) -> NarxBushing:
    """Identify a "nn" (NarxBushing) or "hybrid" (HybridBushing) model from ``data``.

    With ``options.choose == "on"`` the network's size and lags are first chosen on the
    validation parts (``narx_choice.py``). The returned model carries a ``training`` dict
    (losses, validation RMS ratios, times, the choice, ``options_used``: the options of the
    network returned) as an attribute; it is not saved in the model file.
    """
    if kind not in ("nn", "hybrid"):
        raise IdentificationError(f"fit_narx: kind must be 'nn' or 'hybrid', got {kind!r}")
    opt = options
    terms = [*loss_terms_of(opt), *loss_terms]
    old_threads = torch.get_num_threads()
    torch.set_num_threads(max(1, int(opt.threads)))
    try:
        if opt.choose == "on":
            trainer, opt, choice = choose_and_train(kind, data, opt, seed, progress, terms, _stages)
        else:
            problem = narx_problem(kind, data, opt.n_past_x, opt.n_past_f, opt.val_fraction)
            torch.manual_seed(seed)
            trainer = Trainer(problem, opt, terms, seed, progress, _stages(problem, opt))
            trainer.run()
            choice = None
    finally:
        torch.set_num_threads(old_threads)
    model = export(trainer.net, trainer.problem)
    model.training = trainer.log
    model.training.update(choice=choice, options_used=opt)
    if kind == "nn":
        model.training.update(linear_check(trainer.problem, float(trainer.keep.val)))
    return model


def linear_check(problem: NarxProblem, nn_val: float) -> dict:
    """The least-squares Kelvin-Voigt model's RMS ratio on the same validation parts, and a
    note when the network does not take at least half of that error away (then the records
    may not excite what the network needs, or its training did not converge)."""
    segs, n = problem.data.segments, [hi - lo for lo, hi in problem.train]
    k, c = least_squares_kc(
        *(np.concatenate([getattr(s, a)[:m] for s, m in zip(segs, n, strict=True)]) for a in "xfv")
    )
    pred = np.concatenate([k * s.x[m:] + c * s.v[m:] for s, m in zip(segs, n, strict=True)])
    lin = rms_ratio(problem.f_val, pred)
    out = {"linear_validation_rms_ratio": lin, "note": None}
    if not nn_val < 0.5 * lin:
        out["note"] = (
            f"the network's validation free-run RMS ratio, {100 * nn_val:.2f} %, is not below "
            f"half the linear model's ({100 * lin:.2f} %) on the same parts: it learned little "
            "beyond a spring and a damper. Try the hybrid, longer or richer records (the range "
            "and frequencies the bushing meets in use), or --choose-networks with larger ones"
        )
    return out


def _stages(problem: NarxProblem, opt: NarxOptions) -> list[tuple[int, int]]:
    """The free-run stages (window length, iterations) the records are long enough for."""
    if opt.recipe == "teacher-forcing":
        return []
    longest = problem.longest_train
    if longest < 4 * min(opt.window_lengths):
        raise IdentificationError(
            f"records too short for windows of {min(opt.window_lengths)} samples: the longest "
            f"training part holds {longest} samples (a {opt.val_fraction:.0%} validation split "
            "kept), windows need a quarter of it; pass shorter --window-lengths"
        )
    return [
        (length, n)
        for length, n in zip(opt.window_lengths, opt.iters_per_length, strict=True)
        if 4 * length <= longest
    ]


def export(net: TorchNarx, problem: NarxProblem) -> NarxBushing:
    """The numpy model of the trained net (weights in the lag basis, float64)."""
    arrays = net.arrays()
    common = dict(
        x_offset_m=problem.x_off,
        x_scale_m=problem.x_sc,
        f_offset_n=problem.f_off,
        f_scale_n=problem.f_sc,
        w1=arrays["w1"],
        b1=arrays["b1"],
        w2=arrays["w2"],
        b2=arrays["b2"],
        w_out=arrays["w_out"],
        b_out=float(arrays["b_out"]),
        n_past_x=problem.n_past_x,
        n_past_f=problem.n_past_f,
        dt=problem.dt,
    )
    if problem.kind == "hybrid":
        return HybridBushing(k_n_per_m=problem.k, c_ns_per_m=problem.c, **common)
    return NarxBushing(**common)
