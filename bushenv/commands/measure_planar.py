"""``bushenv measure --axes 3``: the 3-axis programme on a planar model, as 3-axis CSV records."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from bushenv.persist import write_json


def _model_for(args: argparse.Namespace, dt: float):
    """The planar model measured: the reference (default, with load-cell noise), a registered
    planar name with a preset, or a planar ``.npz`` file."""
    from bushenv.cli import CliError
    from bushenv.models import MODELS, get_model, has_preset, names_for
    from bushenv.models.base import DT_TOLERANCE
    from bushenv.planar.machine import reference_for

    spec = "reference" if args.model in ("rubber", "reference") else args.model
    if spec == "reference":
        return spec, reference_for(args.seed, dt)
    if spec.endswith(".npz"):
        model = get_model(spec, coords=3, wanted_by="bushenv measure --axes 3")
        if abs(model.dt - dt) > DT_TOLERANCE * dt:  # a fitted model runs only at its rate
            raise CliError(
                f"{spec}: model sampled at {1 / model.dt:.6g} Hz, --rate is {1 / dt:.6g} Hz: "
                f"pass --rate {1 / model.dt:.6g}"
            )
        return spec, lambda k: model.copy()
    presets = [n for n in names_for(3) if has_preset(MODELS[n].model_class(3))]
    if spec in presets:
        cls = MODELS[spec].model_class(3)
        return spec, lambda k: cls.preset(dt=dt)
    raise CliError(
        f"--model {spec!r} with --axes 3: give a three-axis model with a preset "
        f"({', '.join(presets)}) or a three-axis .npz file (bushenv fit on 3-axis records "
        "writes one)"
    )


def run_planar(args: argparse.Namespace) -> int:
    from bushenv.cli import CliError
    from bushenv.planar.machine import items, measure
    from bushenv.planar.records import save_planar_csv
    from bushenv.progress import Progress
    from bushenv.records import RecordError

    if args.programme not in ("papers", "random", "combined"):
        raise CliError(
            f"--programme {args.programme} has no 3-axis form; with --axes 3 choose papers "
            "(random n = 1 and 1.5, independent and correlated, and the coupled sine sets), "
            "random, or combined (each coordinate held at +- n x its n = 1 peak while each "
            "other one is swept: 12 records)"
        )
    if args.axis != "axial":
        raise CliError("--axis names one axis; --axes 3 measures all three (drop --axis)")
    dt = 1.0 / args.rate
    motions = items(args.programme, dt, args.seed, args.n, args.duration)
    out = Path(args.out)
    paths = [out / f"{name}.csv" for name, _ in motions]
    existing = [str(p) for p in paths if p.exists()]
    if existing and not args.force:
        raise RecordError(
            f"{len(existing)} record file(s) already exist, e.g. {existing[0]}; refusing to "
            "overwrite (pass --force to replace them)"
        )
    spec, model_for = _model_for(args, dt)
    progress = Progress(quiet=args.quiet)
    progress(f"3-axis {args.programme} programme, {len(motions)} record(s), model {spec}, "
             f"{1 / dt:g} Hz")  # fmt: skip
    records = measure(model_for, motions, say=progress)
    out.mkdir(parents=True, exist_ok=True)
    for (_, q, f), path in zip(records, paths, strict=True):
        t = dt * np.arange(len(q))
        save_planar_csv(path, t, q, f, overwrite=args.force)
        print(path)
    manifest = {
        "model": {"spec": spec, "axes": 3},
        "sample_rate_hz": 1.0 / dt,
        "programme": args.programme,
        "seed": args.seed,
        "records": [
            {"file": p.name, "samples": len(q), "max_abs_force": abs(f).max(axis=0).tolist()}
            for (_, q, f), p in zip(records, paths, strict=True)
        ],
    }
    write_json(out / "measure.json", manifest)
    return 0
