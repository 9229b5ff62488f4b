"""``bushenv measure``: run a test programme on a model of C coordinates and write CSV records
(``bushenv.machine``, ``bushenv.programmes``)."""

from __future__ import annotations

import argparse
import inspect
import sys
import warnings
from pathlib import Path

import numpy as np

from bushenv.machine import MachineError, MachineWarning, reference_for, run_programme
from bushenv.models.base import DT_TOLERANCE, PAPER_DT
from bushenv.persist import write_json
from bushenv.programmes import (
    IDENTIFICATION_N,
    PROGRAMMES,
    STEP_HOLD_S,
    STEP_SIZE_M,
    programme_items,
)
from bushenv.record_files import save_record
from bushenv.records import RecordError

EXAMPLE = (
    "bushenv measure --model rubber --axis axial --programme random --n 1 --duration 40 "
    "--seed 0 --out records/"
)


def _forms(n_coords: int) -> str:
    return "; ".join(f"{k}: {v[n_coords]}" for k, v in PROGRAMMES.items() if n_coords in v)


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
        help="the bushing's coordinates: 3 measures axial, radial and rotation at once "
        "(--model: the coupled reference by default, a three-axis preset or .npz) into "
        "three-axis CSV records (default: 1)",
    )
    parser.add_argument(
        "--programme",
        default="papers",
        choices=tuple(PROGRAMMES),
        help=f"one axis: {_forms(1)} (default papers); with --axes 3: {_forms(3)}",
    )
    parser.add_argument("--n", type=float, default=IDENTIFICATION_N, help="random index n")
    parser.add_argument(
        "--duration",
        type=float,
        default=None,
        help="random record length, s (default 40 for n <= 1, else 20; combined: 10 each)",
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


def _model(args: argparse.Namespace, dt: float):
    """The model measured, or a factory of one per record: a registered model whose preset
    measures with noise gets its own noise seed per record (``machine.reference_for``)."""
    from bushenv.models import MODELS, get_model

    wanted_by = "bushenv measure" + (f" --axes {args.axes}" if args.axes != 1 else "")
    named = args.model in MODELS  # a preset is built at the rate; a file runs at its own
    model = get_model(
        args.model, axis=args.axis, dt=dt if named else None, coords=args.axes, wanted_by=wanted_by
    )
    if abs(model.dt - dt) > DT_TOLERANCE * dt:  # a fitted model runs only at its own rate
        raise MachineError(
            f"{args.model}: model sampled at {1 / model.dt:.6g} Hz, --rate is {1 / dt:.6g} Hz: "
            f"pass --rate {1 / model.dt:.6g}"
        )
    if named and "seed" in inspect.signature(type(model).preset).parameters:
        return model, reference_for(args.model, args.axes, args.seed, dt, args.axis)
    return model, model


def cli_run(args: argparse.Namespace) -> int:
    from bushenv.progress import Progress

    progress = Progress(quiet=args.quiet)
    if not (np.isfinite(args.rate) and args.rate > 0):
        raise MachineError(f"--rate must be a positive number of Hz, got {args.rate!r}")
    if args.seed < 0:
        raise MachineError(f"--seed must be >= 0, got {args.seed}")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise MachineError(f"--out {out}: exists and is not a folder")
    if args.axes != 1 and args.axis != "axial":
        raise MachineError(
            f"--axis names one axis; --axes {args.axes} measures all of them (drop --axis)"
        )
    forms = PROGRAMMES[args.programme]
    if args.axes not in forms:
        raise MachineError(
            f"--programme {args.programme} has no {args.axes}-axis form (add --axes "
            f"{' or '.join(map(str, forms))}); with --axes {args.axes} choose {_forms(args.axes)}"
        )
    dt = 1.0 / args.rate
    items = programme_items(
        args.programme, args.axes, dt, args.seed, args.n, args.duration,
        args.step_mm * 1e-3, args.hold,
    )  # fmt: skip
    paths = [out / f"{item.name}.csv" for item in items]
    existing = [str(p) for p in paths if p.exists()]
    if existing and not args.force:
        raise RecordError(
            f"{len(existing)} record file(s) already exist, e.g. {existing[0]}; refusing to "
            "overwrite (pass --force to replace them)"
        )
    model, source = _model(args, dt)
    where = f"({args.axis})" if model.n_coords == 1 else f"({', '.join(model.coords)})"
    progress(
        f"{args.programme} programme, {len(items)} item(s), model {model.name} {where}, "
        f"{1 / model.dt:g} Hz"
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", MachineWarning)
        records = run_programme(source, items, progress=progress)
    for w in caught:
        print(f"bushenv measure: warning: {w.message}", file=sys.stderr)
    out.mkdir(parents=True, exist_ok=True)
    for k, (record, path) in enumerate(zip(records, paths, strict=True), start=1):
        if not record.info["force_finite"]:
            raise MachineError(
                f"{record.name}: the model's force is not finite (diverged); nothing written "
                f"for it or later items ({k - 1} of {len(records)} written)"
            )
        save_record(record, path, overwrite=args.force)
        peaks = np.abs(record.f).max(axis=0)
        shown = ", ".join(f"{p:.4g} {u}" for p, u in zip(peaks, model.force_units, strict=True))
        progress(f"[{k}/{len(records)}] {path}: {len(record)} samples, max |F| = {shown}")
        print(path)
    write_json(out / "measure.json", _manifest(args, model, records, paths))
    return 0


def _manifest(args, model, records, paths) -> dict:
    """What made the records: the model (spec, class, file and parameter hashes), the
    programme and its settings, and each record's file, length and peak force per coordinate."""
    from bushenv.models import file_hash, model_file, params_sha

    path = model_file(args.model, args.axis)
    return {
        "model": {
            "spec": args.model,
            "class": type(model).__name__,
            "file_sha256": file_hash(path) if path is not None and path.is_file() else None,
            "params_sha256": params_sha(model),
            "axis": args.axis if model.n_coords == 1 else None,
            "coords": list(model.coords),
        },
        "sample_rate_hz": 1.0 / model.dt,
        "programme": args.programme,
        "seed": args.seed,
        "records": [
            {
                "file": p.name,
                "samples": len(r),
                "max_abs_force_n": r.info["max_abs_force_n"],
                "max_abs_force": np.abs(r.f).max(axis=0).tolist(),
            }
            for r, p in zip(records, paths, strict=True)
        ],
    }
