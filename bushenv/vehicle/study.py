"""The vehicle comparison: every manoeuvre x every bushing kind in HalfCar-v0 against the
reference bushing, the table of vehicle-level and component-level differences, and the verdict
on seed 000's finding that a hybrid bushing gives vehicle responses "almost identical" to the
linear one's (§5.3, §6).

``run_vehicle(manoeuvres, bushings, ...)`` returns the report (plain values, ``report.json``'s
content) and the runs (for the plots). Each model car is compared with its reference twin;
seed 000's own comparison, the hybrid car against the linear car, is computed from the same
runs.
"""

from __future__ import annotations

import math
import statistics
import time
from typing import Any

from bushenv.rigs.halfcar_params import ENV_ID, REFERENCE
from bushenv.rigs.specs import spec_kwargs
from bushenv.vehicle.compare import (
    OUTPUTS,
    CarRun,
    at_rest,
    component_errors,
    run_car,
    transfer,
    vehicle_differences,
    worst,
)
from bushenv.vehicle.manoeuvres import Manoeuvre

IDENTICAL_PCT = 5.0  # "almost identical": within this % of the linear car's peak
# the outputs the verdict judges: they exist in every manoeuvre (the accelerations' relative
# figures are ruled by a near-zero reference in the events that do not excite them); on the
# road events also the Wk-weighted a_w, seed 001's ride output
JUDGED = ("wheel_load", "roll", "camber", "track_change")
PAPER_PAIR = ("hybrid", "linear")  # seed 000 §5.3 compares these two cars
# seed 000 §5.3 put its hybrid in the upper control arm's pivot only: that car, the others linear
UPPER_ONLY = "hybrid-upper"
REFERENCE_CAR = "reference"  # runs' key of a car with the reference bushing in both (plots)


def upper_only(lower: Any, upper: Any) -> dict[str, Any]:
    """A HalfCar-v0 pivot table: ``upper`` in both upper arm pivots, ``lower`` in the lower."""
    return {"lower_left": lower, "upper_left": upper, "lower_right": lower, "upper_right": upper}


def env_overrides(manoeuvres: list[Manoeuvre]) -> dict[str, Any]:
    """HalfCar-v0 kwargs for replaying ``manoeuvres``: the lateral-load step limit raised, in
    0.05 m/s^2 steps, to the largest a_y change of any when it exceeds the spec's (0.4 m/s^2
    per step covers ISO 7401's 500 deg/s and NHTSA's 720 deg/s, so the standard manoeuvres need
    none); the limit only checks inputs, the physics does not use it."""
    spec = float(spec_kwargs(ENV_ID, {})["max_lateral_accel_step_m_per_s2"])
    need = max(m.largest_steps()[1] for m in manoeuvres)
    if need <= spec:
        return {}
    return {"max_lateral_accel_step_m_per_s2": math.ceil(need * 1.02 / 0.05) * 0.05}


def _row(run: CarRun, manoeuvre: Manoeuvre, model: Any, reference: Any) -> dict[str, Any]:
    vehicle = vehicle_differences(run.model, run.reference, run.dt_s)
    component = component_errors(run, model, reference)
    v_rms = worst({k: vehicle[k] for k in JUDGED}, "rms_pct")
    c_rms = worst(component["open_loop"], "rms_pct")
    return {
        "manoeuvre": run.manoeuvre, "kind": run.label, "steps": run.steps,
        "samples": manoeuvre.samples, "end": run.end,
        "reference_outside_range_steps": run.reference_outside_steps,
        "at_rest": at_rest(run, manoeuvre),
        "vehicle": vehicle, "component": component,
        "worst_judged_rms_pct": v_rms, "worst_component_rms_pct": c_rms,
        "transfer": transfer(v_rms, c_rms), "seconds": run.seconds,
    }  # fmt: skip


def _pair(a: CarRun, b: CarRun) -> dict[str, Any]:
    """Car ``a`` against car ``b`` (both model cars), relative to ``b``'s own peak and RMS."""
    return {"manoeuvre": a.manoeuvre, "kind": a.label, "baseline": b.label,
            "steps": min(a.steps, b.steps),
            "vehicle": vehicle_differences(a.model, b.model, a.dt_s)}  # fmt: skip


def judged_peaks(vehicle: dict[str, Any], road: bool) -> dict[str, float]:
    """The verdict's figures of one comparison: each judged output's peak difference (%), and
    on a road event the a_w difference; outputs nil in the baseline are left out."""
    out = {k: vehicle[k]["peak_pct"] for k in JUDGED if vehicle[k]["peak_pct"] is not None}
    if road and vehicle["a_w_Wk"]["difference_pct"] is not None:
        out["a_w_Wk"] = vehicle["a_w_Wk"]["difference_pct"]
    return out


