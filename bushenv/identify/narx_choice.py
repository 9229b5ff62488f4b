"""The NARX network's size and lags chosen on the validation parts of the user's own records.

With ``choose="on"`` (the NN's default) every candidate of ``choose_networks`` (tanh units of
one layer x lags, n_past_x = n_past_f) first trains with
``choose_share`` of the iteration counts (teacher steps and every window stage), on the same
training parts and seed as the full training; it is scored by its best free-run RMS ratio on
the validation parts (the last ``val_fraction`` of each record, never trained on). The
candidate with the lowest score then trains in full. Iteration counts only: the choice is as
deterministic as one training. Why: the defaults tuned on the reference rubber (9 units, 5
lags) underfit bushings of another stiffness, memory or sample rate (docs/fit.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import torch

from bushenv.identify.data import IdentificationError, TrainingSet
from bushenv.identify.narx_data import NarxProblem, narx_problem
from bushenv.identify.narx_options import NarxOptions
from bushenv.identify.narx_train import Trainer, training_work
from bushenv.progress import Progress, ProgressSpec


@dataclass
class Candidate:
    """One network of the grid: its options, its problem (lags decide the padding), and the
    screening's score once trained."""

    options: NarxOptions
    problem: NarxProblem
    score: float = math.inf
    seconds: float = 0.0

    @property
    def name(self) -> str:
        o = self.options
        return f"{','.join(map(str, o.hidden))} units, lags {o.n_past_x}"


def candidates(kind: str, data: TrainingSet, opt: NarxOptions) -> list[Candidate]:
    """Every grid point the records are long enough for (refused only if none is)."""
    out, refused = [], []
    for hidden, lag in opt.networks():
        o = replace(opt, hidden=(hidden,), n_past_x=lag, n_past_f=lag, choose="off")
        try:
            out.append(Candidate(o, narx_problem(kind, data, lag, lag, opt.val_fraction)))
        except IdentificationError as exc:
            refused.append(exc)
    if not out:
        raise refused[0]
    return out


def screening(opt: NarxOptions) -> NarxOptions:
    """The options of a candidate's short training: ``choose_share`` of every iteration count."""
    share = opt.choose_share
    return replace(
        opt,
        teacher_steps=math.ceil(share * opt.teacher_steps),
        iters_per_length=tuple(math.ceil(share * n) for n in opt.iters_per_length),
    )


def choose_and_train(
    kind: str,
    data: TrainingSet,
    opt: NarxOptions,
    seed: int,
    progress: ProgressSpec,
    terms: list,
    stages_of: Any,
) -> tuple[Trainer, NarxOptions, dict[str, Any]]:
    """Screen every candidate, train the best in full; (its trainer, its options, the choice
    log). ``stages_of(problem, options)`` gives a training's window stages."""
    grid = candidates(kind, data, opt)
    work = sum(_work(c.problem, screening(c.options), stages_of) for c in grid)
    work += max(_work(c.problem, c.options, stages_of) for c in grid)
    prog = Progress.of(
        progress,
        total=work,
        label=kind,
        every_s=opt.progress_every_s,
        budget_s=opt.time_limit_s or None,
        upper_bound=True,
    )
    prog.say(
        f"choosing the network on the validation parts: {len(grid)} candidates "
        f"({'; '.join(c.name for c in grid)}), {opt.choose_share:.0%} of the iterations each"
    )
    best, best_trainer = None, None
    for c in grid:
        short = screening(c.options)
        t0 = prog.elapsed_s()
        trainer = _train(c.problem, short, terms, seed, prog, stages_of, f"{c.name}: ")
        c.score, c.seconds = float(trainer.keep.val), prog.elapsed_s() - t0
        if best is None or c.score < best.score:
            best, best_trainer = c, trainer
        if trainer.time_limited:
            break
    log = {
        "share": opt.choose_share,
        "candidates": [
            {
                "hidden": list(c.options.hidden),
                "n_past_x": c.options.n_past_x,
                "n_past_f": c.options.n_past_f,
                "validation_rms_ratio": c.score,
                "seconds": c.seconds,
            }
            for c in grid
        ],
        "summary": f"{best.name} (validation free-run RMS ratio {100 * best.score:.2f} % after "
        f"{opt.choose_share:.0%} of the iterations; "
        + ", ".join(f"{c.name} {100 * c.score:.2f} %" for c in grid if math.isfinite(c.score))
        + ")",
    }
    chosen = replace(best.options, choose="on")
    if best_trainer.time_limited:  # no time for the full training: the best screened net
        log["summary"] += "; no full training (time limit)"
        return best_trainer, chosen, log
    prog.say(f"chosen: {best.name}; training it in full")
    trainer = _train(best.problem, best.options, terms, seed, prog, stages_of, f"{best.name}: ")
    return trainer, chosen, log


def _work(problem: NarxProblem, opt: NarxOptions, stages_of: Any) -> float:
    return training_work(problem, opt, stages_of(problem, opt))


def _train(
    problem: NarxProblem,
    opt: NarxOptions,
    terms: list,
    seed: int,
    prog: Progress,
    stages_of: Any,
    tag: str,
) -> Trainer:
    torch.manual_seed(seed)
    trainer = Trainer(problem, opt, terms, seed, prog, stages_of(problem, opt))
    trainer.tag = tag
    trainer.run()
    return trainer
