"""``bushenv measure``: run a test programme on a model and write CSV records (``machine.py``)."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

from bushenv.machine import (
    IDENTIFICATION_N,
    PROGRAMMES,
    STEP_HOLD_S,
    STEP_SIZE_M,
    MachineError,
    MachineWarning,
    ProgrammeItem,
    default_random_duration,
    harmonic_programme,
    papers_programme,
    random_item,
    run_programme,
    step_item,
)
from bushenv.models.base import PAPER_DT
from bushenv.persist import write_json
from bushenv.records import RecordError, save_csv

EXAMPLE = (
    "bushenv measure --model rubber --axis axial --programme random --n 1 --duration 40 "
    "--seed 0 --out records/"
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--model", default="rubber", help="registered model name or .npz file (default: rubber)"
    )
    parser.add_argument("--axis", default="axial", choices=("axial", "radial"))
    parser.add_argument(
        "--axes",
        type=int,
        default=1,
        choices=(1, 3),
        help="3: the 3-axis programme on a planar model (--model: the planar reference by "
        "default, a planar preset or .npz), 3-axis CSV records (default: 1)",
    )
    parser.add_argument(
        "--programme",
        default="papers",
        choices=(*PROGRAMMES, "combined"),
        help="harmonic: 25 sines; random: one RPC-like record (--n, --duration, --seed); "
        "step: one held step (--step-mm, --hold); papers: harmonic + random n=1 40 s + "
        "random n=1.5 20 s (seed+1) + 4 mm step (default); with --axes 3: papers, random, or "
        "combined (each coordinate held at +- n x its n = 1 peak while each other one is "
        "swept, 10 s each or --duration)",
    )
    parser.add_argument("--n", type=float, default=IDENTIFICATION_N, help="random index n")
    parser.add_argument(
        "--duration",
        type=float,
        default=None,
        help="random record length, s (default 40 for n <= 1, else 20)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the random drive")
    parser.add_argument("--step-mm", type=float, default=STEP_SIZE_M * 1e3, help="step size, mm")
    parser.add_argument("--hold", type=float, default=STEP_HOLD_S, help="step hold time, s")
    parser.add_argument(
        "--rate",
        type=float,
        default=1.0 / PAPER_DT,
        help="sample rate, Hz (default: the papers' 204.8)",
    )
    parser.add_argument("--out", required=True, metavar="DIR", help="folder for the CSV records")
    parser.add_argument("--force", action="store_true", help="replace existing record files")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")


def programme_items(args: argparse.Namespace, dt: float) -> list[ProgrammeItem]:
    if args.programme == "harmonic":
        return harmonic_programme(dt)
    if args.programme == "random":
        duration = default_random_duration(args.n) if args.duration is None else args.duration
        return [random_item(args.n, duration, args.seed, dt)]
    if args.programme == "step":
        return [step_item(args.step_mm * 1e-3, args.hold, dt)]
    return papers_programme(dt, seed=args.seed)


def cli_run(args: argparse.Namespace) -> int:
    from bushenv.models import get_model
    from bushenv.progress import Progress

    progress = Progress(quiet=args.quiet)

    if not (np.isfinite(args.rate) and args.rate > 0):
        raise MachineError(f"--rate must be a positive number of Hz, got {args.rate!r}")
    if args.seed < 0:
        raise MachineError(f"--seed must be >= 0, got {args.seed}")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise MachineError(f"--out {out}: exists and is not a folder")
    if args.axes == 3:
        from bushenv.commands.measure_planar import run_planar

        return run_planar(args)
    if args.programme == "combined":
        raise MachineError(
            "--programme combined holds one coordinate while another moves: it is a programme "
            "of several coordinates (add --axes 3)"
        )
    model = get_model(args.model, axis=args.axis, dt=1.0 / args.rate)
    items = programme_items(args, model.dt)
    paths = [out / f"{item.name}.csv" for item in items]
    existing = [str(p) for p in paths if p.exists()]
    if existing and not args.force:
        raise RecordError(
            f"{len(existing)} record file(s) already exist, e.g. {existing[0]}; refusing to "
            "overwrite (pass --force to replace them)"
        )
    progress(
        f"{args.programme} programme, {len(items)} item(s), model {model.name} ({args.axis}), "
        f"{1 / model.dt:g} Hz"
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", MachineWarning)
        records = run_programme(model, items, progress=progress)
    for w in caught:
        print(f"bushenv measure: warning: {w.message}", file=sys.stderr)
    out.mkdir(parents=True, exist_ok=True)
    for k, (record, path) in enumerate(zip(records, paths, strict=True), start=1):
        if not record.info["force_finite"]:
            raise MachineError(
                f"{record.name}: the model's force is not finite (diverged); nothing written "
                f"for it or later items ({k - 1} of {len(records)} written)"
            )
        save_csv(record, path, overwrite=args.force)
        progress(
            f"[{k}/{len(records)}] {path}: {len(record)} samples, "
            f"max |F| = {record.info['max_abs_force_n']:.4g} N"
        )
        print(path)
    write_json(out / "measure.json", _manifest(args, model, records, paths))
    return 0


def _manifest(args, model, records, paths) -> dict:
    """What made the records: the model (spec, class, file and parameter hashes), the
    programme and its settings, and each record's file, length and peak force."""
    from bushenv.models import file_hash, model_file, params_sha

    path = model_file(args.model, args.axis)
    return {
        "model": {
            "spec": args.model,
            "class": type(model).__name__,
            "file_sha256": file_hash(path) if path is not None and path.is_file() else None,
            "params_sha256": params_sha(model),
            "axis": args.axis,
        },
        "sample_rate_hz": 1.0 / model.dt,
        "programme": args.programme,
        "seed": args.seed,
        "records": [
            {"file": p.name, "samples": len(r), "max_abs_force_n": r.info["max_abs_force_n"]}
            for r, p in zip(records, paths, strict=True)
        ],
    }