def verdict(
    report: dict[str, Any], kind: str = PAPER_PAIR[0], identical_pct: float = IDENTICAL_PCT
) -> dict[str, Any]:
    """Seed 000's finding judged for the ``kind`` car: within ``identical_pct`` of the linear
    car's peak in every judged output of every manoeuvre; beside it, each car against the
    reference."""
    base = PAPER_PAIR[1]
    pairs = [p for p in report["pairs"] if p["kind"] == kind and p["baseline"] == base]
    if not pairs:
        return {"status": "not judged", "why": f"needs both {kind} and {base} bushings"}
    road = {m["name"]: m["peak_road_m"] > 0 for m in report["manoeuvres"]}
    per = {p["manoeuvre"]: judged_peaks(p["vehicle"], road[p["manoeuvre"]]) for p in pairs}
    flat = [(m, k, v) for m, d in per.items() for k, v in d.items()]
    m_w, k_w, v_w = max(flat, key=lambda x: x[2])
    against_ref = {}
    for label in (kind, base):
        rows = [r for r in report["rows"] if r["kind"] == label]
        vals = [v for r in rows
                for v in judged_peaks(r["vehicle"], road[r["manoeuvre"]]).values()]  # fmt: skip
        against_ref[label] = {
            "median_peak_pct": statistics.median(vals) if vals else None,
            "max_peak_pct": max(vals) if vals else None,
        }
    ended = [p["manoeuvre"] for p in pairs if p["steps"] < _samples(report, p["manoeuvre"])]
    within = sum(v <= identical_pct for _, _, v in flat)
    by_output: dict[str, dict[str, Any]] = {}
    for m, k, v in flat:
        if k not in by_output or v > by_output[k]["peak_pct"]:
            by_output[k] = {"peak_pct": v, "manoeuvre": m}
    return {
        "status": "reproduced" if v_w <= identical_pct else "refuted", "kind": kind,
        "baseline": base, "threshold_pct": identical_pct, "judged": [*JUDGED, "a_w_Wk (roads)"],
        "worst": {"manoeuvre": m_w, "output": k_w, "peak_pct": v_w},
        "median_peak_pct": statistics.median(v for _, _, v in flat),
        "within_threshold": f"{within} of {len(flat)}", "worst_by_output": by_output,
        "per_manoeuvre": per, "against_reference": against_ref,
        "compared_over_fewer_steps": ended,
    }  # fmt: skip


def _samples(report: dict[str, Any], name: str) -> int:
    return next(m["samples"] for m in report["manoeuvres"] if m["name"] == name)


def run_vehicle(
    manoeuvres: list[Manoeuvre],
    bushings: dict[str, Any],
    reference: Any = REFERENCE,
    progress: Any = None,
    identical_pct: float = IDENTICAL_PCT,
    paper_car: bool = True,
) -> tuple[dict[str, Any], dict[tuple[str, str], CarRun]]:
    """Run every manoeuvre with each of ``bushings`` (label -> model, name or file) in all four
    pivots against ``reference``; the report and the runs by (manoeuvre, label) (and by
    (manoeuvre, ``REFERENCE_CAR``) where every model car ended early: the reference's whole
    history, for the figures).

    ``progress``: a ``bushenv.progress.Progress`` (its ``total`` set here to the steps to run)
    or None. ``paper_car``: with both a ``hybrid`` and a ``linear`` bushing, also the car of
    seed 000 §5.3 (``UPPER_ONLY``: the hybrid in the upper arm pivots, linear in the lower).
    """
    t0 = time.perf_counter()
    bushings = dict(bushings)
    if paper_car and all(k in bushings for k in PAPER_PAIR):
        bushings[UPPER_ONLY] = upper_only(bushings[PAPER_PAIR[1]], bushings[PAPER_PAIR[0]])
    overrides = env_overrides(manoeuvres)
    total = sum(m.samples for m in manoeuvres) * len(bushings)
    if progress is not None:
        progress.total = total
        progress.say(f"{len(manoeuvres)} manoeuvres x {len(bushings)} cars ({', '.join(bushings)})"
                     f": {total} car steps, each beside its reference twin")  # fmt: skip
    runs: dict[tuple[str, str], CarRun] = {}
    rows, pairs, done = [], [], 0
    for m in manoeuvres:
        for label, model in bushings.items():

            def tick(steps: int, m=m, label=label, base=done) -> None:
                if progress is not None:
                    progress.update(base + steps, f"{m.name}: {label} car")

            run = run_car(m, model, reference, label, overrides, tick)
            runs[(m.name, label)] = run
            rows.append(_row(run, m, model, reference))
            done += m.samples
            if progress is not None:
                end = run.end
                status = (f"ENDED at {end['time_s']:.2f} s: {end['reason']}"
                          if end.get("reason") else "ran to the end")  # fmt: skip
                progress.update(done, f"{m.name}: {label} car {status}", force=True)
        if all(runs[(m.name, k)].steps < m.samples for k in bushings):
            # every model car ended early: the reference car alone, for its whole history
            runs[(m.name, REFERENCE_CAR)] = run_car(m, reference, reference, REFERENCE_CAR,
                                                    overrides)  # fmt: skip
        for label in bushings:
            if label != PAPER_PAIR[1] and PAPER_PAIR[1] in bushings:
                pairs.append(_pair(runs[(m.name, label)], runs[(m.name, PAPER_PAIR[1])]))
    report = {
        "env": ENV_ID, "env_kwargs": overrides, "dt_s": manoeuvres[0].dt_s,
        "reference": reference if isinstance(reference, str) else type(reference).__name__,
        "outputs": {o.name: {"title": o.title, "unit": o.unit, "info_keys": list(o.keys),
                             "floor": o.floor} for o in OUTPUTS},
        "manoeuvres": [m.describe() for m in manoeuvres],
        "kinds": list(bushings), "rows": rows, "pairs": pairs,
        "run_seconds": time.perf_counter() - t0,
    }  # fmt: skip
    report["finding"] = verdict(report, PAPER_PAIR[0], identical_pct)
    report["finding_upper_only"] = verdict(report, UPPER_ONLY, identical_pct)
    return report, runs
