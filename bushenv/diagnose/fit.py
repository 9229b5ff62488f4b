"""``diagnose()``: where a baseline's gap lies, which candidate closes it, how far.

Records are any objects with ``.time``, ``.displacement``, ``.force`` ((T,) arrays, s, m, N)
and ``.dt`` (s), such as ``bushenv.records.Record``. ``report.py`` writes the files; the
naming rule is ``rule.py``, the fitting ``fitting.py``, the candidates ``candidates.py``.

Two modes. **Every record** (``cross=True``, the default with the linear baseline): each
record, TRAIN or TEST, is judged by weights fitted on all the others (leave one record out),
so an effect only some records excite is identified and still judged on a record it was not
fitted on. **Held out** (``cross=False``, the default with another baseline): weights and
shapes fitted on the TRAIN records, every gap measured on the TESTs. The delay's phase test
(``lag.py``) reads every record.

Baselines: ``linear`` (``F = k x + c v``, refitted with every candidate: continuous-time, so
TESTs at other sample rates are handled) or a registered model identified on the first TRAIN
by ``bushenv.identify.fit_model`` (then every candidate also gets a spring/damper correction;
discrete-time, so TESTs must share TRAIN's rate; not with ``cross``).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from bushenv.diagnose import evidence, partner, regimes, rule, showing
from bushenv.diagnose.candidates import candidate_sets, get_effect
from bushenv.diagnose.coordinates import coordinate_count, diagnose_coordinates
from bushenv.diagnose.design import ColumnStore, Prepared
from bushenv.diagnose.effects.base import NULL, Scales
from bushenv.diagnose.errors import DiagnoseError
from bushenv.diagnose.fitting import Fold, Judged, best_shapes, describe_shapes, judge, predict
from bushenv.diagnose.fitting import parameters as fit_parameters
from bushenv.diagnose.inputs import (
    LINEAR,
    Progress,
    baseline_names,
    check_inputs,
    fit_nonlinear_baseline,
    make_folds,
    names_of,
    prepare_records,
    record_name,
)
from bushenv.diagnose.lag import lag_evidence
from bushenv.diagnose.shift import shift_warnings
from bushenv.metrics import rms_ratio

__all__ = ["DiagnoseError", "diagnose", "baseline_names"]


# ----- judging the candidates ------------------------------------------------------------------
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
            "_elastic": any(get_effect(n).holds_its_law for n in j.combo.names),
            "shape": describe_shapes(j.fits[0]),
            "gap_train": j.gap_train,
            "_mse": j.mse,
            "_pred": pred,
            "_judged": j,
        }


def _judge_all(run: Run, effects, say: Progress, ctx: rule.Context) -> tuple[list, list]:
    """Rows of every single effect and every pair, ranked best first (rule applied)."""
    sets = candidate_sets(effects)
    rows = []
    start = time.monotonic()
    for i, combo in enumerate(sets):
        elapsed = time.monotonic() - start
        left = f" (about {elapsed / i * (len(sets) - i):.0f} s left)" if i else ""
        say(f"which: candidate {i + 1}/{len(sets)} {combo.name}{left}")
        rows.append(run.row(judge(run.store, combo, run.folds, run.linear_base)))
    singles = [r for r in rows if len(r["members"]) == 1]
    pairs = [r for r in rows if len(r["members"]) == 2]
    rule.mark_failed(rows, ctx)
    best = min(rows, key=lambda r: r["gap_after"])
    if best["gap_after"] < run.gap_null:  # the noise is what not even the best model explains
        ctx.gap_noise = min(ctx.gap_noise, run.noise_gap(best["_pred"]))
        run.gap_noise = ctx.gap_noise
    rule.mark_passes(rows, ctx)
    singles = rule.rank(singles, [r["effect"] for r in singles], ctx)
    order = [r["effect"] for r in singles]
    for r in pairs:  # the better single first
        r["members"] = sorted(r["members"], key=order.index)
        r["effect"] = "+".join(r["members"])
    rule.mark_pairs(singles, pairs, ctx)
    pairs = rule.rank(pairs, order, ctx)
    say("which: each partner beside the other's richest form")
    partner.check_partners(
        pairs, lambda c: run.row(judge(run.store, c, run.folds, run.linear_base)), ctx
    )
    return singles, pairs


def _test_only_hint(run: Run, te: list[Prepared], singles: list[dict]) -> list[dict]:
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


# ----- the diagnosis ---------------------------------------------------------------------------
def diagnose(
    train: Any,
    tests: Sequence[Any],
    baseline: str = LINEAR,
    progress: Progress | None = None,
    seed: int = 0,
    test_names: Sequence[str] | None = None,
    *,
    cross: bool | None = None,
    effects: Sequence[str] | None = None,
    train_names: Sequence[str] | None = None,
) -> dict[str, Any]:
    """Where the gap lies, which candidate effect closes it, and by how much.

    ``train`` is one record or a sequence of identification records. ``cross``: None (the
    default) uses every record -- each judged by a fit on all the others -- with the linear
    baseline, and holds out the TESTs with another baseline (it is identified once, on
    TRAIN); True / False ask for the cross / held-out mode. Returns a JSON-ready dict
    (docs/diagnose.md) plus ``"predictions"``: one dict per judged record with ``name``,
    ``role`` and (T,) arrays ``time``, ``displacement``, ``force_measured``,
    ``force_baseline``, ``force_augmented`` (the answer's held-out prediction).

    Records of C > 1 coordinates (``.q``, ``.f`` (T, C)) go to
    ``bushenv.diagnose.coordinates.diagnose_coordinates``: which coordinate carries the gap,
    then this diagnosis on that coordinate.
    """
    trains = list(train) if isinstance(train, list | tuple) else [train]
    if any(coordinate_count(r) > 1 for r in trains + list(tests)):  # records of C coordinates
        return diagnose_coordinates(
            trains,
            tests,
            baseline,
            progress,
            seed,
            test_names,
            cross=cross,
            effects=effects,
            train_names=train_names,
            engine=diagnose,
        )
    say = progress or (lambda msg: None)
    if not trains:
        raise DiagnoseError("no TRAIN record given")
    t_names = (
        list(train_names or [])
        + [record_name(r, "train" if i == 0 else f"train{i + 1}") for i, r in enumerate(trains)][
            len(train_names or []) :
        ]
    )
    names = names_of(tests, test_names, "test")
    eff = tuple(effects) if effects is not None else None
    linear_base = baseline == LINEAR
    default_mode = cross is None
    cross = linear_base if cross is None else bool(cross)
    check_inputs(trains, list(tests), t_names, names, baseline, cross, eff)
    n_train = sum(np.size(r.force) for r in trains)
    say(f"identifying baseline {baseline!r} on TRAIN ({n_train} samples)")
    model = None if linear_base else fit_nonlinear_baseline(baseline, trains[0], seed, say)
    tr, te, stencil = prepare_records(trains, tests, t_names, names, model, cross, say)
    fitting = tr + (te if cross else [])
    store = ColumnStore(Scales.of([p.signals for p in fitting]), admissible=linear_base)
    run = Run(store, make_folds(tr, te, cross), linear_base)
    say(f"baseline gap on the judged records: {100 * run.gap_before:.2f} % (RMS ratio)")
    raw = [np.asarray(r.displacement, float) for r in list(trains) + list(tests)]
    lag = lag_evidence(
        [(p.name, x, p.force - p.b0, p.dt) for p, x in zip(tr + te, raw, strict=True)]
    )
    say(f"delay: {lag.text}")
    null_pred = run.stack(run.null.predictions)
    dx = np.concatenate([p.signals.v * p.dt for p in run.judged])
    x = np.concatenate([p.signals.x for p in run.judged])
    records = rule.record_edges([p.n for p in run.judged])
    ctx = rule.Context(
        run.force, null_pred, run.edges, run.gap_null, run.gap_noise, lag, dx, x, records
    )
    singles, pairs = _judge_all(run, eff, say, ctx)
    ans = rule.answer(singles, pairs, ctx)
    on_records: list[str] = []
    if ans.effect == rule.OUTSIDE:  # the records that show the effect may still name it
        alt = showing.answer_on_showing(singles, ctx)
        if alt is not None:
            ans, on_records = alt[0], [run.judged[i].name for i in alt[1]]
    say(f"answer: {ans.effect}" + (f" ({' or '.join(ans.between)})" if ans.between else ""))
    result = _result(run, singles, pairs, ans, ctx, baseline, cross)
    result["delay_evidence"] = lag.as_dict()
    result["named_on_records"] = on_records  # empty: named on all judged records together
    result["shift_warnings"] = shift_warnings(
        [(p.signals.x, p.dt) for p in tr], [(p.name, p.signals.x, p.dt) for p in te]
    )
    if not cross:
        result["shift_warnings"] += _test_only_hint(run, te, singles)
        if result["shift_warnings"] and result["unexplained"]["mostly_outside_candidates"]:
            result["unexplained"]["text"].append(
                "The TESTs hold regimes the TRAIN records lack (shift warning): an effect only "
                "they excite cannot be identified on TRAIN; the default mode fits on them too."
            )
    result["records"] = {
        "train": [{"name": p.name, "samples": p.n, "rate_hz": 1.0 / p.dt} for p in tr],
        "tests": [{"name": p.name, "samples": p.n, "rate_hz": 1.0 / p.dt} for p in te],
        "judged": [p.name for p in run.judged],
        "folds": [
            {"identified_on": [p.name for p in f.fit], "judged": [p.name for p in f.judged]}
            for f in run.folds
        ],
    }
    result["derivative_stencil"] = stencil
    result["displacement_band_hz"] = {
        p.name: p.band_edge_hz for p in tr + te if p.band_edge_hz is not None
    }
    result["notes"] = _notes(tr, te, baseline, cross)
    if default_mode and not linear_base:
        result["notes"].append(
            f"baseline {baseline!r} is identified once, on TRAIN: the TESTs are held out "
            "(every record is used by fitting on the others only with the linear baseline)."
        )
    return result


def _mode(cross: bool, n_records: int) -> dict[str, str]:
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


def _clean(r: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in r.items() if not k.startswith("_")}


def _result(run: Run, singles, pairs, ans: rule.Answer, ctx, baseline: str, cross: bool) -> dict:
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
        "telling_test": _telling_test(ans.between),
        "top_two": ans.top_two,
        "runner_up": others[0] if others else None,
        "baseline": baseline,
        **_mode(cross, len(run.judged) if cross else 0),
        "gap_before": run.gap_before,
        "gap_null": run.gap_null,
        "gap_noise": run.gap_noise,
        "gap_after": gap_after,
        "shrink": 1.0 - gap_after / run.gap_before if run.gap_before > 0 else 0.0,
        "unexplained": rule.unexplained(ans, rows, run.gap_before, ctx),
        "ranking": [_clean(r) for r in singles if not r["failed_to_fit"]],
        "pairs": [_clean(r) for r in pairs if not r["failed_to_fit"]],
        "failed_to_fit": [_clean(r) for r in rows if r["failed_to_fit"]],
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


def _telling_test(between: list[str]) -> str:
    """A programme that would tell the two effects of an ambiguous answer apart."""
    if not between:
        return ""
    parts = [f"{n}: {get_effect(n).telling_test}" for n in between]
    return (
        f"{' or '.join(between)}: these records cannot tell them apart; a test that would: "
        + "; ".join(parts)
    )


def _notes(tr: list[Prepared], te: list[Prepared], baseline: str, cross: bool) -> list[str]:
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
