"""``bushenv zoo``: argparse in, a ``ZooConfig`` out, the population study (``zoo/study.py``)
over the number of coordinates of the ``--env``'s target (rig3: the MIMO population)."""

from __future__ import annotations

import argparse
from pathlib import Path

from bushenv.execution import get_backend
from bushenv.identify.mimo_options import HYBRID_TRAININGS
from bushenv.identify.narx_options import RECIPES
from bushenv.models.planar_narx import STRUCTURES
from bushenv.progress import Progress
from bushenv.search.matrix import parse_seeds
from bushenv.zoo.study import ENVS, ZooConfig, refuse_other_kind, run_study

EXAMPLE = (
    "bushenv zoo --recipes teacher-forcing,free-run --models nn,hybrid --seeds 0-9 "
    "--axes axial,radial --out runs/zoo\n  "
    "bushenv zoo --env rig3 --recipes teacher-forcing,free-run --models nn,hybrid --seeds 0-9 "
    "--out runs/zoo-rig3"
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    d = ZooConfig().checked()
    p.add_argument(
        "--env",
        choices=ENVS,
        default="rig",
        help="rig: one-axis NARX models per axis; rig3: MIMO planar networks, the single-axis "
        "check then the attack across axes",
    )
    p.add_argument("--recipes", default=",".join(RECIPES), help="training recipes")
    p.add_argument("--models", default=",".join(d.models), help="NARX models to train")
    p.add_argument(
        "--axes", default=None, help=f"bushing axes (default {','.join(d.axes)}; rig only)"
    )
    p.add_argument("--seeds", default="0-9", help="training and record seeds, e.g. 0-9 or 1,4")
    p.add_argument(
        "--searchers",
        default=None,
        help=f"searchers per model (default {','.join(d.searchers)}; rig3: random,cma)",
    )
    p.add_argument("--budget", type=int, default=d.budget, help="evaluations per search")
    p.add_argument(
        "--certified",
        choices=("off", "on"),
        default="off",
        help="train every model with the certified-holds loss term (bushenv fit --certified on; "
        "rig3: the planar term, identify/mimo_certified.py)",
    )
    p.add_argument(
        "--structure",
        choices=STRUCTURES,
        default="free",
        help="rig3: the planar network's weights tied by construction (bushenv fit --structure; "
        "mirror: odd in each coordinate, identify/mimo_structure.py)",
    )
    p.add_argument(
        "--training",
        choices=HYBRID_TRAININGS,
        default="plain",
        help="rig3, --models hybrid: the hybrid's training (bushenv fit --training; "
        "noisy-feedback: 3x as accurate, more than one fixed point at some holds)",
    )
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--resume", action="store_true", help="continue an interrupted study")
    p.add_argument("--workers", type=int, default=None, help="local worker processes")
    p.add_argument("--ray", action="store_true", help="run on Ray (a local instance)")
    p.add_argument("--ray-address", default=None, help="run on an existing Ray cluster")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def _names(text: str) -> tuple[str, ...]:
    return tuple(n.strip() for n in text.split(",") if n.strip())


def config_from(args: argparse.Namespace) -> ZooConfig:
    """The study the arguments describe (checked); C is the env's target's."""
    env = getattr(args, "env", "rig")
    options = {
        **({"certified": "on"} if args.certified == "on" else {}),
        **_given(args, "structure", "free"),
        **_given(args, "training", "plain"),
    }
    return ZooConfig(
        env=env,
        recipes=_names(args.recipes),
        models=_names(args.models),
        axes=_names(args.axes) if args.axes is not None else None,
        seeds=tuple(parse_seeds(args.seeds)),
        searchers=_names(args.searchers) if args.searchers is not None else None,
        budget=args.budget,
        out=Path(args.out),
        resume=args.resume,
        train_options=options,
    ).checked()


def _given(args: argparse.Namespace, name: str, default: str) -> dict:
    """A training option given on the command line (none for its default)."""
    value = getattr(args, name, default)
    return {} if value == default else {name: value}


def run(args: argparse.Namespace) -> int:
    config = config_from(args)
    backend = get_backend(
        "ray" if (args.ray or args.ray_address) else "local",
        workers=args.workers,
        address=args.ray_address,
    )
    if config.resume:
        refuse_other_kind(config.out / "cells.jsonl", config.coords)
    run_study(config, backend, Progress(quiet=args.quiet))
    print((config.out / "summary.md").read_text())
    made = ("cells.jsonl", "summary.json", "summary.md", "accuracy_vs_robustness.png")
    written = [name for name in made if (config.out / name).is_file()]  # the plot: one axis
    print(f"wrote {config.out}/" + ", ".join(written))
    return 0
