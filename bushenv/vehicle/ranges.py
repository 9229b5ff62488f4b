"""How long the standard manoeuvres keep the car's pivots outside the ranges their laws hold:
the reference twin beyond its calibrated rotation (``reference_outside_range``) and each fitted
model car beyond the deflections its identification records reached, per coordinate.

    python studies/2026-11-vehicle-manoeuvres/ranges.py --bushings DIR [--seed 0] [--out F.json]

(``measure``; the script is the study's.) ``DIR`` holds ``linear.npz``, ``hybrid.npz``,
``nn.npz`` as ``bushenv vehicle`` caches them
(``DIR/<kind>.fit.json`` names the records' recipe); the records are measured again from that
recipe (``bushenv.reproduce.identification_records``) for their peaks. Prints one line per
manoeuvre and car on stderr, and writes the table as JSON when ``--out`` is given.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.models import load_model
from bushenv.models.planar_base import COORDS
from bushenv.rigs.halfcar_params import ENV_ID, REFERENCE
from bushenv.rigs.specs import spec_kwargs
from bushenv.vehicle.checks import VehicleInputError
from bushenv.vehicle.compare import run_car
from bushenv.vehicle.manoeuvres import standard_manoeuvres
from bushenv.vehicle.study import env_overrides

KINDS = ("linear", "hybrid", "nn")


def record_peaks(key: dict[str, Any]) -> np.ndarray:
    """(3,) the largest |q| per coordinate over the identification records of a fit's key."""
    from bushenv.reproduce import identification_records

    records = identification_records(
        key["dt_s"], key["seed"], key["identification_s"], key["records"], key["rotation"]
    )
    return np.max([np.abs(q).max(axis=0) for q, _ in records], axis=0)


def steps_outside(deflection: np.ndarray, peaks: np.ndarray) -> dict[str, int]:
    """Steps where any pivot's coordinate exceeds ``peaks``, per coordinate and in any."""
    beyond = np.abs(deflection) > peaks  # (T, 4, 3)
    out = {c: int(beyond[:, :, i].any(axis=1).sum()) for i, c in enumerate(COORDS)}
    out["any"] = int(beyond.any(axis=(1, 2)).sum())
    return out


def measure(bushings: Path, seed: int = 0, say=None) -> dict[str, Any]:
    """Per manoeuvre: the reference car's steps beyond its calibrated rotation and peak
    deflection per coordinate; per kind its model car's steps beyond its records' peaks."""
    dt = float(spec_kwargs(ENV_ID, {})["dt_s"])
    manoeuvres = standard_manoeuvres(dt, seed)
    overrides = env_overrides(manoeuvres)
    models, peaks, by_key = {}, {}, {}
    for kind in KINDS:
        meta_path = bushings / f"{kind}.fit.json"
        if not meta_path.exists():
            raise VehicleInputError(f"{meta_path} missing: run `bushenv vehicle` first")
        key = json.loads(meta_path.read_text())["key"]
        models[kind] = load_model(bushings / f"{kind}.npz", dt=dt, coords=3)
        recipe = json.dumps({k: v for k, v in key.items() if k != "kind"}, sort_keys=True)
        if recipe not in by_key:  # the kinds share their records
            by_key[recipe] = record_peaks(key)
        peaks[kind] = by_key[recipe]
    out: dict[str, Any] = {"record_peaks": {k: p.tolist() for k, p in peaks.items()}, "rows": {}}
    for m in manoeuvres:
        row: dict[str, Any] = {}
        run = run_car(m, REFERENCE, REFERENCE, "reference", overrides)
        row["reference"] = {
            "steps": run.steps,
            "outside_calibrated_steps": run.reference_outside_steps,
            "peak": np.abs(run.deflection).max(axis=(0, 1)).tolist(),
        }
        for kind in KINDS:
            run = run_car(m, models[kind], REFERENCE, kind, overrides)
            row[kind] = {"steps": run.steps, "outside_records": steps_outside(run.deflection,
                         peaks[kind]), "twin_outside_calibrated_steps":
                         run.reference_outside_steps}  # fmt: skip
        out["rows"][m.name] = row
        if say:
            ref = row["reference"]
            kinds = ", ".join(
                f"{k} {row[k]['outside_records']['any']}/{row[k]['steps']} "
                f"(rotation {row[k]['outside_records']['rotation']})"
                for k in KINDS
            )
            say(f"{m.name}: reference {ref['outside_calibrated_steps']}/{ref['steps']} beyond "
                f"its calibrated rotation (peak {ref['peak'][2]:.3f} rad); beyond the records: "
                f"{kinds}")  # fmt: skip
    return out
