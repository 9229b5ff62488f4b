"""``bushenv reproduce``: argparse in, ``bushenv.reproduce.reproduce`` called, tables printed."""

from __future__ import annotations

import argparse
from pathlib import Path

from bushenv.models import AXES
from bushenv.programmes import IDENTIFICATIONS
from bushenv.progress import Progress
from bushenv.reproduce import coupled_table, reproduce
from bushenv.reproduce_report import format_coupled, format_tables

EXAMPLE = "bushenv reproduce --out runs/reproduce"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", required=True, help="output folder (refused if it holds a report)")
    p.add_argument("--axes", default="axial,radial", help="comma list of axes")
    p.add_argument("--seed", type=int, default=0, help="seed for records and training")
    p.add_argument("--identification-s", type=float, default=40.0, help="n = 1 record length, s")
    p.add_argument(
        "--verification-s",
        type=float,
        default=20.0,
        help="length of each unseen record (n = 1 and n = 1.5), s",
    )
    p.add_argument(
        "--shipped",
        action="store_true",
        help="use the trained models shipped in the package instead of identifying anew",
    )
    p.add_argument(
        "--planar",
        choices=("off", "add", "only"),
        default="off",
        help="the 3-axis table beside seed 000 Table 3 (planar models on unseen coupled "
        "records, DIR/planar.json and planar.md): add it to the papers' tables, or run only it",
    )
    p.add_argument(
        "--planar-identification",
        choices=tuple(IDENTIFICATIONS),
        default="programme",
        help="the 3-axis table's identification records: "
        + "; ".join(f"{k}: {v}" for k, v in IDENTIFICATIONS.items()),
    )
    p.add_argument("--force", action="store_true", help="overwrite an existing report in --out")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def run(args: argparse.Namespace) -> int:
    from bushenv.cli import CliError

    out = Path(args.out)
    written = ["report.json"] if args.planar != "only" else []
    written += ["planar.json"] if args.planar != "off" else []
    for name in written:
        if (out / name).exists() and not args.force:
            raise CliError(f"{out}/{name} exists; pass --force to overwrite it")
    if args.seed < 0:
        raise CliError(f"--seed must be >= 0, got {args.seed}")
    for name in ("identification_s", "verification_s"):
        if not getattr(args, name) >= 6.44:
            flag = "--" + name.replace("_", "-")
            raise CliError(f"{flag} must be at least 6.44 s, got {getattr(args, name)}")
    axes = [a.strip() for a in args.axes.split(",") if a.strip()]
    for a in axes:
        if a not in AXES:
            raise CliError(f"unknown axis {a!r}; choose from {list(AXES)}")
    out.mkdir(parents=True, exist_ok=True)
    progress = Progress(quiet=args.quiet)
    if args.planar != "only":
        report = reproduce(
            out, axes, args.seed, args.identification_s, args.verification_s, args.shipped, progress
        )
        print(format_tables(report))
        print(f"\nwrote {out / 'report.json'}, {out / 'report.md'} and plots")
    if args.planar != "off":
        _planar(out, args, progress)
    return 0


def _planar(out: Path, args: argparse.Namespace, progress: Progress) -> None:
    from bushenv.models.base import PAPER_DT
    from bushenv.persist import json_text, write_text

    report = coupled_table(
        args.seed,
        args.identification_s,
        args.verification_s,
        PAPER_DT,
        progress,
        identification=args.planar_identification,
    )
    text = format_coupled(report)
    write_text(out / "planar.json", json_text(report, indent=2))
    write_text(out / "planar.md", "# The 3-axis table\n\n```\n" + text + "\n```\n")
    print(("\n" if args.planar == "add" else "") + text)
    print(f"\nwrote {out / 'planar.json'}, {out / 'planar.md'}")
