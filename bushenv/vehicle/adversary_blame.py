"""Which bushing and which coordinate carry a car's difference under one manoeuvre.

Two views of the same run (``blame``):

- swap: the manoeuvre driven again with the reference bushing put back in one pivot (the model
  in the other three), and with the model in that pivot only; the pivot whose return to the
  reference removes most of the wheel-load difference carries it;
- forces: per pivot and coordinate, the RMS of the model car's bushing force (moment) less the
  twin's, in N (N m) and in % of the twin's RMS (in the car: each on its own motion), and the
  open-loop error: the model's and the reference's laws driven by the model car's pivot motion.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.rigs.halfcar_params import POSITIONS, REFERENCE
from bushenv.vehicle import adversary_space as space
from bushenv.vehicle.compare import run_car, vehicle_differences

COORDS = ("axial", "radial", "rotation")  # HalfCar-v0's pivot coordinates (moment for rotation)
OBJECTIVE = "wheel_load"


def _d(run) -> float | None:
    return vehicle_differences(run.model, run.reference, run.dt_s)[OBJECTIVE]["peak_pct"]


def _rms(a: np.ndarray) -> float:
    return float(np.sqrt(np.mean(a**2))) if a.size else float("nan")


def _table(model, reference: Any, model_at: set[str]) -> dict[str, Any]:
    """A pivot table: a copy of ``model`` where ``model_at``, ``reference`` elsewhere."""
    return {k: (model.copy() if k in model_at else reference) for k in POSITIONS}


def force_table(run, model, reference: Any) -> dict[str, dict[str, dict[str, float]]]:
    """Per pivot and coordinate: in-car and open-loop force difference, RMS (N or N m) and %
    of the twin's (in car) or the reference law's (open loop) RMS."""
    from bushenv.rigs.common import resolve_model
    from bushenv.rigs.halfcar_params import ENV_ID

    ref_law = resolve_model(reference, dt=run.dt_s, coords=3, what="reference", env_id=ENV_ID)
    out: dict[str, dict[str, dict[str, float]]] = {}
    for i, pivot in enumerate(POSITIONS):
        q = np.ascontiguousarray(run.deflection[:, i, :])
        law_m, law_r = model.copy(), ref_law.copy()
        law_m.reset(1)
        law_r.reset(1)
        with np.errstate(all="ignore"):
            f_m, f_r = law_m.simulate(q), law_r.simulate(q)
        row = {}
        for c, name in enumerate(COORDS):
            d_car = run.force_model[:, i, c] - run.force_reference[:, i, c]
            d_open = f_m[:, c] - f_r[:, c]
            base_car, base_open = _rms(run.force_reference[:, i, c]), _rms(f_r[:, c])
            row[name] = {
                "in_car_rms": _rms(d_car),
                "in_car_pct": 100 * _rms(d_car) / base_car if base_car > 0 else None,
                "open_loop_rms": _rms(d_open),
                "open_loop_pct": 100 * _rms(d_open) / base_open if base_open > 0 else None,
            }
        out[pivot] = row
    return out


def blame(profile: np.ndarray, dt_s: float, model, reference: Any = REFERENCE) -> dict[str, Any]:
    """The swap and the force views of ``profile`` (module docstring); the wheel-load
    difference D in % of the reference car's peak, as the search judged it."""
    m = space.as_manoeuvre(profile, dt_s)
    kwargs = {"max_lateral_accel_step_m_per_s2": space.AY_STEP_M_PER_S2}
    full = run_car(m, model, reference, "all four", kwargs)
    swap = {}
    for pivot in POSITIONS:
        others = set(POSITIONS) - {pivot}
        without = run_car(m, _table(model, reference, others), reference, "", kwargs)
        alone = run_car(m, _table(model, reference, {pivot}), reference, "", kwargs)
        swap[pivot] = {
            "d_pct_reference_here": _d(without),
            "ended_reference_here": without.end.get("reason") or None,
            "d_pct_model_here_only": _d(alone),
            "ended_model_here_only": alone.end.get("reason") or None,
        }
    forces = force_table(full, model, reference)
    d_all = _d(full)
    # the pivot whose return to the reference removes most of D; its largest in-car coordinate
    drop = {k: (d_all or 0.0) - (v["d_pct_reference_here"] or 0.0) for k, v in swap.items()}
    pivot = max(drop, key=drop.get)
    coord = max(COORDS, key=lambda c: forces[pivot][c]["in_car_pct"] or 0.0)
    return {"d_pct_all_four": d_all, "ended_all_four": full.end.get("reason") or None,
            "swap": swap, "forces": forces, "carried_by": {"pivot": pivot, "coordinate": coord,
            "d_drop_pct": drop[pivot]}}  # fmt: skip
