"""The NARX training loop: one step ahead, then (recipe "free-run") free-run fine-tuning.

``Trainer(problem, options, loss_terms, seed, progress, stages).run()`` trains a ``TorchNarx``
in place and returns the training log; ``neural.py`` describes the procedure and the options.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from bushenv.identify.narx_data import NarxProblem
from bushenv.identify.narx_torch import TorchNarx, difference_basis
from bushenv.identify.options import as_dict
from bushenv.metrics import rms_ratio
from bushenv.progress import Progress, ProgressSpec


def sample_cost(opt: Any) -> float:
    """Relative cost of one sample through the net (multiply-adds plus a fixed overhead)."""
    inputs = 1 + opt.n_past_x + opt.n_past_f
    h = opt.hidden
    return (inputs * h[0] + (h[0] * h[1] if len(h) > 1 else 0) + 100) / 200.0


def training_work(problem: NarxProblem, opt: Any, stages: list[tuple[int, int]]) -> float:
    """Units of work of one training (samples through the net, weighted by ``sample_cost``):
    the progress lines' total."""
    work = opt.teacher_steps * problem.n_train
    work += sum(n * opt.batch_windows * length for length, n in stages)
    return work * sample_cost(opt)


class Keeper:
    """The weights a training keeps: admitted ones (every loss term with ``admits`` admits
    them) beat any others, then the lower validation error wins. Patience is a separate
    matter: ``offer`` says whether the error improved on the lowest seen, admitted or not, so
    a stage is not ended early only because its weights are not admitted yet."""

    def __init__(self, trainer: Trainer) -> None:
        self.trainer = trainer
        self.judged = any(hasattr(t, "admits") for t in trainer.terms)
        self.val, self.ok, self.state, self.lowest = np.inf, False, trainer.state(), np.inf

    def offer(self, val: float) -> bool:
        """Keep the current weights if they are better; True when ``val`` is the lowest yet."""
        if not self.judged:
            ok, better = True, val < self.val
        elif self.ok and not val < self.val:
            ok, better = False, False  # cannot win: admission not checked
        else:
            ok = self.trainer.admitted()
            better = (not ok, val) < (not self.ok, self.val)
        if better:
            self.val, self.ok, self.state = val, ok, self.trainer.state()
        progress = val < self.lowest
        self.lowest = min(self.lowest, val)
        return progress


