"""``diagnose()``: where a baseline's gap lies, which candidate closes it, how far.

Records are any objects with ``.time``, ``.displacement``, ``.force`` ((T,) arrays, s, m, N)
and ``.dt`` (s), such as ``bushenv.records.Record``. ``report.py`` writes the files; the
naming rule is ``rule.py`` (applied by ``naming.py``), the fitting ``fitting.py``, the
candidates ``candidates.py``, judging them ``judging.py``, the result dict ``outcome.py``.

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

from collections.abc import Sequence
from typing import Any

import numpy as np

from bushenv.diagnose import halves, rule, showing
from bushenv.diagnose.coordinates import coordinate_count, diagnose_coordinates
from bushenv.diagnose.design import ColumnStore
from bushenv.diagnose.effects.base import Scales
from bushenv.diagnose.errors import DiagnoseError
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
from bushenv.diagnose.judging import Run, judge_all, test_only_hint
from bushenv.diagnose.lag import lag_evidence
from bushenv.diagnose.outcome import notes_of, result_of
from bushenv.diagnose.session import Order, link
from bushenv.diagnose.shift import shift_warnings

__all__ = ["DiagnoseError", "diagnose", "baseline_names"]


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
    run_order: Order | None = None,
) -> dict[str, Any]:
    """Where the gap lies, which candidate effect closes it, and by how much.

    ``train`` is one record or a sequence of identification records. ``cross``: None (the
    default) uses every record -- each judged by a fit on all the others -- with the linear
    baseline, and holds out the TESTs with another baseline (it is identified once, on
    TRAIN); True / False ask for the cross / held-out mode. Returns a JSON-ready dict
    (docs/diagnose.md) plus ``"predictions"``: one dict per judged record with ``name``,
    ``role`` and (T,) arrays ``time``, ``displacement``, ``force_measured``,
    ``force_baseline``, ``force_augmented`` (the answer's held-out prediction).

    ``run_order``: the records in the order the rig ran them, ``[(name, rest_s), ...]``
    (``bushenv.diagnose.session``): a heat is carried from record to record and a session has
    one start. Without it every record may start warm, each at its own heat.

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
            run_order=run_order,
        )
    if not trains:
        raise DiagnoseError("no TRAIN record given")
    return _diagnose_axis(
        trains, list(tests), baseline, progress, seed, test_names, cross, effects, train_names,
        run_order, halve=True,
    )  # fmt: skip


def _diagnose_axis(
    trains: list[Any],
    tests: list[Any],
    baseline: str,
    progress: Progress | None,
    seed: int,
    test_names: Sequence[str] | None,
    cross: bool | None,
    effects: Sequence[str] | None,
    train_names: Sequence[str] | None,
    run_order: Order | None,
    halve: bool,
) -> dict[str, Any]:
    """``diagnose`` on records of one coordinate; ``halve``: a record that alone shows the
    gap may be judged half against half (``halves.py``)."""
    say = progress or (lambda msg: None)
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
    sessions = link(tr + te, run_order) if run_order else []
    for names_run in sessions:
        say("run in one session, heat carried over: " + " -> ".join(names_run))
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
    runs = None if halve else halves.runs_of([p.name for p in run.judged])
    ctx = rule.Context(
        run.force, null_pred, run.edges, run.gap_null, run.gap_noise, lag, dx, x, records, runs
    )
    singles, pairs = judge_all(run, eff, say, ctx)
    ans = rule.answer(singles, pairs, ctx)
    on_records: list[str] = []
    if ans.effect == rule.OUTSIDE:  # the records that show the effect may still name it
        alt = showing.answer_on_showing(singles, pairs, ctx, run.row_of)
        if alt is not None:
            ans, on_records = alt[0], [run.judged[i].name for i in alt[1]]
    if ans.effect == rule.OUTSIDE and cross and linear_base and halve:
        lone = showing.showing_records(ctx)
        if len(lone) == 1 and len(run.judged) > 1:
            again = _by_halves(
                run.judged[lone[0]].name, trains, tests, t_names, names, seed, effects,
                run_order, progress,
            )  # fmt: skip
            if again is not None:
                return again
    say(f"answer: {ans.effect}" + (f" ({' or '.join(ans.between)})" if ans.between else ""))
    result = result_of(run, singles, pairs, ans, ctx, baseline, cross)
    result["delay_evidence"] = lag.as_dict()
    result["named_on_records"] = on_records  # empty: named on all judged records together
    result["shift_warnings"] = shift_warnings(
        [(p.signals.x, p.dt) for p in tr], [(p.name, p.signals.x, p.dt) for p in te]
    )
    if not cross:
        result["shift_warnings"] += test_only_hint(run, te, singles)
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
    result["records"]["sessions"] = sessions  # the run order given (empty: none)
    result["records"]["session_time_s"] = {  # each ordered record's start in its session
        p.name: p.signals.session_time_s for p in tr + te if any(p.name in s for s in sessions)
    }
    result["derivative_stencil"] = stencil
    result["displacement_band_hz"] = {
        p.name: p.band_edge_hz for p in tr + te if p.band_edge_hz is not None
    }
    result["notes"] = notes_of(tr, te, baseline, cross)
    if default_mode and not linear_base:
        result["notes"].append(
            f"baseline {baseline!r} is identified once, on TRAIN: the TESTs are held out "
            "(every record is used by fitting on the others only with the linear baseline)."
        )
    return result


def _by_halves(name, trains, tests, t_names, names, seed, effects, run_order, progress):
    """The diagnosis again with the record ``name`` split in halves run as one session
    (``halves.py``), or None when it cannot be split or its answer names nothing."""
    say = progress or (lambda msg: None)
    if not halves.can_split(dict(zip(t_names + names, trains + tests, strict=True))[name]):
        return None
    say(f"{name} alone shows a gap: judged again half against half (halves run as one session)")
    tr, tr_names = halves.split_records(trains, t_names, name)
    te, te_names = halves.split_records(tests, names, name)
    order = halves.order_with_halves(run_order, name)
    res = _diagnose_axis(
        tr, te, LINEAR, progress, seed, te_names, True, effects, tr_names, order, halve=False
    )
    if res["effect"] in (rule.OUTSIDE, "none"):
        say(f"half against half: {res['effect']}; the answer on whole records stands")
        return None
    res["named_on_records"] = [name + s for s in halves.SUFFIXES]
    res["notes"].append(
        f"{name} alone shows a gap: judged by fits on records without the effect, no "
        f"candidate could close it there; split in two halves run as one session, each half "
        f"judged by a fit on the other half and the other records, {res['effect']} "
        "closes it."
    )
    return res
