"""The planar attack on trained MIMO networks: ``python studies/2026-11-planar-attack/planar_attack.py``.

Trains the MIMO NARX network (``nn``), the seeds' per-axis kind (``nn-axis``) and the MIMO
hybrid on 60 s of independent random motion on all axes at n = 1 (as
``scripts/planar_benchmark.py``, seed 0, default options), saves them under ``--out``/models
and runs ``bushenv attack --env rig3`` on each (random and CMA-ES over ``any3``, ``--budget``
evaluations each). Prints one table: evaluations to the first failure, failures per family and
per axis, the linear control's rechecks. Numbers in studies/2026-11-planar-attack/README.md.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import torch

from bushenv.identify.mimo_options import NOISY_FEEDBACK_TRAINING, MimoOptions
from bushenv.identify.mimo_train import fit_mimo
from bushenv.models.base import PAPER_DT
from bushenv.motions import random_independent
from bushenv.progress import Progress
from bushenv.reference.planar import PlanarRubber
from bushenv.search.campaign import run_attack
from bushenv.search.campaign_config import CampaignConfig

KINDS = ("nn", "nn-axis", "hybrid")


def train(out: Path, seed: int, progress: Progress, training: str = "plain") -> dict[str, Path]:
    dt = PAPER_DT
    q = random_independent(1.0, 60.0, dt, seed)
    f = PlanarRubber.preset(seed=seed).simulate(q)
    paths = {}
    for kind in KINDS:
        noisy = kind == "hybrid" and training == "noisy-feedback"
        tag = "-noisy-feedback" if noisy else ""
        path = out / "models" / f"planar-{kind}{tag}-seed{seed}.npz"
        if not path.is_file():
            t0 = time.perf_counter()
            opts = MimoOptions(**NOISY_FEEDBACK_TRAINING) if noisy else None
            fit_mimo(q, f, dt, kind=kind, options=opts, seed=seed).save(path)
            progress.say(f"{kind} trained in {time.perf_counter() - t0:.0f} s")
        paths[kind] = path
    return paths


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--budget", type=int, default=128)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--training", choices=("plain", "noisy-feedback"), default="plain",
        help="the hybrid's training (bushenv fit --training)",
    )  # fmt: skip
    p.add_argument("--out", default="runs/planar_attack")
    p.add_argument("--quiet", action="store_true")
    args = p.parse_args()
    torch.set_num_threads(1)
    out = Path(args.out)
    progress = Progress(quiet=args.quiet)
    t0 = time.perf_counter()
    paths = train(out, args.seed, progress, args.training)
    rows = {}
    for kind, path in paths.items():
        config = CampaignConfig(
            model=str(path),
            reference="rubber",  # the coupled reference the networks were trained on
            budget=args.budget,
            target="rig3",
            seed=args.seed,
            out=out / kind,
            force=True,
            max_shrink=1,
            shrink_budget=100,
            threads=1,
        )
        one = Progress(quiet=args.quiet, label=kind)
        rows[kind] = run_attack(config, one).report
    print(
        "| model | searcher | failures / evals | in an axis at rest | evals to 1st failure |"
        " 1st: family (axis) | failures by family | by axis | control flagged |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for kind, rep in rows.items():
        ctrl = rep["recheck"].get("linear", {"diverged": 0})
        profiles = rep["recheck"].get("profiles", 0)
        target = next(k for k, m in rep["models"].items() if m["role"] == "target")
        for name, s in rep["models"][target]["searchers"].items():
            ff = s.get("first_failure")
            v = (ff or {}).get("verdict", {})
            first = f"{ff['family']} ({v.get('axis')}, {v.get('first_criterion')})" if ff else "-"
            print(
                f"| {kind} | {name} | {s['n_failures']} / {s['evaluations']} | "
                f"{s['failures']['in_a_coordinate_at_rest']} | "
                f"{s['evaluations_to_failure'] or '-'} | {first} | "
                f"{json.dumps(s['failures']['by_family'])} | "
                f"{json.dumps(s['failures']['by_axis'])} | "
                f"{ctrl['diverged']} of {profiles} |"
            )
    for kind, rep in rows.items():
        for k in rep["shrunk"]:
            sh = k["shrink"]
            print(
                f"{kind}: shrunk {k['family']} failure ({k.get('axis')}): "
                f"moving {k.get('moving')}, segments {sh['original']['segments']} -> "
                f"{sh['final']['segments']}, samples {sh['original']['samples']} -> "
                f"{sh['final']['samples']}"
            )
    print(f"\n{time.perf_counter() - t0:.0f} s in total")


if __name__ == "__main__":
    main()
