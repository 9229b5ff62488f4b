"""``bushenv vehicle-transfer``: the error-transfer map of HalfCar-v0's arm bushings (every
pivot x coordinate x kind of model error at one component-level size, under the standard
manoeuvres of ``bushenv vehicle``) and the predictor from component-level to vehicle-level
errors, checked on cases it was not built from.

    bushenv vehicle-transfer --out DIR [--size-pct 10] [--combinations 16] [--held 2] [--order 2]

Writes DIR/transfer.md (the findings first), DIR/transfer.json, DIR/transfer_map.csv (every
component, manoeuvre and output), DIR/transfer_predictor.npz (the predictor:
``bushenv.vehicle.transfer_predict.TransferPredictor.load``), DIR/transfer_map.png (the heat
map) and DIR/transfer_check.png (predicted against measured on the held-out cases).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from bushenv.commands.vehicle import add_manoeuvre_arguments

EXAMPLE = "bushenv vehicle-transfer --out runs/transfer"


def _multiples(text: str) -> list[float]:
    try:
        return [float(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"comma-separated numbers, got {text!r}") from None


def add_arguments(p: argparse.ArgumentParser) -> None:
    from bushenv.vehicle.transfer import HELD_MULTIPLES

    p.add_argument("--out", required=True, metavar="DIR", help="folder for the report")
    p.add_argument(
        "--size-pct",
        type=float,
        default=10.0,
        metavar="PCT",
        help="component error of the map: RMS force error ratio on the bench's random motion "
        "at n = 1, %% of the erring coordinate's force",
    )
    p.add_argument(
        "--combinations",
        type=int,
        default=16,
        metavar="N",
        help="held-out combinations of several errors (sizes 0.5-1.5x, either sign) the "
        "predictor is checked on",
    )
    p.add_argument(
        "--held",
        type=_multiples,
        default=list(HELD_MULTIPLES),
        metavar="LIST",
        help="every single error also run at these multiples of --size-pct, held out of the "
        "predictor (default: 2; a list with a minus first is written --held=-0.5,2)",
    )
    p.add_argument(
        "--order",
        type=int,
        choices=(1, 2),
        default=2,
        help="the predictor: 1, first-order superposition of the +size runs; 2, also the "
        "-size runs (each error's own curvature; 48 more cars)",
    )
    add_manoeuvre_arguments(p)
    p.add_argument(
        "--seed", type=int, default=0, help="the ISO 8608 road's and the combinations' draws"
    )
    p.add_argument("--no-plots", action="store_true", help="no figures")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def run(args: argparse.Namespace) -> int:
    from bushenv.cli import CliError
    from bushenv.persist import write_json, write_text
    from bushenv.progress import Progress, format_seconds
    from bushenv.rigs.halfcar_params import ENV_ID
    from bushenv.rigs.specs import spec_kwargs
    from bushenv.vehicle.transfer import TransferConfig, run_transfer
    from bushenv.vehicle.transfer_errors import TransferInputError
    from bushenv.vehicle.transfer_report import findings, map_csv, markdown, plot_check, plot_map

    t0 = time.perf_counter()
    if args.duration_s is not None and not args.duration_s > 0.1:
        raise CliError(f"--duration-s must be > 0.1 s, got {args.duration_s}")
    dt = float(spec_kwargs(ENV_ID, {})["dt_s"])
    config = TransferConfig(dt, args.size_pct, tuple(args.manoeuvres), args.duration_s,
                            args.seed, args.combinations, tuple(args.held),
                            args.order)  # fmt: skip
    try:
        config.check()
    except TransferInputError as exc:
        raise CliError(
            str(exc)
            .replace("size_pct", "--size-pct")
            .replace("combinations", "--combinations")
            .replace("held multiple", "--held")
        ) from None
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    progress = Progress(quiet=args.quiet, label="transfer")
    report, predictor = run_transfer(config, progress)
    found = findings(report)
    report["findings"] = found
    predictor.save(out / "transfer_predictor.npz")
    write_text(out / "transfer_map.csv", map_csv(report))
    figures = []
    if not args.no_plots:
        figures = [str(plot_map(report, out / "transfer_map.png")),
                   str(plot_check(report, out / "transfer_check.png"))]  # fmt: skip
    report["figures"] = [Path(f).name for f in figures]
    report["wall_time_s"] = time.perf_counter() - t0
    write_json(out / "transfer.json", report)
    write_text(out / "transfer.md", markdown(report, found, figures))
    progress.say(f"done in {format_seconds(report['wall_time_s'])}")
    print(markdown(report, found, []).split("\n## What")[0].split("\n## The map")[0].strip())
    print(f"report: {out / 'transfer.md'}, {out / 'transfer.json'}")
    return 0
