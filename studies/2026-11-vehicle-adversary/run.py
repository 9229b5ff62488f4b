"""Rerun the study: ``bushenv vehicle --search`` on the vehicle-manoeuvres study's seed-0
bushings (linear, hybrid, nn) for search seeds 0 and 1, and once at the command's defaults
(bushings identified from scratch, default budget) for its wall time; a summary.

    python studies/2026-11-vehicle-adversary/run.py [--seeds 0 1] [--budget 256] [--no-default]

Each search goes to ``seedN/`` here (figures kept for seed 0 only); seed 0's cases also go to
``tests/vehicle/corpus/`` (the regression cases ``tests/vehicle/test_adversary_cases.py``
replays). ``summary.json`` holds,
per run and kind, the worst standard manoeuvre, the found one, the amplification, the pivot
and coordinate that carry it, the terminations per family, the wall time and the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
# relative to the repository (the command runs there): the cases name the files so
BUSHINGS = Path("studies") / "2026-11-vehicle-manoeuvres" / "seed0" / "bushings"
CORPUS = Path("tests") / "vehicle" / "corpus"


def drop_figures(out: Path) -> None:
    """Keep a run's report without its figures (the study keeps seed 0's only)."""
    from bushenv.vehicle.adversary_report import markdown

    for png in out.glob("*.png"):
        png.unlink()
    report = json.loads((out / "adversary.json").read_text())
    (out / "adversary.md").write_text(markdown(report))


def search(out: Path, seed: int, budget: int | None, files: bool, corpus: bool) -> dict:
    argv = [sys.executable, "-m", "bushenv.cli", "vehicle", "--search", "--out",
            str(out.relative_to(ROOT)),
            "--seed", str(seed)]  # fmt: skip
    if budget is not None:
        argv += ["--budget", str(budget)]
    if files:
        argv += [
            a for k in ("linear", "hybrid", "nn") for a in (f"--{k}", str(BUSHINGS / f"{k}.npz"))
        ]
    else:
        shutil.rmtree(out / "bushings", ignore_errors=True)
    if corpus:
        shutil.rmtree(ROOT / CORPUS, ignore_errors=True)
        argv += ["--corpus", str(CORPUS)]
    load_before = os.getloadavg()
    subprocess.run(argv, check=True, cwd=ROOT)
    report = json.loads((out / "adversary.json").read_text())
    kinds = {}
    for kind, k in report["kinds"].items():
        found, worst = k["found"], k["worst_standard"]
        kinds[kind] = {
            "worst_standard": worst and {x: worst[x] for x in ("kind", "d_pct",
                                                               "difference_peak_n")},
            "found": found and {x: found[x] for x in ("d_pct", "difference_peak_n",
                                                      "reference_peak_n", "searcher",
                                                      "evaluation", "params",
                                                      "outputs_peak_pct")},
            "amplification": k["amplification"],
            "carried_by": k.get("blame", {}).get("carried_by"),
            "standard_terminated": k["standard_terminated"],
            "terminations": {f: t for f, t in k["terminations"].items() if t["tried"]},
            "reference_unusable": k["reference_unusable"],
            "seconds": k["seconds"],
        }  # fmt: skip
    return {"seed": seed, "budget": report["config"]["budget"], "wall_time_s":
            report["wall_time_s"], "load_average_before": load_before,
            "load_average_after": os.getloadavg(), "kinds": kinds,
            "cases": report["cases"]}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--budget", type=int, default=256)
    ap.add_argument("--no-default", action="store_true", help="skip the default-settings run")
    args = ap.parse_args()
    runs = [search(HERE / f"seed{s}", s, args.budget, True, s == 0) for s in args.seeds]
    summary = {"searches": runs}
    if not args.no_default:
        summary["default_run"] = search(HERE / "default", 0, None, False, False)
    for out in [HERE / f"seed{s}" for s in args.seeds if s != 0] + [HERE / "default"]:
        drop_figures(out)
    (HERE / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")


if __name__ == "__main__":
    main()
