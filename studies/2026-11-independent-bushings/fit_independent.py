"""Held-out accuracy of every fittable model on bushings bushenv was not tuned on.

``python studies/2026-11-independent-bushings/fit_independent.py --dir runs/independent`` runs ``bushenv fit TRAIN --model M
--validate HELD`` (a fresh process each, default options, seed 0) on the records of
``studies/2026-11-independent-bushings/independent_bushings.py`` (written first if missing) and on the reference rubber's
radial records of ``bushenv reproduce`` (seed 0: 40 s at n = 1, held out the unseen 20 s n = 1
record), and prints one markdown table: the held-out free-run RMS ratio, %, per bushing and
model, the NN over the hybrid, and each fit's wall time. studies/2026-11-independent-bushings/README.md shows the table.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

SCRIPTS = Path(__file__).resolve().parent
MODELS = ("linear", "nn", "hybrid", "boucwen")
BUSHINGS = ("reference-radial", "stiff-cubic", "soft-prony", "berg")


def records(folder: Path) -> None:
    """The independent records (the generator script) and the reference's, if missing."""
    if not (folder / "berg_held.csv").is_file():
        subprocess.run(
            [sys.executable, str(SCRIPTS / "independent_bushings.py"), "--out", str(folder)],
            check=True,
        )
    if not (folder / "reference-radial_held.csv").is_file():
        from bushenv.records import save_csv
        from bushenv.reproduce import _records

        train, same, _ = _records("radial", 0, 40.0, 20.0)
        save_csv(train, folder / "reference-radial_train.csv", overwrite=True)
        save_csv(same, folder / "reference-radial_held.csv", overwrite=True)


def fit_one(folder: Path, tag: str, bushing: str, model: str, extra: list[str]) -> dict:
    """Run one ``bushenv fit``; its card's held-out metrics and the command's wall time."""
    out = folder / tag / f"{bushing}-{model}.npz"
    out.parent.mkdir(parents=True, exist_ok=True)
    argv = [sys.executable, "-m", "bushenv.cli", "fit", str(folder / f"{bushing}_train.csv")]
    argv += ["--model", model, "--validate", str(folder / f"{bushing}_held.csv")]
    argv += ["--out", str(out), "--force", "--no-plots", "--quiet", *extra]
    t0 = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)}: {done.stderr[-800:]}")
    card = json.loads(out.with_name(out.stem + ".card.json").read_text())
    held = next(r for r in card["records"] if r["role"] == "held-out")
    train = next(r for r in card["records"] if r["role"] == "train")
    return {
        "held": 100.0 * held["metrics"]["rms_ratio"],
        "train": 100.0 * train["metrics"]["rms_ratio"],
        "wall_s": wall,
        "stopped": card["source"].get("stopped"),
        "stdout": done.stdout,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--dir", default="runs/independent", help="records and fitted models")
    p.add_argument("--tag", default="now", help="subfolder of the fitted models")
    p.add_argument("--models", default=",".join(MODELS))
    p.add_argument("--bushings", default=",".join(BUSHINGS))
    p.add_argument("--json", help="also write the results here")
    args = p.parse_args(argv)
    folder = Path(args.dir)
    folder.mkdir(parents=True, exist_ok=True)
    records(folder)
    models, bushings = args.models.split(","), args.bushings.split(",")
    results: dict[str, dict[str, dict]] = {}
    for b in bushings:
        for m in models:
            r = fit_one(folder, args.tag, b, m, [])
            results.setdefault(b, {})[m] = r
            print(
                f"{b:17s} {m:8s} held-out {r['held']:6.2f} %  train {r['train']:6.2f} %  "
                f"{r['wall_s']:6.1f} s  {r['stopped'] or ''}",
                file=sys.stderr,
                flush=True,
            )
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    head = " | ".join(f"{m} %" for m in models)
    print(f"| bushing | {head} | nn / hybrid | fit wall s ({', '.join(models)}) |")
    print("|---|" + "---:|" * len(models) + "---:|---|")
    for b, row in results.items():
        ratio = row["nn"]["held"] / row["hybrid"]["held"] if {"nn", "hybrid"} <= set(row) else None
        cells = " | ".join(f"{row[m]['held']:.2f}" for m in models)
        walls = ", ".join(f"{row[m]['wall_s']:.0f}" for m in models)
        print(f"| {b} | {cells} | {'' if ratio is None else f'{ratio:.2f}'} | {walls} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
