"""``bushenv vehicle``: the standard manoeuvres in HalfCar-v0 with linear, hybrid and network
bushings in all four arm pivots against the reference bushing; the table of vehicle-level
differences beside the bushings' component-level error, and seed 000's "almost identical"
finding judged.

    bushenv vehicle --out DIR [--kinds linear,hybrid,nn] [--hybrid FILE] [--nn FILE]
    bushenv vehicle --search --out DIR [--budget N] [--searchers random,cma] [--corpus DIR]

Writes DIR/report.json, DIR/report.md (the finding first) and DIR/<manoeuvre>.png; bushings
not given as files are identified on the coupled reference's records and kept in
DIR/bushings/ (a rerun with the same seed and budget reuses them).

With ``--search`` the adversary runs instead (``bushenv/vehicle/adversary.py``): per bushing
kind, the searchers look within the standards' bounds for the manoeuvre with the largest
wheel-load difference to the reference car; DIR/adversary.json, DIR/adversary.md,
DIR/adversary-*.png and the finds as regression cases in DIR/cases/ (and ``--corpus``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from bushenv.models import names_for
from bushenv.persist import write_json, write_text
from bushenv.progress import Progress, format_seconds

EXAMPLE = "bushenv vehicle --out runs/vehicle"
SEARCH_BUDGET = 96  # runs per searcher and kind: 185 s of search for three kinds (load 12)


def _names(text: str) -> list[str]:
    return [t.strip() for t in text.split(",") if t.strip()]


def add_manoeuvre_arguments(p: argparse.ArgumentParser) -> None:
    """--manoeuvres and --duration-s, as every vehicle command takes them."""
    from bushenv.vehicle.manoeuvres import NAMES

    p.add_argument(
        "--manoeuvres",
        type=_names,
        default=list(NAMES),
        metavar="LIST",
        help=f"comma-separated, of: {', '.join(NAMES)} (default: all)",
    )
    p.add_argument(
        "--duration-s",
        type=float,
        default=None,
        metavar="S",
        help="every manoeuvre this long (default: each its own, 3-7.7 s)",
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    from bushenv.vehicle.bushings import DEFAULT_KINDS
    from bushenv.vehicle.study import IDENTICAL_PCT

    p.add_argument("--out", required=True, metavar="DIR", help="folder for the report")
    add_manoeuvre_arguments(p)
    p.add_argument(
        "--kinds",
        type=_names,
        default=list(DEFAULT_KINDS),
        metavar="LIST",
        help=f"bushing kinds in the model cars, of: "
        f"{', '.join(names_for(3, fittable=True))} (default: "
        f"{','.join(DEFAULT_KINDS)})",
    )
    for kind in names_for(3, fittable=True):
        p.add_argument(
            f"--{kind}",
            dest=f"file_{kind.replace('-', '_')}",
            metavar="FILE",
            default=None,
            help=f"a three-axis {kind} model file instead of identifying one",
        )
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        help="identification seed (records, noise, network initialisation) and the ISO 8608 road's",
    )
    p.add_argument(
        "--identification-s",
        type=float,
        default=40.0,
        metavar="S",
        help="seconds of each random identification record (the coupled sets: half)",
    )
    p.add_argument(
        "--identical-pct",
        type=float,
        default=IDENTICAL_PCT,
        metavar="PCT",
        help="'almost identical': the hybrid car within this %% of the linear car's peak",
    )
    p.add_argument(
        "--search",
        action="store_true",
        help="run the adversary instead of the comparison: search the standards' bounds for "
        "the manoeuvre with the largest wheel-load difference to the reference car",
    )
    p.add_argument(
        "--budget",
        type=int,
        default=None,
        metavar="N",
        help=f"with --search: car runs per searcher per bushing kind (default {SEARCH_BUDGET})",
    )
    p.add_argument(
        "--searchers",
        type=_names,
        default=["random", "cma"],
        metavar="LIST",
        help="with --search: comma-separated, of random, cma (default: both)",
    )
    p.add_argument(
        "--corpus",
        default=None,
        metavar="DIR",
        help="with --search: also keep the found manoeuvres as cases in this corpus folder",
    )
    p.add_argument("--no-plots", action="store_true", help="no figures")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def _shown(entry: dict, out: Path) -> dict:
    """A bushing's entry with its file relative to the report's folder when inside it."""
    path = Path(entry["file"])
    try:
        return {**entry, "file": str(path.resolve().relative_to(out.resolve()))}
    except ValueError:
        return entry


def run(args: argparse.Namespace) -> int:
    from bushenv.cli import CliError
    from bushenv.rigs.halfcar_params import ENV_ID, REFERENCE
    from bushenv.rigs.specs import spec_kwargs
    from bushenv.vehicle.bushings import Recipe, check_kinds, vehicle_bushings
    from bushenv.vehicle.manoeuvres import NAMES, standard_manoeuvres
    from bushenv.vehicle.report import markdown, plot_manoeuvre
    from bushenv.vehicle.study import REFERENCE_CAR, UPPER_ONLY, run_vehicle

    t0 = time.perf_counter()
    if args.duration_s is not None and not args.duration_s > 0.1:
        raise CliError(f"--duration-s must be > 0.1 s, got {args.duration_s}")
    if not args.identification_s >= 5:
        raise CliError(f"--identification-s must be >= 5 s, got {args.identification_s}")
    kinds = check_kinds(args.kinds)
    if not args.search and (args.corpus is not None or args.budget is not None):
        raise CliError("--budget and --corpus are options of --search; add --search")
    if args.search and (args.duration_s is not None or list(args.manoeuvres) != list(NAMES)):
        raise CliError(
            "--manoeuvres and --duration-s choose the comparison's manoeuvres; "
            "--search judges its finds against all seven standard ones as they are"
        )
    files = {k: getattr(args, f"file_{k.replace('-', '_')}") for k in names_for(3, fittable=True)}
    files = {k: f for k, f in files.items() if f is not None}
    unused = sorted(set(files) - set(kinds))
    if unused:
        raise CliError(f"--{unused[0]} FILE given but {unused[0]} is not in --kinds "
                       f"{','.join(kinds)}")  # fmt: skip
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    progress = Progress(quiet=args.quiet, label="vehicle")
    dt = float(spec_kwargs(ENV_ID, {})["dt_s"])
    manoeuvres = standard_manoeuvres(dt, args.seed, args.manoeuvres, args.duration_s)
    recipe = Recipe(dt, args.seed, args.identification_s)
    bushings = vehicle_bushings(kinds, recipe, out / "bushings", files, say=progress.say)
    if args.search:
        return _search(args, bushings, out, progress, t0)
    report, runs = run_vehicle(
        manoeuvres, {k: b.model for k, b in bushings.items()}, REFERENCE, progress,
        args.identical_pct,
    )  # fmt: skip
    report["bushings"] = {k: _shown(b.describe(), out) for k, b in bushings.items()}
    if UPPER_ONLY in report["kinds"]:
        report["bushings"][UPPER_ONLY] = {
            "kind": UPPER_ONLY, "model": "linear / hybrid / linear / hybrid", "file": "-",
            "sha256": "-", "how": "seed 000 §5.3's car: the hybrid above in the upper arm "
            "pivots, the linear above in the lower ones",
        }  # fmt: skip
    report["settings"] = {"seed": args.seed, "identification_s": args.identification_s,
                          "duration_s": args.duration_s, "manoeuvres": list(args.manoeuvres),
                          "kinds": list(kinds)}  # fmt: skip
    figures = []
    if not args.no_plots:
        for m in manoeuvres:
            path = out / f"{m.name}.png"
            cars = [*report["kinds"], REFERENCE_CAR]
            plot_manoeuvre(m, {k: runs[(m.name, k)] for k in cars if (m.name, k) in runs}, path)
            figures.append(str(path))
    report["figures"] = [Path(f).name for f in figures]
    report["wall_time_s"] = time.perf_counter() - t0
    write_json(out / "report.json", report)
    write_text(out / "report.md", markdown(report, figures))
    progress.say(f"done in {format_seconds(report['wall_time_s'])}")
    text = markdown(report).split("\n## ")[0]
    print(text.strip())
    print(f"report: {out / 'report.md'}, {out / 'report.json'}", file=sys.stdout)
    return 0


def _search(args: argparse.Namespace, bushings: dict, out: Path, progress, t0: float) -> int:
    """``--search``: the adversary, its report, figures and cases."""
    from bushenv.rigs.common import resolve_model
    from bushenv.rigs.halfcar_params import ENV_ID
    from bushenv.vehicle.adversary import REFERENCE, AdversaryConfig, run_adversary
    from bushenv.vehicle.adversary_cases import save_cases
    from bushenv.vehicle.adversary_report import markdown, plot_found, plot_search

    budget = SEARCH_BUDGET if args.budget is None else args.budget
    config = AdversaryConfig(tuple(args.searchers), budget, args.seed)
    models = {k: b.model for k, b in bushings.items()}
    report, kept = run_adversary(models, config, progress)
    report["bushings"] = {k: _shown(b.describe(), out) for k, b in bushings.items()}
    dt = next(iter(models.values())).dt
    reference = resolve_model(REFERENCE, dt=dt, coords=3, what="reference", env_id=ENV_ID)
    dirs = [out / "cases"] + ([Path(args.corpus)] if args.corpus else [])
    report["cases"] = save_cases(kept, bushings, reference, args.seed, dirs)
    figures = []
    if not args.no_plots:
        figures.append(str(plot_search(report, kept, out / "adversary-search.png")))
        for kind, k in kept.items():
            if k["found"] is not None:
                path = out / f"adversary-found-{kind}.png"
                figures.append(str(plot_found(kind, k, models[kind], REFERENCE, path)))
    report["figures"] = [Path(f).name for f in figures]
    report["wall_time_s"] = time.perf_counter() - t0
    write_json(out / "adversary.json", report)
    write_text(out / "adversary.md", markdown(report, figures))
    progress.say(f"done in {format_seconds(report['wall_time_s'])}")
    print(markdown(report).split("\n## ")[0].strip())
    print(f"report: {out / 'adversary.md'}, {out / 'adversary.json'}; cases: {out / 'cases'}")
    return 0
