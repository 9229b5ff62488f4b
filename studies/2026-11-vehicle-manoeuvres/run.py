"""Rerun the study: ``bushenv vehicle`` from scratch for identification seeds 0, 1, 2 (default
kinds) and once for seed 0 with ``hybrid-bw`` added; a summary of the verdicts and times.

    python studies/2026-11-vehicle-manoeuvres/run.py [--seeds 0 1 2] [--no-extra]

Each run goes to ``seedN/`` here (``seed0-hybrid-bw/`` for the extra one); the cached fits in
``seedN/bushings/`` are removed first, so every wall time includes the identification.
``summary.json`` collects each run's findings, terminations, at-rest motion and wall time.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def run(out: Path, seed: int, kinds: str | None) -> dict:
    shutil.rmtree(out / "bushings", ignore_errors=True)
    argv = [sys.executable, "-m", "bushenv.cli", "vehicle", "--out", str(out), "--seed", str(seed)]
    if kinds:
        argv += ["--kinds", kinds]
    subprocess.run(argv, check=True)
    report = json.loads((out / "report.json").read_text())
    keep = ("status", "worst", "median_peak_pct", "within_threshold", "worst_by_output")
    return {
        "seed": seed,
        "kinds": report["kinds"],
        "wall_time_s": report["wall_time_s"],
        "car_runs_s": report["run_seconds"],
        "fit_seconds": {
            k: b["fit_seconds"]
            for k, b in report["bushings"].items()
            if b.get("fit_seconds") is not None
        },  # fmt: skip
        "finding_all_four": {k: report["finding"].get(k) for k in keep},
        "finding_upper_only": {k: report["finding_upper_only"].get(k) for k in keep},
        "against_reference": report["finding"].get("against_reference"),
        "ended": [
            {"kind": r["kind"], "manoeuvre": r["manoeuvre"], **r["end"]}
            for r in report["rows"]
            if r["end"].get("reason")
        ],
        "at_rest_wheel_load_rms_n": {
            f"{r['kind']} {r['manoeuvre']}": r["at_rest"]["wheel_load_rms_n"]
            for r in report["rows"]
        },
        "worst_judged_rms_pct": {
            f"{r['kind']} {r['manoeuvre']}": r["worst_judged_rms_pct"] for r in report["rows"]
        },
    }


def compact_table(report: dict) -> str:
    """Markdown: per manoeuvre and car, the largest component RMS error and the judged
    outputs' RMS differences to the reference car (%), and how the run ended."""
    names = ("wheel_load", "roll", "camber", "track_change")
    lines = ["| manoeuvre | car | run | component (max of 3) | wheel load | roll | camber | "
             "track | a_w (Wk) |", "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip

    def pct(v):
        return "n/a" if v is None else f"{v:.0f}" if v >= 100 else f"{v:.1f}"

    for r in report["rows"]:
        end = r["end"]
        ran = f"ended {end['time_s']:.2f} s" if end.get("reason") else "ran"
        cells = [r["manoeuvre"], r["kind"], ran, pct(r["worst_component_rms_pct"]),
                 *(pct(r["vehicle"][n]["rms_pct"]) for n in names),
                 pct(r["vehicle"]["a_w_Wk"]["difference_pct"])]  # fmt: skip
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def reference_deflections(seed: int = 0) -> dict:
    """Per manoeuvre: the reference car's largest pivot deflection over the four pivots, per
    coordinate, over the n = 1 identification peaks (``bushenv.motions.PEAK_AT_N1``)."""
    import numpy as np

    from bushenv.motions import PEAK_AT_N1
    from bushenv.rigs.halfcar_params import ENV_ID, REFERENCE
    from bushenv.rigs.specs import spec_kwargs
    from bushenv.vehicle.compare import run_car
    from bushenv.vehicle.manoeuvres import standard_manoeuvres
    from bushenv.vehicle.study import env_overrides

    dt = float(spec_kwargs(ENV_ID, {})["dt_s"])
    manoeuvres = standard_manoeuvres(dt, seed)
    overrides = env_overrides(manoeuvres)
    out = {}
    for m in manoeuvres:
        run = run_car(m, REFERENCE, REFERENCE, "reference", overrides)
        peak = np.abs(run.deflection).max(axis=(0, 1)) / PEAK_AT_N1
        out[m.name] = {"axial": float(peak[0]), "radial": float(peak[1]),
                       "rotation": float(peak[2]),
                       "outside_calibrated_steps": run.reference_outside_steps}  # fmt: skip
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--no-extra", action="store_true", help="skip the hybrid-bw run")
    args = ap.parse_args()
    runs = [run(HERE / f"seed{s}", s, None) for s in args.seeds]
    if not args.no_extra:
        runs.append(run(HERE / "seed0-hybrid-bw", 0, "linear,hybrid,nn,hybrid-bw"))
    summary = {"runs": runs, "reference_deflection_over_n1_peak": reference_deflections()}
    (HERE / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    first = json.loads((HERE / f"seed{args.seeds[0]}" / "report.json").read_text())
    (HERE / "table.md").write_text(compact_table(first) + "\n")
    for r in runs:
        f, u = r["finding_all_four"], r["finding_upper_only"]
        print(f"seed {r['seed']} {','.join(r['kinds'])}: all four {f['status']} "
              f"(worst {f['worst']['peak_pct']:.1f} %), upper only {u['status']} "
              f"(worst {u['worst']['peak_pct']:.1f} %), {r['wall_time_s']:.0f} s")  # fmt: skip


if __name__ == "__main__":
    main()
