"""The vector Bouc-Wen against its per-axis kind (``yield_surface="axis"``) on unseen records.

    python studies/2026-11-planar-benchmark/planar_yield_surface.py [--seeds 0 1] [--uncoupled]

The benchmark's protocol (``planar_benchmark.py``): 60 s of independent random motion at n = 1
on the planar reference identifies both (default options); each runs free on the random
records of ``bushenv.motions``. Prints the RMS ratio per axis, mean over the seeds,
and axis / vector. ``--uncoupled``: the reference with coupling off and friction axis by axis.
"""

from __future__ import annotations

import argparse
import importlib.util
from pathlib import Path

import numpy as np

from bushenv.identify.vector_boucwen import VectorBoucWenOptions, fit_vector_boucwen
from bushenv.metrics import rms_ratio
from bushenv.models.base import PAPER_DT
from bushenv.motions import random_independent, verification_motions
from bushenv.progress import Progress

_spec = importlib.util.spec_from_file_location(
    "planar_benchmark", Path(__file__).resolve().parents[2] / "scripts" / "planar_benchmark.py"
)
_bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_bench)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--uncoupled", action="store_true")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args()
    dt = PAPER_DT
    progress = Progress(2 * len(args.seeds), quiet=args.quiet, label="yield surfaces")
    rms: dict[str, dict[str, list]] = {}
    for k, seed in enumerate(args.seeds):
        q = random_independent(1.0, 60.0, dt, seed)
        f = _bench.reference(args.uncoupled, seed).simulate(q)
        for j, surface in enumerate(("vector", "axis")):
            model, _ = fit_vector_boucwen([(q, f)], dt, VectorBoucWenOptions(yield_surface=surface))
            progress.update(2 * k + j + 1, f"seed {seed}: {surface} fitted")
            for name, qt in verification_motions(dt, seed).items():
                if not name.startswith("random"):
                    continue
                ft = _bench.reference(args.uncoupled, seed + 100).simulate(qt)
                pred = model.simulate(qt)
                row = [100 * rms_ratio(ft[:, i], pred[:, i]) for i in range(3)]
                rms.setdefault(name, {}).setdefault(surface, []).append(row)
    progress.update(None, "done", force=True)
    print("| record | vector | axis | axis / vector |\n|---|---|---|---|")
    for name, by in rms.items():
        v, a = np.mean(by["vector"], axis=0), np.mean(by["axis"], axis=0)
        cells = [" / ".join(f"{x:.{d}f}" for x in arr) for arr, d in ((v, 1), (a, 1), (a / v, 2))]
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
