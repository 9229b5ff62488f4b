"""Rerun the study: ``bushenv vehicle-transfer`` with its defaults (the command's run and wall
time), then the wider check (every single error also at 0.5x and 2x the map's size besides
the sign reversed, and 48 held-out combinations); a summary of both.

    python studies/2026-11-error-transfer/run.py [--only default|wide]

Each run goes to ``default/`` or ``wide/`` here; ``summary.json`` collects the findings, the
predictor's figures against the targets and the times, with the load average at start and end.
The wide run's map is the default run's (the same 48 singles, deterministic): where its
predictor and CSV hash equal the default's they are removed from ``wide/`` and the summary says
so. ``--rewrite`` rebuilds each ``transfer.md`` from its ``transfer.json`` with the current
report code (no car runs).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RUNS = {
    "default": [],
    "wide": ["--held=-1.5,0.5,2", "--combinations", "48"],
}


def run(name: str) -> dict:
    out = HERE / name
    load0 = os.getloadavg()
    t0 = time.perf_counter()
    argv = [sys.executable, "-m", "bushenv.cli", "vehicle-transfer", "--out", str(out)]
    subprocess.run(argv + RUNS[name], check=True)
    wall = time.perf_counter() - t0
    report = json.loads((out / "transfer.json").read_text())
    found = report["findings"]
    checks = report["checks"]
    return {
        "argv": ["bushenv", *argv[3:], *RUNS[name]],
        "wall_time_s": wall,
        "command_wall_time_s": report["wall_time_s"],
        "cars": report["cars"],
        "car_steps": report["car_steps"],
        "load_average_start_end": [load0[0], os.getloadavg()[0]],
        "predictors": found["predictors"],
        "singles": {
            k: {
                n: {**v[n]["cells"], "influence_rank": v[n]["influence"]["overall"]}
                for n in checks["predictors"]
            }
            for k, v in checks["singles"].items()
        },  # fmt: skip
        "first_order_sign": checks.get("first_order_sign"),
        "combined": checks.get("combined"),
        "never_reach": [" ".join(r["component"]) for r in found["never_reach"]],
        "amplified": {
            " ".join(r["component"]): [r["max_pct"], r["where"], r["change"]]
            for r in found["amplified"]
        },  # fmt: skip
        "median_of_largest_by": found["median_of_largest_by"],
        "ended": report["ended"],
    }


def breakdown(report: dict, name: str) -> dict:
    """Predictor ``name``'s median relative error on the combinations by type (even: one
    error in all four pivots, odd: random mixes), by kind for the all-four ones, and by the size
    of the measured change (also below the judged 5 % of the size)."""
    import numpy as np

    least = report["checks"]["combined"][name]["least_pct"]
    combos = report["checks"]["combinations"]

    def rel(cs: list, lo: float = least, hi: float = np.inf) -> dict:
        m = np.concatenate([np.ravel(np.asarray(c["measured_pct"], float)) for c in cs])
        p = np.concatenate([np.ravel(np.asarray(c[f"{name}_pct"], float)) for c in cs])
        ok = np.isfinite(m) & (m > 0) & (m >= lo) & (m < hi)
        r = np.abs(p[ok] - m[ok]) / m[ok]
        return {"cells": int(ok.sum()), "median": float(np.median(r)) if ok.any() else None}

    kinds = sorted({c["terms"][0]["kind"] for c in combos[0::2]})
    return {
        "all_four_pivots": rel(combos[0::2]), "random_mixes": rel(combos[1::2]),
        "all_four_by_kind": {k: rel([c for c in combos[0::2] if c["terms"][0]["kind"] == k])
                             for k in kinds},
        "by_measured_pct": {f"{lo:g}-{hi:g}": rel(combos, lo, hi)
                            for lo, hi in ((0.5, 2), (2, 10), (10, np.inf))},
        "below_least": rel(combos, 0.0, least),
    }  # fmt: skip


def symmetric_track() -> dict:
    """The step steer's track change (RMS of the difference to the reference car, m) with the
    lower-left pivot's axial stiffness 10 % stiff, and with both lower pivots' so."""
    from bushenv.rigs.halfcar_params import ENV_ID, REFERENCE
    from bushenv.rigs.specs import spec_kwargs
    from bushenv.vehicle.manoeuvres import standard_manoeuvres
    from bushenv.vehicle.study import env_overrides
    from bushenv.vehicle.transfer import difference_histories, pivot_table
    from bushenv.vehicle.transfer_car import single_car_run
    from bushenv.vehicle.transfer_errors import ErrorTerm

    dt = float(spec_kwargs(ENV_ID, {})["dt_s"])
    m = standard_manoeuvres(dt, 0, ["step_steer"])[0]
    ov = env_overrides(standard_manoeuvres(dt, 0))
    base = single_car_run(m, REFERENCE, ov)
    out = {"reference_rms_m": float((base.outputs["track_change"] ** 2).mean() ** 0.5)}
    for label, pivots in (("lower_left", ["lower_left"]),
                          ("both lower", ["lower_left", "lower_right"])):  # fmt: skip
        terms = [ErrorTerm(p, "axial", "stiffness", 10.0) for p in pivots]
        d = difference_histories(single_car_run(m, pivot_table(terms, dt), ov), base, dt)[3]
        out[f"{label}_change_rms_m"] = float((d**2).mean() ** 0.5)
    return out


DUPLICATES = ("transfer_predictor.npz", "transfer_map.csv", "transfer_map.png")


def drop_duplicates(name: str) -> bool:
    """Remove ``name``'s map files where they equal the default run's; True if they did."""

    def sha(p: Path) -> str:
        return hashlib.sha256(p.read_bytes()).hexdigest()

    first, here = HERE / "default", HERE / name
    if name == "default" or not (first / DUPLICATES[0]).exists():
        return False
    if any(sha(first / f) != sha(here / f) for f in DUPLICATES[:2]):
        return False
    for f in DUPLICATES:
        (here / f).unlink()
    return True


def rewrite(name: str) -> None:
    from bushenv.vehicle.transfer_report import findings, markdown

    out = HERE / name
    report = json.loads((out / "transfer.json").read_text())
    figures = [str(out / f) for f in report["figures"]]
    text = markdown(report, findings(report), figures)
    for f in DUPLICATES[2:]:  # a figure dropped as the default's: link the default's
        if not (out / f).exists():
            text = text.replace(f"]({f})", f"](../default/{f})")
    (out / "transfer.md").write_text(text)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", choices=sorted(RUNS), default=None)
    ap.add_argument("--rewrite", action="store_true", help="only rebuild the markdown")
    args = ap.parse_args()
    path = HERE / "summary.json"
    summary = json.loads(path.read_text()) if path.exists() else {}
    for name in [args.only] if args.only else list(RUNS):
        if args.rewrite:
            rewrite(name)
            continue
        summary[name] = run(name)
        summary[name]["same_map_as_default"] = drop_duplicates(name)
        report = json.loads((HERE / name / "transfer.json").read_text())
        summary[name]["breakdown"] = {
            n: breakdown(report, n) for n in report["checks"]["predictors"]
        }
        path.write_text(json.dumps(summary, indent=1) + "\n")
        rewrite(name)
    if not args.rewrite:
        summary["symmetric_track"] = symmetric_track()
        path.write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps({k: v.get("predictors", v) for k, v in summary.items()}, indent=1))


if __name__ == "__main__":
    main()
