"""``bushenv campaign``: argparse in, a ``MatrixConfig`` out, the matrix run (``matrix.py``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from bushenv.execution import get_backend
from bushenv.models import AXES
from bushenv.progress import Progress
from bushenv.search.matrix import (
    MatrixConfig,
    MatrixError,
    parse_seeds,
    run_matrix,
    summarise,
    write_summary,
)
from bushenv.search.searchers import SEARCHERS
from bushenv.search.targets import TARGETS

EXAMPLE = (
    "bushenv campaign --models nn,hybrid --axes axial --searchers random,cma "
    "--seeds 0-3 --budget 128 --out runs/matrix"
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    d = MatrixConfig()
    p.add_argument("--models", default=",".join(d.models), help="comma list of model names")
    p.add_argument("--axes", default=",".join(d.axes), help=f"comma list: {', '.join(AXES)}")
    p.add_argument(
        "--searchers",
        default=",".join(d.searchers),
        help=f"comma list: {', '.join(SEARCHERS.names())}",
    )
    p.add_argument("--seeds", default="0-3", help="e.g. 0-9 or 1,4,7")
    p.add_argument("--budget", type=int, default=d.budget, help="model evaluations per cell (> 0)")
    p.add_argument("--env", choices=TARGETS.names(), default=d.target)
    p.add_argument(
        "--reference",
        default=d.reference,
        help="the bushing every cell is judged against: a registered name or a model file; "
        "'none' judges with the criteria that need no reference",
    )
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--resume", action="store_true", help="continue an interrupted matrix")
    p.add_argument("--workers", type=int, default=None, help="local worker processes")
    p.add_argument("--ray", action="store_true", help="run on Ray (a local instance)")
    p.add_argument("--ray-address", default=None, help="run on an existing Ray cluster")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def _names(flag: str, text: str) -> tuple[str, ...]:
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    if not names:
        raise MatrixError(f"{flag} {text!r} names nothing")
    return names


def run(args: argparse.Namespace) -> int:
    config = MatrixConfig(
        models=_names("--models", args.models),
        axes=_names("--axes", args.axes),
        searchers=_names("--searchers", args.searchers),
        seeds=tuple(parse_seeds(args.seeds)),
        budget=args.budget,
        target=args.env,
        reference=args.reference,
        out=Path(args.out),
        resume=args.resume,
    ).checked()
    backend = get_backend(
        "ray" if (args.ray or args.ray_address) else "local",
        workers=args.workers,
        address=args.ray_address,
    )
    progress = Progress(quiet=args.quiet)
    with backend:
        rows = run_matrix(
            config.cells(), config.out, backend, resume=config.resume, progress=progress
        )
    summary = summarise(rows)
    write_summary(config.out, summary)
    print((config.out / "summary.md").read_text())
    print(f"wrote {config.out}/cells.jsonl, summary.json, summary.md, summary.png")
    return 0