class Trainer:
    """State of one NARX training: the net, its optimiser stages, the best weights so far."""

    def __init__(
        self,
        problem: NarxProblem,
        opt: Any,
        loss_terms: list,
        seed: int,
        progress: ProgressSpec,
        stages: list[tuple[int, int]],
    ) -> None:
        self.problem, self.opt, self.terms, self.stages = problem, opt, loss_terms, stages
        # a Progress given is shared with other trainings (the network choice): its work and
        # clock go on from where they are
        self.shared = isinstance(progress, Progress)
        self.tag = ""
        if isinstance(progress, Progress):
            self.progress = progress
        else:
            self.progress = Progress.of(
                progress,
                total=training_work(problem, opt, stages),
                label=problem.kind,
                every_s=opt.progress_every_s,
                budget_s=opt.time_limit_s or None,
                upper_bound=True,
            )
        self.work, self.unit = self.progress.done, sample_cost(opt)
        self.t0 = self.progress.elapsed_s()  # this training's start on a shared clock
        self.teacher_done = self.it = 0
        self.time_limited = False
        self.rng = np.random.default_rng(seed)
        nx, nf = problem.n_past_x, problem.n_past_f
        basis = None
        if opt.basis() == "differences":
            parts = problem.train
            basis = difference_basis(
                nx,
                nf,
                [problem.xs_p[lo:hi] for lo, hi in parts],
                [problem.ys_p[lo:hi] for lo, hi in parts],
            )
        self.net = TorchNarx(1 + nx + nf, opt.hidden, basis)
        self.val_runs = problem.validation_runs()
        self.adam, self.sched = self._free_run_optimiser()
        self.stale = 0  # free-run evaluations since the validation error last improved
        # the weights kept (renewed after teacher forcing) and the free-run validation history
        self.keep = Keeper(self)
        self.history: list[tuple[int, float]] = []
        self.log: dict[str, Any] = {
            "options": as_dict(opt),
            "recipe": opt.recipe,
            "input_basis": opt.basis(),
            "records": problem.data.labels,
            "teacher_losses": [],
            "free_run_losses": [],
            "stage_stops": [],
            "skipped_windows": [
                n
                for n in opt.window_lengths
                if opt.recipe == "free-run" and 4 * n > problem.longest_train
            ],
        }

    # ----- pieces ----------------------------------------------------------------------------
    def say(self, msg: str, force: bool = False) -> None:
        self.progress.update(self.work, self.tag + msg, force)

    def total_loss(self, loss: torch.Tensor, stage: str) -> torch.Tensor:
        """The data loss plus every loss term that applies to ``stage``."""
        for term in self.terms:
            if stage in term.stages:
                loss = loss + term(self.net, self.problem)
        return loss

    def admitted(self) -> bool:
        """Whether every term that judges weights (``admits``) admits the current ones."""
        return all(t.admits(self.net, self.problem) for t in self.terms if hasattr(t, "admits"))

    def out_of_time(self) -> bool:
        """True once an explicit ``time_limit_s`` has passed (then the log says where)."""
        limit = self.opt.time_limit_s
        if self.time_limited or not limit or self.progress.elapsed_s() <= limit:
            return self.time_limited
        self.time_limited = True
        where = (
            f"free-run iteration {self.it} of {sum(n for _, n in self.stages)}"
            if self.it
            else f"teacher step {self.teacher_done} of {self.opt.teacher_steps}"
        )
        self.log["stopped"] = f"time limit {limit:g} s hit at {where}"
        self.say(f"stopped early: {self.log['stopped']}", True)
        return True

    def state(self) -> dict[str, torch.Tensor]:
        return {k: t.detach().clone() for k, t in self.net.state_dict().items()}

    def validate_free_run(self) -> float:
        """RMS ratio of the free run over every validation part (from its measured history)."""
        p = self.problem
        with torch.no_grad():
            ys = np.concatenate(
                [
                    self.net.unroll(x_in, y_hist, p.n_past_x, self.opt.engine)[0].numpy()
                    for x_in, y_hist in self.val_runs
                ]
            )
        pred = p.backbone_val + p.f_off + p.f_sc * ys
        if not np.all(np.isfinite(pred)):
            return float("inf")
        return rms_ratio(p.f_val, pred)

    # ----- stage 1: one step ahead -------------------------------------------------------------
    def teacher(self) -> None:
        """Full-batch Adam one step ahead; recipe "teacher-forcing" keeps the weights with the
        lowest one-step validation error."""
        opt, p = self.opt, self.problem
        inp, tgt = p.one_step_batch(p.train)
        select = opt.recipe == "teacher-forcing"
        v_inp, v_tgt = p.one_step_batch(p.val) if select else (None, None)
        keep, stale, history = Keeper(self), 0, []
        adam = torch.optim.Adam(self.net.parameters(), lr=opt.teacher_lr)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(adam, max(1, opt.teacher_steps))
        for i in range(opt.teacher_steps):
            adam.zero_grad()
            loss = torch.mean((self.net(inp) - tgt) ** 2)
            self.total_loss(loss, "teacher").backward()
            adam.step()
            sched.step()
            self.log["teacher_losses"].append(loss.item())
            self.teacher_done = i + 1
            self.work += self.unit * p.n_train
            self.say(f"teacher step {i + 1}/{opt.teacher_steps}: one-step MSE {loss.item():.3e}")
            if self.out_of_time():
                break
            if not select or ((i + 1) % opt.eval_every and i + 1 < opt.teacher_steps):
                continue
            with torch.no_grad():
                val = torch.mean((self.net(v_inp) - v_tgt) ** 2).item()
            history.append((i + 1, val))
            stale = 0 if keep.offer(val) else stale + 1
            if stale >= opt.patience:
                self.say(f"one-step validation: patience {opt.patience} ran out at {i + 1}", True)
                break
        if select:
            self.net.load_state_dict(keep.state)
            self.log["teacher_validation_mse"] = history
            self.log["best_teacher_validation_mse"] = float(keep.val)

    # ----- stage 2: free-run fine-tuning -------------------------------------------------------
    def _free_run_optimiser(self):
        """Adam and its cosine schedule over every free-run iteration (nothing is stepped
        before ``free_run``, so building them with the net changes no number)."""
        opt = self.opt
        adam = torch.optim.Adam(self.net.parameters(), lr=opt.free_run_lr)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(
            adam,
            max(1, sum(n for _, n in self.stages)),
            eta_min=opt.free_run_lr * opt.free_run_lr_final,
        )
        return adam, sched

    def free_run(self) -> None:
        self.it, self.stale, self.log["stopped"] = 0, 0, "iterations done"
        if self.log["skipped_windows"]:
            longest = self.problem.longest_train
            self.say(
                f"windows {self.log['skipped_windows']} skipped: longer than a quarter of "
                f"{longest} samples",
                True,
            )
        for length, n_iter in self.stages:
            if self._stage(length, n_iter):
                break

    def _stage(self, length: int, n_iter: int) -> bool:
        """One window length; True when the whole training must stop."""
        opt = self.opt
        if opt.early_stop == "stage":
            self.stale = 0
        starts = self.problem.window_starts(length)
        for _ in range(n_iter):
            self.it += 1
            loss = self._window_step(starts, length)
            if self.it % opt.eval_every == 0:
                self._evaluate(length, loss)
                if self.stale >= opt.patience and opt.early_stop == "stage":
                    self.log["stage_stops"].append((length, self.it))
                    self.say(f"window {length}: patience {opt.patience} ran out at {self.it}", True)
                    return False
                if self.stale >= opt.patience:
                    self.log["stopped"] = (
                        f"early stop at iteration {self.it} (patience {opt.patience})"
                    )
                    return True
            if self.out_of_time():
                return True
        return False

    def _window_step(self, starts: np.ndarray, length: int) -> float:
        opt, p = self.opt, self.problem
        s = starts[self.rng.integers(0, starts.size, size=opt.batch_windows)]
        x_in, y_hist, tgt = p.windows(s, length)
        self.adam.zero_grad()
        loss = torch.mean((self.net.unroll(x_in, y_hist, p.n_past_x, opt.engine) - tgt) ** 2)
        self.total_loss(loss, "free-run").backward()
        torch.nn.utils.clip_grad_norm_(self.net.parameters(), opt.grad_clip)
        self.adam.step()
        self.sched.step()
        self.log["free_run_losses"].append(loss.item())
        self.work += self.unit * opt.batch_windows * length
        return loss.item()

    def _evaluate(self, length: int, loss: float) -> None:
        val = self.validate_free_run()
        self.history.append((self.it, val))
        self.stale = 0 if self.keep.offer(val) else self.stale + 1
        self.say(
            f"free-run iter {self.it} (window {length}): loss {loss:.3e}, "
            f"validation RMS ratio {val:.4f} (kept {self.keep.val:.4f})"
        )

    # ----- the whole training ------------------------------------------------------------------
    def run(self) -> dict[str, Any]:
        """Train; the net ends with the kept weights. Returns the training log."""
        self.teacher()
        val = self.validate_free_run()
        self.say(
            f"teacher forcing done: one-step MSE {self.log['teacher_losses'][-1]:.3e} (scaled), "
            f"validation free-run RMS ratio {val:.4f}"
            if self.log["teacher_losses"]
            else f"validation free-run RMS ratio {val:.4f} before free-run training",
            force=True,
        )
        self.keep, self.history = Keeper(self), [(0, val)]
        self.keep.offer(val)
        if not self.time_limited:
            self.log["stopped"] = "one step ahead only (teacher-forcing recipe)"
        if self.opt.recipe == "free-run" and not self.time_limited:
            self.free_run()
            self.net.load_state_dict(self.keep.state)
        elapsed = self.progress.elapsed_s() - self.t0
        if not self.shared:
            self.work = self.progress.total
        self.say(
            f"done in {elapsed:.1f} s ({self.log['stopped']}); best validation free-run RMS "
            f"ratio {self.keep.val:.4f}",
            force=True,
        )
        with torch.no_grad():
            terms = {t.name: float(t(self.net, self.problem)) for t in self.terms}
        self.log["term_reports"] = {
            t.name: t.report(self.net, self.problem) for t in self.terms if hasattr(t, "report")
        }
        self.log.update(
            kept_weights_admitted=self.admitted(),
            validation_rms_ratio=self.history,
            best_validation_rms_ratio=self.keep.val,
            validation_after_teacher=val,
            loss_terms=terms,
            seconds=elapsed,
            time_limited=self.time_limited,
            budget_used={
                "teacher_steps": self.teacher_done,
                "teacher_steps_planned": self.opt.teacher_steps,
                "free_run_iterations": self.it,
                "free_run_iterations_planned": sum(n for _, n in self.stages),
            },
        )
        return self.log
