"""``bushenv diagnose``: a baseline's sim-to-real gap, where it lies, which effect closes it.

    bushenv diagnose TRAIN_CSV TEST_CSV [TEST_CSV ...] --out DIR [--train CSV ...]
                     [--cross | --held-out]

Every record is used: each record, TRAIN or TEST, is judged by a fit on all the others (the
default with the linear baseline, ``--cross``); ``--held-out`` fits on TRAIN only and judges
the TESTs. Writes

- ``DIR/report.json``: effect named, ranking, pairs, unexplained share, shift warnings, where
  the gap lies, parameters (docs/diagnose.md)
- ``DIR/report.md`` with the plots ``DIR/*.png``
- ``DIR/predictions/<file-stem>.csv`` per judged record:
  time,force_measured,force_baseline,force_augmented (the named model's prediction)

An existing DIR is refused unless ``--force``; with ``--force`` only the files named above are
replaced, nothing else in DIR is touched. The core is ``bushenv.diagnose.fit.diagnose``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.commands.options import add_resample_option
from bushenv.diagnose.candidates import effect_names
from bushenv.diagnose.errors import DiagnoseError
from bushenv.diagnose.fit import baseline_names, diagnose
from bushenv.diagnose.plots import make_plots
from bushenv.record_rates import one_rate

EXAMPLE = (
    "bushenv diagnose train.csv test_random.csv test_steps.csv --out diag/ "
    "[--train more.csv] [--held-out] [--max-displacement 0.5]"
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("train", metavar="TRAIN_CSV", help="record that identifies the models")
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


def _load(paths: list[str], args: argparse.Namespace, progress) -> list:
    from bushenv.records import MAX_PLAUSIBLE_DISPLACEMENT_M, MAX_PLAUSIBLE_FORCE_N, load_csv

    limits = {
        "max_displacement_m": args.max_displacement or MAX_PLAUSIBLE_DISPLACEMENT_M,
        "max_force_n": args.max_force or MAX_PLAUSIBLE_FORCE_N,
    }
    out = []
    for p in paths:
        progress(f"loading {p}")
        out.append(load_csv(p, **limits))
    return out


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    check_out_dir(out, args.force)
    start = time.monotonic()

    def progress(msg: str) -> None:
        if not args.quiet:
            print(f"[{time.monotonic() - start:6.1f} s] {msg}", file=sys.stderr, flush=True)

    train_paths = [args.train] + list(args.more_train)
    stems = [Path(p).stem for p in args.tests]
    cross = True if args.cross else False if args.held_out else None
    every = cross or (cross is None and args.baseline == "linear")
    judged = stems + ([Path(p).stem for p in train_paths] if every else [])
    if len(set(judged)) != len(judged):
        raise DiagnoseError(
            f"judged files need distinct file names (stems {judged}): each one's predictions "
            "go to predictions/<stem>.csv"
        )
    trains = _load(train_paths, args, progress)
    tests = _load(list(args.tests), args, progress)
    trains, tests = one_rate([trains, tests], args.resample, "diagnose")
    result = diagnose(
        trains,
        tests,
        baseline=args.baseline,
        progress=progress,
        seed=args.seed,
        test_names=stems,
        train_names=[Path(p).stem for p in train_paths],
        cross=cross,
        effects=args.effects,
    )
    result["files"] = {"train": [str(p) for p in train_paths], "tests": list(args.tests)}
    progress(f"writing {out}")
    write_report(result, out)
    progress(
        f"done ({result['mode']}): effect {result['effect']}, gap {100 * result['gap_before']:.2f}"
        f" % -> {100 * result['gap_after']:.2f} % (shrink {100 * result['shrink']:.0f} %)"
    )
    print(out / "report.md")
    return 0


def check_out_dir(out: Path, force: bool) -> None:
    if out.exists() and not out.is_dir():
        raise DiagnoseError(f"--out {out}: exists and is not a folder; refusing to touch it")
    if out.exists() and not force:
        raise DiagnoseError(
            f"--out {out}: folder already exists; refusing to write into it (pass --force to "
            "replace the report's own files there; nothing else is touched)"
        )


# ----- writing -----------------------------------------------------------------------------
def json_safe(obj: Any) -> Any:
    """Plain JSON values; non-finite numbers become None."""
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_safe(v) for v in obj]
    if isinstance(obj, float | np.floating):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def atomic_write(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix="." + path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_predictions(pred: dict[str, Any], path: Path) -> None:
    cols = ("time", "force_measured", "force_baseline", "force_augmented")
    data = np.column_stack([np.asarray(pred[c], dtype=np.float64) for c in cols])
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix="." + path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            np.savetxt(fh, data, delimiter=",", header=",".join(cols), comments="", fmt="%.10g")
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_report(result: dict[str, Any], out: Path) -> None:
    """report.json, report.md, plots and predictions/<stem>.csv under ``out``."""
    from bushenv.diagnose.markdown import markdown

    out.mkdir(parents=True, exist_ok=True)
    (out / "predictions").mkdir(exist_ok=True)
    for pred in result["predictions"]:
        write_predictions(pred, out / "predictions" / f"{pred['name']}.csv")
    data = {k: v for k, v in result.items() if k != "predictions"}
    data["predictions"] = [f"predictions/{p['name']}.csv" for p in result["predictions"]]
    data["plots"] = make_plots(result, out)
    atomic_write(out / "report.json", json.dumps(json_safe(data), indent=2) + "\n")
    atomic_write(out / "report.md", markdown(data))
