"""``bushenv attack``: the command; argparse in, a ``CampaignConfig`` out, the table printed.

    bushenv attack --model nn --budget 256 [--axis axial] [--env rig|quartercar|rig3]
                   [--searchers random,cma,ppo,sac] [--seed S] [--out DIR] [--save]

One attack for a bushing of any number of coordinates: ``--env rig3`` searches a three-axis
model (a three-axis .npz file, or a registered kind with a three-axis preset) in the limits of
the user's card, with the same stages, report and resume as one axis.

Outputs in ``DIR`` (default ``runs/attack``): ``report.json`` (see ``campaign_report.py``),
``plots/*.png``, ``failures/*.npz`` (the profiles each search found), ``cases/*.json`` (the
shrunk failures in corpus format). An existing report is refused unless ``--resume`` (finish
what is missing; every step is seeded, so the result is the same) or ``--force``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bushenv.models import AXES
from bushenv.progress import Progress
from bushenv.search.campaign import CampaignConfig, run_attack
from bushenv.search.campaign_report import format_table
from bushenv.search.case_file import DEFAULT_CORPUS
from bushenv.search.searchers import SEARCHERS
from bushenv.search.targets import TARGETS

EXAMPLE = "bushenv attack --model nn --budget 256 --searchers random,cma,ppo,sac --out runs/attack"


def add_arguments(p: argparse.ArgumentParser) -> None:
    d = CampaignConfig()
    p.add_argument(
        "--model",
        default=d.model,
        help="model under attack: name or .npz file (default: nn-paper, the papers' NARX "
        "network as seed 000 trained it; nn is the certified one; with --env rig3 a three-axis "
        "model: a registered kind with a three-axis preset or a three-axis .npz file)",
    )
    p.add_argument("--budget", type=int, default=d.budget, help="model evaluations per search")
    p.add_argument("--rl-budget", type=int, default=d.rl_budget, help="cap on RL episodes")
    p.add_argument("--axis", default=d.axis, choices=AXES)
    p.add_argument("--env", default=d.target, choices=TARGETS.names(), help="where to search")
    defaults = "; ".join(f"{n}: {','.join(t.default_searchers)}" for n, t in TARGETS.items())
    p.add_argument(
        "--searchers",
        default=None,
        help=f"comma list of {','.join(SEARCHERS.names())} (default per env: {defaults})",
    )
    p.add_argument("--seed", type=int, default=d.seed)
    p.add_argument("--out", default=str(d.out), help="output directory")
    p.add_argument(
        "--reference",
        default=None,
        help="the bushing the verdicts compare with: a registered name, a model file or "
        "'none' (default: rubber for a registered --model; none for a model file: then only "
        "the criteria that need no reference run). It is vetted before it judges",
    )
    p.add_argument(
        "--trust-reference",
        action="store_true",
        help="judge with a reference that failed its vetting; every verdict is then marked "
        "as judged by an unvetted reference",
    )
    p.add_argument(
        "--hybrid",
        default=None,
        help="name or file rechecked on the failures and attacked (default: the shipped hybrid "
        "with the built-in rubber; none for your bushing)",
    )
    p.add_argument(
        "--control",
        default=None,
        help="name or file that must stay clean (default: the Table-1 linear model with the "
        "built-in rubber; for your bushing a linear model fitted to the reference)",
    )
    p.add_argument(
        "--stroke-mm",
        type=float,
        default=None,
        help="the bushing's stroke, +-mm (with --env rig3: axial and radial)",
    )
    p.add_argument(
        "--rotation-mrad",
        type=float,
        default=None,
        help="with --env rig3: the rotation's range, +-mrad (default: 1.5 x the card's "
        "records', else the machine's)",
    )
    p.add_argument(
        "--max-velocity", type=float, default=None, help="the bushing's velocity limit, m/s"
    )
    p.add_argument(
        "--force-floor-n", type=float, default=None, help="verdicts' force resolution, N"
    )
    p.add_argument(
        "--force-scale-n",
        type=float,
        default=None,
        help="the bushing's typical peak force, N (scales the verdicts without a reference)",
    )
    p.add_argument("--max-shrink", type=int, default=d.max_shrink, help="failures to shrink")
    p.add_argument("--shrink-budget", type=int, default=d.shrink_budget, help="evals per shrink")
    p.add_argument("--threads", type=int, default=None, help="evaluation threads (default: cores)")
    p.add_argument("--save", action="store_true", help="add shrunk failures to the corpus")
    p.add_argument("--corpus", default=str(DEFAULT_CORPUS), help="corpus directory")
    p.add_argument("--resume", action="store_true", help="continue an interrupted campaign")
    p.add_argument("--force", action="store_true", help="overwrite an existing report/cases")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    p.add_argument(
        "--paper-step",
        action="store_true",
        help="also judge the papers' 4 mm step held 10 s (seed 000 §5.2) and keep it as a case",
    )
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def config_from(args: argparse.Namespace) -> CampaignConfig:
    """The campaign the arguments describe."""
    searchers = None
    if args.searchers is not None:
        searchers = tuple(s.strip() for s in args.searchers.split(","))
    return CampaignConfig(
        model=args.model,
        budget=args.budget,
        rl_budget=args.rl_budget,
        axis=args.axis,
        target=args.env,
        searchers=searchers,
        seed=args.seed,
        out=Path(args.out),
        reference=args.reference,
        hybrid=args.hybrid,
        control=args.control,
        stroke_mm=args.stroke_mm,
        max_velocity_m_per_s=args.max_velocity,
        rotation_mrad=args.rotation_mrad,
        force_floor_n=args.force_floor_n,
        force_scale_n=args.force_scale_n,
        max_shrink=args.max_shrink,
        shrink_budget=args.shrink_budget,
        threads=args.threads,
        save=args.save,
        corpus=Path(args.corpus),
        resume=args.resume,
        force=args.force,
        plots=not args.no_plots,
        paper_step=args.paper_step,
        trust_reference=args.trust_reference,
    )


def run(args: argparse.Namespace) -> int:
    import torch

    torch.set_num_threads(1)
    progress = Progress(quiet=args.quiet)
    command = getattr(TARGETS[args.env], "command", "")
    if command:  # a target with its own command (the half car: four bushings, not one)
        from bushenv.cli import CliError

        raise CliError(f"--env {args.env} is searched by `{command}`, not by bushenv attack")
    if args.rotation_mrad is not None and not TARGETS[args.env].coords:
        from bushenv.cli import CliError

        raise CliError(
            f"--rotation-mrad is the rotation's range of a three-axis bushing; --env {args.env} "
            "has no rotation (add --env rig3, or drop it)"
        )
    attacked = run_attack(config_from(args), progress)
    report = attacked.report
    print(format_table(report, attacked.target_key))
    print(f"\nreport: {attacked.report_path}  ({report['seconds']:.1f} s in total)")
    if attacked.control_flagged:
        control = report.get("control") or {}
        progress.say(
            f"WARNING: the control ({control.get('label', attacked.control_key)}) was flagged: "
            "the divergence criteria or the coupling are at fault, not only the model under "
            "attack"
        )
    return 0
