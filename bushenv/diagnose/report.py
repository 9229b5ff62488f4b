"""A diagnosis run from files to files: ``DiagnoseConfig`` in, ``DIR/report.json``,
``report.md``, the plots ``*.png`` and ``predictions/<file-stem>.csv`` out (docs/diagnose.md).

``bushenv diagnose`` (``bushenv/commands/diagnose.py``) translates its arguments into a
``DiagnoseConfig``; the core is ``bushenv.diagnose.fit.diagnose``. An existing DIR is refused
unless ``force``; with it only the files named above are replaced, nothing else in DIR is
touched.
"""

from __future__ import annotations

import io
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.diagnose.errors import DiagnoseError
from bushenv.diagnose.fit import diagnose
from bushenv.diagnose.plots import make_plots
from bushenv.persist import write_text
from bushenv.record_rates import one_rate

Say = Callable[[str], None]


@dataclass(frozen=True)
class DiagnoseConfig:
    """One diagnosis: records (paths), mode, candidates, limits and the output folder.

    ``cross``: None is the default mode (every record judged with the linear baseline, the
    TESTs held out with another), True / False ask for cross / held-out. ``max_displacement_m``
    and ``max_force_n``: plausibility limits of the records (None: the loader's defaults).
    ``resample``: ``--resample``'s value (None refuses mixed rates).
    """

    train: tuple[str, ...]
    tests: tuple[str, ...]
    out: Path
    cross: bool | None = None
    effects: tuple[str, ...] | None = None
    baseline: str = "linear"
    max_displacement_m: float | None = None
    max_force_n: float | None = None
    force: bool = False
    seed: int = 0
    resample: float | str | None = None


def _load(paths: tuple[str, ...], config: DiagnoseConfig, say: Say) -> list:
    from bushenv.records import MAX_PLAUSIBLE_DISPLACEMENT_M, MAX_PLAUSIBLE_FORCE_N, load_csv

    limits = {
        "max_displacement_m": config.max_displacement_m or MAX_PLAUSIBLE_DISPLACEMENT_M,
        "max_force_n": config.max_force_n or MAX_PLAUSIBLE_FORCE_N,
    }
    out = []
    for p in paths:
        say(f"loading {p}")
        out.append(load_csv(p, **limits))
    return out


def run_diagnosis(config: DiagnoseConfig, say: Say | None = None) -> dict[str, Any]:
    """Load the records, diagnose, write the report under ``config.out``; returns the result
    (``diagnose``'s dict plus ``files``)."""
    say = say or (lambda msg: None)
    out = Path(config.out)
    check_out_dir(out, config.force)
    stems = [Path(p).stem for p in config.tests]
    every = config.cross or (config.cross is None and config.baseline == "linear")
    judged = stems + ([Path(p).stem for p in config.train] if every else [])
    if len(set(judged)) != len(judged):
        raise DiagnoseError(
            f"judged files need distinct file names (stems {judged}): each one's predictions "
            "go to predictions/<stem>.csv"
        )
    trains = _load(config.train, config, say)
    tests = _load(config.tests, config, say)
    trains, tests = one_rate([trains, tests], config.resample, "diagnose")
    result = diagnose(
        trains,
        tests,
        baseline=config.baseline,
        progress=say,
        seed=config.seed,
        test_names=stems,
        train_names=[Path(p).stem for p in config.train],
        cross=config.cross,
        effects=config.effects,
    )
    result["files"] = {"train": [str(p) for p in config.train], "tests": list(config.tests)}
    say(f"writing {out}")
    write_report(result, out)
    return result


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


def write_predictions(pred: dict[str, Any], path: Path) -> None:
    cols = ("time", "force_measured", "force_baseline", "force_augmented")
    data = np.column_stack([np.asarray(pred[c], dtype=np.float64) for c in cols])
    text = io.StringIO()
    np.savetxt(text, data, delimiter=",", header=",".join(cols), comments="", fmt="%.10g")
    write_text(path, text.getvalue())


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
    write_text(out / "report.json", json.dumps(json_safe(data), indent=2) + "\n")
    write_text(out / "report.md", markdown(data))
