"""Judging the candidates: what one diagnosis shares (``Run``: records, folds, the null's
numbers, a row per candidate), every single effect and pair judged and named by the rule
(``judge_all``), and the held-out mode's hint that the TESTs show what TRAIN does not."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from bushenv.diagnose import evidence, naming, rule
from bushenv.diagnose.candidates import candidate_sets, get_effect
from bushenv.diagnose.design import ColumnStore, Prepared
from bushenv.diagnose.effects.base import NULL
from bushenv.diagnose.fitting import Fold, Judged, best_shapes, describe_shapes, judge, predict
from bushenv.diagnose.inputs import Progress
from bushenv.metrics import rms_ratio


class Run:
    """What every step of one diagnosis shares: records, folds, the null's numbers."""

    def __init__(self, store: ColumnStore, folds: list[Fold], linear_base: bool) -> None:
        self.store = store
        self.folds = folds
        self.linear_base = linear_base
        self.judged = [p for f in folds for p in f.judged]
        self.force = np.concatenate([p.force for p in self.judged])
        self.n_fit = int(np.mean([sum(p.n for p in f.fit) for f in folds]))
        self.null = judge(store, NULL, folds, linear_base)
        self.base_pred = {
            p.uid: (self.null.predictions[p.uid] if linear_base else p.b0) for p in self.judged
        }
        self.gap_before = rms_ratio(self.force, self.stack(self.base_pred))
        self.gap_null = rms_ratio(self.force, self.stack(self.null.predictions))
        self.edges = evidence.block_edges([p.n for p in self.judged], [p.dt for p in self.judged])
        self.gap_noise = self.noise_gap(self.stack(self.null.predictions))

    def noise_gap(self, pred: np.ndarray) -> float:
        """The force's measurement noise as a gap, read from the residual of ``pred``."""
        res = np.split(self.force - pred, np.cumsum([p.n for p in self.judged])[:-1])
        xs = [p.signals.x for p in self.judged]
        noise = evidence.noise_variance(res, xs, [p.dt for p in self.judged])
        return float(np.sqrt(noise / np.mean(self.force**2)))

    def stack(self, preds: dict[int, np.ndarray]) -> np.ndarray:
        return np.concatenate([preds[p.uid] for p in self.judged])

    def row_of(self, combo) -> dict[str, Any]:
        """The row of ``combo`` judged on this run's folds."""
        return self.row(judge(self.store, combo, self.folds, self.linear_base))

    def row(self, j: Judged) -> dict[str, Any]:
        pred = self.stack(j.predictions)
        gap = rms_ratio(self.force, pred)
        return {
            "effect": j.combo.name,
            "members": list(j.combo.names),
            "gap_before": self.gap_before,
            "gap_after": gap,
            "shrink": 1.0 - gap / self.gap_before if self.gap_before > 0 else 0.0,
            "shrink_vs_null": 1.0 - gap / self.gap_null if self.gap_null > 0 else 0.0,
            "n_extra_parameters": j.n_extra,
            "_dissipative": any(get_effect(n).shows_dissipation for n in j.combo.names),
            "_holds_law": any(get_effect(n).holds_its_law for n in j.combo.names),
            "shape": describe_shapes(j.fits[0]),
            "gap_train": j.gap_train,
            "_mse": j.mse,
            "_pred": pred,
            "_judged": j,
        }


def judge_all(run: Run, effects, say: Progress, ctx: rule.Context) -> tuple[list, list]:
    """Rows of every single effect and every pair, ranked best first (rule applied)."""
    sets = candidate_sets(effects)
    rows = []
    start = time.monotonic()
    for i, combo in enumerate(sets):
        elapsed = time.monotonic() - start
        left = f" (about {elapsed / i * (len(sets) - i):.0f} s left)" if i else ""
        say(f"which: candidate {i + 1}/{len(sets)} {combo.name}{left}")
        rows.append(run.row_of(combo))
    singles = [r for r in rows if len(r["members"]) == 1]
    pairs = [r for r in rows if len(r["members"]) == 2]
    rule.mark_failed(rows, ctx)
    best = min(rows, key=lambda r: r["gap_after"])
    if best["gap_after"] < run.gap_null:  # the noise is what not even the best model explains
        ctx.gap_noise = min(ctx.gap_noise, run.noise_gap(best["_pred"]))
        run.gap_noise = ctx.gap_noise
    say("which: the rule, each partner beside the other's richest form")
    return naming.apply_rule(singles, pairs, ctx, run.row_of)


def test_only_hint(run: Run, te: list[Prepared], singles: list[dict]) -> list[dict]:
    """Fitted on the TESTs themselves, does some effect close far more than held out?"""
    force = np.concatenate([p.force for p in te])
    null = best_shapes(run.store, NULL, tuple(te), run.linear_base)
    gap0 = rms_ratio(force, np.concatenate([predict(run.store, null, p) for p in te]))
    held = {r["effect"]: r["shrink_vs_null"] for r in singles}
    out: list[dict] = []
    if max(held.values()) >= 0.3:  # TRAIN already explains a good part: no hint
        return out
    for r in singles:
        combo = r["_judged"].combo
        f = best_shapes(run.store, combo, tuple(te), run.linear_base)
        gap = rms_ratio(force, np.concatenate([predict(run.store, f, p) for p in te]))
        inside = 1.0 - gap / gap0 if gap0 > 0 else 0.0
        if inside >= 0.5 and inside - held[r["effect"]] >= 0.3:
            out.append(
                {
                    "test": "all",
                    "regime": "test_only_behaviour",
                    "text": f"Fitted on the TESTs themselves, {r['effect']} would close "
                    f"{100 * inside:.0f} % of their gap, against {100 * held[r['effect']]:.0f} % "
                    "when fitted on TRAIN: the TESTs show behaviour the identification records "
                    "do not excite (--cross fits on them too).",
                }
            )
    return out
