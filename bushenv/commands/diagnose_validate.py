"""``bushenv diagnose-validate``: blind validation of the gap diagnosis.

    bushenv diagnose-validate --set reference|widened --cases N --seed S --out DIR

Arguments become a ``ValidationConfig``; the cases, scoring and report are
``bushenv/diagnose/validation/validate.py`` (docs/diagnose.md).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bushenv.diagnose.validation.validate import SETS, ValidationConfig, write_validation

EXAMPLE = "bushenv diagnose-validate --set widened --cases 60 --seed 0 --out validation/"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--set",
        dest="case_set",
        default="reference",
        choices=list(SETS),
        help="reference: the forms the candidates assume; widened: other forms, strengths, "
        "rates and noise; outside: effects none of the candidates models (docs/diagnose.md)",
    )
    parser.add_argument("--cases", type=int, default=70, help="number of blind cases")
    parser.add_argument("--seed", type=int, default=0, help="validation seed")
    parser.add_argument("--start", type=int, default=0, help="first case index")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder")
    parser.add_argument("--force", action="store_true", help="write into an existing DIR")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")


def config_from(args: argparse.Namespace) -> ValidationConfig:
    return ValidationConfig(
        out=Path(args.out),
        case_set=args.case_set,
        cases=args.cases,
        seed=args.seed,
        start=args.start,
        force=args.force,
    )


def run(args: argparse.Namespace) -> int:
    print(write_validation(config_from(args), progress=not args.quiet))
    return 0
