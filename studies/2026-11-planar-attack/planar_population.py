"""A population of planar networks: how many of the MIMO
networks that pass single-axis tests does the attack across axes break?

``python studies/2026-11-planar-attack/planar_population.py --seeds 4`` trains ``--seeds`` networks of each kind
(``nn``, ``nn-axis``, ``hybrid``; each on its own seed's 60 s record of independent random
motion at n = 1, default options, as ``scripts/planar_benchmark.py``), then for each:

1. the single-axis test: random search over ``one_axis`` (the one-axis rig families, one
   coordinate at a time, the others at rest), ``--single-budget`` evaluations; it passes when
   no profile fails in the coordinate it drives (a single-axis rig measures that one; a
   failure in a coordinate at rest is counted apart, as cross-axis);
2. the attack across axes: random search over the planar families, ``--budget`` evaluations.

Prints, per kind, how many passed the single-axis test and how many of those the attack broke,
with Wilson 95 % intervals (``bushenv.zoo.rates.rate``). Trained networks are kept under
``--out``/models and reused. ``bushenv zoo --env rig3`` is the study this script began: both
searchers, recipes, resumable members (docs/planar_search.md).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch

from bushenv.identify.mimo_train import fit_mimo
from bushenv.models import load_model
from bushenv.models.base import PAPER_DT
from bushenv.motions import random_independent
from bushenv.progress import Progress
from bushenv.reference.planar import PlanarRubber
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.limits import COORDS
from bushenv.search.searchers import RandomSearch
from bushenv.zoo.attack import driven_failed
from bushenv.zoo.rates import rate

KINDS = ("nn", "nn-axis", "hybrid")


def network(out: Path, kind: str, seed: int):
    path = out / "models" / f"planar-{kind}-seed{seed}.npz"
    if not path.is_file():
        q = random_independent(1.0, 60.0, PAPER_DT, seed)
        f = PlanarRubber.preset(seed=seed).simulate(q)
        fit_mimo(q, f, PAPER_DT, kind=kind, seed=seed).save(path)
    return load_model(path)


def member(model, seed: int, single_budget: int, budget: int) -> dict:
    ref = PlanarRubber.preset(measurement=False)
    with BatchEvaluator(model, ref, "rig3") as ev:
        single = RandomSearch(families=("one_axis",)).run(ev, single_budget, seed=seed)
    with BatchEvaluator(model, ref, "rig3") as ev:
        planar = RandomSearch().run(ev, budget, seed=seed)
    # a single-axis rig measures the driven coordinate only: a failure there fails the test;
    # one in a coordinate at rest is a cross-axis failure such a rig does not see
    driven = [c for c in single.failures if driven_failed(c, COORDS)]
    return {
        "seed": seed,
        "single_axis_failures": len(driven),
        "single_axis_cross_axis_failures": single.n_failures - len(driven),
        "planar_failures": planar.n_failures,
        "planar_evaluations_to_failure": (
            planar.first_failure.evaluation if planar.first_failure else None
        ),
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=4)
    p.add_argument("--budget", type=int, default=128)
    p.add_argument("--single-budget", type=int, default=128)
    p.add_argument("--out", default="runs/planar_population")
    p.add_argument("--quiet", action="store_true")
    args = p.parse_args()
    torch.set_num_threads(1)
    out = Path(args.out)
    progress = Progress(total=len(KINDS) * args.seeds, quiet=args.quiet)
    t0 = time.perf_counter()
    rows: dict[str, list[dict]] = {k: [] for k in KINDS}
    for kind in KINDS:
        for seed in range(args.seeds):
            row = member(network(out, kind, seed), seed, args.single_budget, args.budget)
            rows[kind].append(row)
            progress.update(
                progress.done + 1,
                f"{kind} seed {seed}: single-axis failures {row['single_axis_failures']}, "
                f"across axes {row['planar_failures']}",
            )
    summary = {}
    print(
        "| kind | networks | pass the single-axis test | of those, broken across axes "
        "(95 % CI) | broken across axes, all (95 % CI) | median evals to 1st failure |"
    )
    print("|---|---|---|---|---|---|")
    for kind, members in rows.items():
        passed = [m for m in members if m["single_axis_failures"] == 0]
        broken = [m for m in passed if m["planar_failures"] > 0]
        all_broken = [m for m in members if m["planar_failures"] > 0]
        r, a = rate(len(broken), len(passed)), rate(len(all_broken), len(members))
        evals = [m["planar_evaluations_to_failure"] for m in all_broken]
        summary[kind] = {"members": members, "broken_of_passed": r, "broken": a}
        print(
            f"| {kind} | {len(members)} | {len(passed)} | {len(broken)} / {len(passed)} "
            f"({r['ci95'][0]:.2f}-{r['ci95'][1]:.2f}) | {len(all_broken)} / {len(members)} "
            f"({a['ci95'][0]:.2f}-{a['ci95'][1]:.2f}) | "
            f"{np.median(evals) if evals else '-'} |"
        )
    out.mkdir(parents=True, exist_ok=True)
    (out / "population.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(f"\n{time.perf_counter() - t0:.0f} s in total; {out / 'population.json'}")


if __name__ == "__main__":
    main()
