"""The result of a diagnosis as a JSON-ready dict (docs/diagnose.md): the answer, the gaps,
the ranking, where the gap lies before and after, the named model's parameters, the held-out
predictions and the notes on the mode and the records."""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.diagnose import evidence, regimes, rule
from bushenv.diagnose.candidates import get_effect
from bushenv.diagnose.design import Prepared
from bushenv.diagnose.fitting import best_shapes
from bushenv.diagnose.fitting import parameters as fit_parameters
from bushenv.diagnose.inputs import LINEAR
from bushenv.diagnose.judging import Run
from bushenv.metrics import rms_ratio


def mode_of(cross: bool, n_records: int) -> dict[str, str]:
    if cross:
        return {
            "mode": "cross",
            "mode_text": f"every record used: each of the {n_records} records (TRAIN and TEST) "
            f"is judged by weights fitted on the other {n_records - 1} (leave one record out)",
        }
    return {
        "mode": "held_out",
        "mode_text": "held out: weights fitted on the TRAIN records, gaps measured on the TESTs",
    }


def clean(r: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in r.items() if not k.startswith("_")}


def result_of(run: Run, singles, pairs, ans: rule.Answer, ctx, baseline: str, cross: bool) -> dict:
    named = ans.row
    aug = named["_judged"].predictions if named else run.base_pred
    gap_after = rms_ratio(run.force, run.stack(aug))
    rows = singles + pairs
    if named is not None and cross:  # the physical parameters: the named model on all records
        every = tuple(p for f in run.folds for p in f.judged)
        final = best_shapes(run.store, named["_judged"].combo, every, run.linear_base)
    else:
        final = (named or {"_judged": run.null})["_judged"].fits[0]
    judged_x = [p.signals.x for p in run.judged]
    dts = [p.dt for p in run.judged]
    where = regimes.where_analysis(
        judged_x, [p.force - run.base_pred[p.uid] for p in run.judged], dts
    )
    where_after = where
    if named is not None:
        where_after = regimes.where_analysis(
            judged_x, [p.force - aug[p.uid] for p in run.judged], dts
        )
    members = set(named["members"]) if named else set()
    others = [r["effect"] for r in singles if not r["failed_to_fit"] and r["effect"] not in members]
    return {
        "effect": ans.effect,
        "ambiguous_between": ans.between,
        "telling_test": telling_test(ans.between),
        "top_two": ans.top_two,
        "runner_up": others[0] if others else None,
        "baseline": baseline,
        **mode_of(cross, len(run.judged) if cross else 0),
        "gap_before": run.gap_before,
        "gap_null": run.gap_null,
        "gap_noise": run.gap_noise,
        "gap_after": gap_after,
        "shrink": 1.0 - gap_after / run.gap_before if run.gap_before > 0 else 0.0,
        "unexplained": rule.unexplained(ans, rows, run.gap_before, ctx),
        "ranking": [clean(r) for r in singles if not r["failed_to_fit"]],
        "pairs": [clean(r) for r in pairs if not r["failed_to_fit"]],
        "failed_to_fit": [clean(r) for r in rows if r["failed_to_fit"]],
        "rule": {
            "fail_ratio": rule.FAIL_RATIO,
            "z_name": rule.Z_NAME,
            "shrink_min": rule.SHRINK_MIN,
            "pair_gain_min": rule.PAIR_GAIN_MIN,
            "pair_try_if_left": rule.PAIR_TRY_IF_LEFT,
            "outside_noise": rule.OUTSIDE_NOISE,
            "block_s": evidence.BLOCK_S,
            "text": rule.RULE_TEXT,
        },
        "where": where,
        "where_after": where_after,
        "parameters": fit_parameters(run.store, final, run.linear_base),
        "predictions": [
            {
                "name": p.name,
                "role": p.role,
                "dt": p.dt,
                "displacement": p.signals.x,
                "time": p.time,
                "force_measured": p.force,
                "force_baseline": run.base_pred[p.uid],
                "force_augmented": aug[p.uid],
            }
            for p in run.judged
        ],
    }


def telling_test(between: list[str]) -> str:
    """A programme that would tell the two effects of an ambiguous answer apart."""
    if not between:
        return ""
    parts = [f"{n}: {get_effect(n).telling_test}" for n in between]
    return (
        f"{' or '.join(between)}: these records cannot tell them apart; a test that would: "
        + "; ".join(parts)
    )


def notes_of(tr: list[Prepared], te: list[Prepared], baseline: str, cross: bool) -> list[str]:
    notes = [
        f"TEST {p.name} is the TRAIN record {q.name} itself: its gap is not held out."
        for p in te
        for q in tr
        if p.n == q.n
        and np.array_equal(p.force, q.force)
        and np.array_equal(p.signals.x, q.signals.x)
    ]
    if baseline != LINEAR and len(tr) > 1:
        notes.append(
            f"baseline {baseline!r} was identified on {tr[0].name} alone; the other TRAIN "
            "records fit the candidates' weights only."
        )
    if cross:
        notes.append(
            "cross mode: every record is judged by a fit on the others, so the gaps pool TRAIN "
            "and TEST records; the parameters are those of the named model fitted on all."
        )
    return notes
