"""One member of the population: train a NARX model, certify it, judge it, attack it.

A cell is (recipe, model, axis, seed). Its training record is the reference rubber measured
through its load cell (noise, delay, fixture inertia) on an n = 1 random drive of 40 s whose
drive and noise seeds are the cell's seed (so the records vary too); two unseen records (n = 1
and n = 1.5, 20 s) judge its accuracy, as ``bushenv reproduce`` does. Then:

- its hold certificate over the stroke (``bushenv.certify``): folds, departures, wrong-sign
  holds, the least stable attractor, the bands where it generates energy about rest;
- the papers' step (seed 000 §5.2): +-4 mm held 10 s, judged by ``bushenv.divergence``;
- its static force at +-4 mm beside the reference's;
- the same searchers with the same budget against the reference rubber.

``run_cell`` is a pure function of the cell (module-level, so any backend can ship it); the
model file it trains is written under the cell's ``out``.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from bushenv import excitation as ex
from bushenv import metrics
from bushenv.certify import CertifyOptions, certify
from bushenv.identify import fit_model
from bushenv.machine import random_test
from bushenv.reference.rubber import RubberBushing
from bushenv.resolved import resolved as resolved_as
from bushenv.search.campaign_resolve import Resolved, resolve_target
from bushenv.search.campaign_search import run_search

STEP_M = 4e-3  # the papers' step (seed 000 §5.2)
STEP_HOLD_S = 10.0
TRAIN_S, UNSEEN_S = 40.0, 20.0  # the reproduction's record lengths
CERTIFY = CertifyOptions(holds=101, energy_amplitudes_m=(), passivity_holds_m=(0.0,))


def cell_name(cell: dict[str, Any]) -> str:
    extra = "".join(f"-{k}" for k, v in sorted(cell.get("train_options", {}).items()) if v == "on")
    return f"{cell['recipe']}{extra}-{cell['model']}-{cell['axis']}-s{cell['seed']}"


def records(axis: str, seed: int):
    """Training (n = 1) and the two unseen records (n = 1, n = 1.5) of a cell's seed."""
    train = random_test(RubberBushing.preset(axis, seed=seed), 1.0, TRAIN_S, seed=seed)
    seen = random_test(RubberBushing.preset(axis, seed=seed + 7919), 1.0, UNSEEN_S, seed + 7919)
    far = seed + 104729
    beyond = random_test(RubberBushing.preset(axis, seed=far), 1.5, UNSEEN_S, far)
    return train, seen, beyond


def _accuracy(model, seen, beyond) -> dict[str, float]:
    return {
        "rms_ratio_n1": metrics.rms_ratio(seen.force, model.simulate(seen.displacement)),
        "rms_ratio_n15": metrics.rms_ratio(beyond.force, model.simulate(beyond.displacement)),
    }


def _certificate(model, reference) -> dict[str, Any]:
    s = certify(model, reference, CERTIFY).document["summary"]
    keep = (
        "folds",
        "departing_holds",
        "wrong_sign_holds",
        "wrong_sign_ranges_m",
        "static_off_holds",
        "max_reached_spectral_radius",
        "non_passive_bands_hz_at_rest",
        "passes_holds",
    )
    return {k: s[k] for k in keep}


def _steps(resolved: Resolved) -> dict[str, Any]:
    """The papers' step both ways: verdict, departure time, held force beside the reference's."""
    dt = resolved.dt
    out = {}
    profiles = [ex.step_hold(s * STEP_M, STEP_HOLD_S, dt, pre_s=1.0) for s in (1, -1)]
    with resolved.evaluator(resolved.target_key) as ev:
        batch = ev.evaluate(profiles)
    departure = batch.verdict.criterion_first_s["self_sustained"]
    for b, name in enumerate(("+4mm", "-4mm")):
        row = batch.verdict.row(b)
        f_m, f_r = float(batch.f_model[-1, b]), float(batch.f_ref[-1, b])
        out[name] = {
            "bounded": not row["diverged"],
            "criteria": row["criteria"],
            # the free run leaves its hold (self_sustained), s after the profile's start
            "departure_s": None if np.isnan(departure[b]) else float(departure[b]),
            "held_force_n": f_m,
            "reference_held_force_n": f_r,
            "wrong_sign": bool(f_m * f_r < 0),
        }
    return out


def _attack(resolved: Resolved, searcher: str, budget: int, seed: int) -> dict[str, Any]:
    """One search of the attack's (``campaign_search.run_search``) on the member."""
    res = run_search(resolved, resolved.target_key, searcher, budget, seed)
    ff = res.first_failure
    return {
        "diverged": res.diverged,
        "evaluations_to_failure": ff.evaluation if ff else None,
        "first_criterion": ff.verdict["first_criterion"] if ff else None,
        "first_family": ff.family if ff else None,
        "criteria": sorted({c for f in res.failures for c in f.verdict["criteria"]}),
        "families": sorted({f.family for f in res.failures}),
        "n_failures": res.n_failures,
        "worst_robustness": res.worst.robustness if res.worst else None,
    }


def run_cell(cell: dict[str, Any]) -> dict[str, Any]:
    """Train, certify, judge and attack one member; the row the population study keeps."""
    import torch

    torch.set_num_threads(1)
    axis, seed = cell["axis"], int(cell["seed"])
    train, seen, beyond = records(axis, seed)
    t0 = time.perf_counter()
    model = fit_model(
        cell["model"],
        train.displacement,
        train.force,
        train.dt,
        seed=seed,
        progress=False,
        recipe=cell["recipe"],
        # a recipe's population at the papers' network size (no choice of size on validation)
        **{"choose": "off", **cell.get("train_options", {})},
    )
    train_s = time.perf_counter() - t0
    path = model.save(Path(cell["out"]) / "models" / f"{cell_name(cell)}.npz")
    # the attack's resolve stage, on the member as trained (its file hashed, no card read)
    resolved = resolve_target(resolved_as(path, model, axis), "rubber", axis=axis)
    reference = resolved.judge.reference
    t1 = time.perf_counter()
    row = {
        **cell,
        "model_file": str(path.relative_to(cell["out"])),
        "train_s": train_s,
        "accuracy": _accuracy(model, seen, beyond),
        "certificate": _certificate(model, reference),
        "step": _steps(resolved),
        "attacks": {
            s: _attack(resolved, s, int(cell["budget"]), seed) for s in cell["searchers"].split(",")
        },
    }
    row["judge_s"] = time.perf_counter() - t1
    row["diverged"] = any(a["diverged"] for a in row["attacks"].values())
    row["static_error_4mm"] = float(
        np.mean(
            [
                abs(v["held_force_n"] - v["reference_held_force_n"])
                / abs(v["reference_held_force_n"])
                for v in row["step"].values()
            ]
        )
    )
    return row
