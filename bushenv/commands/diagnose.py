"""``bushenv diagnose``: a baseline's sim-to-real gap, where it lies, which effect closes it.

    bushenv diagnose TRAIN_CSV TEST_CSV [TEST_CSV ...] --out DIR [--train CSV ...]
                     [--cross | --held-out] [--run-order CSV]

Every record is used: each record, TRAIN or TEST, is judged by a fit on all the others (the
default with the linear baseline, ``--cross``); ``--held-out`` fits on TRAIN only and judges
the TESTs. ``--run-order`` gives the order the rig ran the records in and the rests between
(``bushenv.diagnose.session``): a heat is carried from record to record. Writes

- ``DIR/report.json``: effect named, ranking, pairs, unexplained share, shift warnings, where
  the gap lies, parameters (docs/diagnose.md)
- ``DIR/report.md`` with the plots ``DIR/*.png``
- ``DIR/predictions/<file-stem>.csv`` per judged record:
  time,force_measured,force_baseline,force_augmented (the named model's prediction)

Three-axis records (header ``time,displacement_axial,displacement_radial,rotation,
force_axial,force_radial,moment``) are diagnosed per coordinate against the linear three-axis
baseline: which coordinate carries the gap, which effect, how far it shrinks; ``DIR/<coordinate>/``
holds each coordinate's report. One-axis and three-axis records are not mixed.

An existing DIR is refused unless ``--force``; with ``--force`` only the files named above are
replaced, nothing else in DIR is touched. Arguments become a ``DiagnoseConfig``
(``bushenv/diagnose/report.py``); the core is ``bushenv.diagnose.fit.diagnose``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bushenv.commands.options import add_resample_option
from bushenv.diagnose.candidates import effect_names
from bushenv.diagnose.fit import baseline_names
from bushenv.diagnose.report import DiagnoseConfig, run_diagnosis
from bushenv.progress import Progress

EXAMPLE = (
    "bushenv diagnose train.csv test_random.csv test_steps.csv --out diag/ "
    "[--train more.csv] [--held-out] [--run-order order.csv] [--max-displacement 0.5]"
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "train",
        metavar="TRAIN_CSV",
        help="record that identifies the models (one-axis or three-axis, all records one kind)",
    )
    parser.add_argument("tests", metavar="TEST_CSV", nargs="+", help="held-out records that judge")
    parser.add_argument(
        "--out", required=True, metavar="DIR", help="output folder (must not exist)"
    )
    parser.add_argument(
        "--train",
        dest="more_train",
        action="append",
        default=[],
        metavar="CSV",
        help="a further identification record (repeatable)",
    )
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument(
        "--cross",
        action="store_true",
        help="judge every record (TRAIN and TEST) by a fit on all the others (leave one out); "
        "the default with the linear baseline",
    )
    mode.add_argument(
        "--held-out",
        action="store_true",
        help="fit on the TRAIN records only and judge on the TESTs (the default with another "
        "baseline)",
    )
    parser.add_argument(
        "--effects",
        type=_effect_list,
        default=None,
        metavar="NAMES",
        help="comma-separated candidate effects to try (default all: "
        + ", ".join(effect_names())
        + ")",
    )
    parser.add_argument(
        "--baseline",
        default="linear",
        choices=baseline_names(),
        help="baseline identified on TRAIN (default: linear, by least squares)",
    )
    parser.add_argument(
        "--max-displacement",
        type=float,
        default=None,
        metavar="M",
        help="plausibility limit of |displacement| in m (default 0.1; records in metres beyond)",
    )
    parser.add_argument(
        "--max-force", type=float, default=None, metavar="N", help="limit of |force| in N"
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="write into an existing DIR (replaces only the report's own files)",
    )
    parser.add_argument(
        "--run-order",
        type=Path,
        default=None,
        metavar="CSV",
        help="the order the rig ran the records in: a CSV 'record,rest_before_s', one row per "
        "record (its file stem), the rest in s since the row before ended; an empty rest (or "
        "'cold') begins a session. A heat is then carried from record to record",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed for baseline identification")
    add_resample_option(parser, keep=True)
    parser.add_argument("--quiet", action="store_true", help="no progress lines")


def _effect_list(text: str) -> tuple[str, ...]:
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    unknown = [n for n in names if n not in effect_names()]
    if unknown or not names:
        raise argparse.ArgumentTypeError(
            f"unknown effect(s) {unknown or [text]}; known: {', '.join(effect_names())}"
        )
    return names


def config_from(args: argparse.Namespace) -> DiagnoseConfig:
    """The diagnosis the arguments describe."""
    return DiagnoseConfig(
        train=(args.train, *args.more_train),
        tests=tuple(args.tests),
        out=Path(args.out),
        cross=True if args.cross else False if args.held_out else None,
        effects=args.effects,
        baseline=args.baseline,
        max_displacement_m=args.max_displacement,
        max_force_n=args.max_force,
        force=args.force,
        seed=args.seed,
        resample=args.resample,
        run_order=args.run_order,
    )


def run(args: argparse.Namespace) -> int:
    config = config_from(args)
    progress = Progress(quiet=args.quiet)
    result = run_diagnosis(config, progress)
    where = f"coordinate {result['coordinate']}, " if result.get("coordinate") else ""
    progress(
        f"done ({result['mode']}): {where}effect {result['effect']}, gap "
        f"{100 * result['gap_before']:.2f} % -> {100 * result['gap_after']:.2f} % (shrink "
        f"{100 * result['shrink']:.0f} %)"
    )
    print(config.out / "report.md")
    return 0
