"""A diagnosis run from files to files: ``DiagnoseConfig`` in, ``DIR/report.json``,
``report.md``, the plots ``*.png`` and ``predictions/<file-stem>.csv`` out (docs/diagnose.md).

``bushenv diagnose`` (``bushenv/commands/diagnose.py``) translates its arguments into a
``DiagnoseConfig``; the core is ``bushenv.diagnose.fit.diagnose``. An existing DIR is refused
unless ``force``; with it only the files named above are replaced, nothing else in DIR is
touched. Three-axis records (every file; a mix is refused) go the same way, written by
``coordinates_report.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bushenv.diagnose.errors import DiagnoseError
from bushenv.diagnose.fit import diagnose
from bushenv.diagnose.report_files import write_report
from bushenv.diagnose.session import read_order
from bushenv.record_files import record_coordinates
from bushenv.record_rates import one_rate

Say = Callable[[str], None]


@dataclass(frozen=True)
class DiagnoseConfig:
    """One diagnosis: records (paths), mode, candidates, limits and the output folder.

    ``cross``: None is the default mode (every record judged with the linear baseline, the
    TESTs held out with another), True / False ask for cross / held-out. ``max_displacement_m``
    and ``max_force_n``: plausibility limits of the records (None: the loader's defaults).
    ``resample``: ``--resample``'s value (None refuses mixed rates). ``run_order``: the order
    the records ran in and the rests between, read before any record is loaded.
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
    run_order: Path | None = None  # a CSV ``record,rest_before_s`` (bushenv.diagnose.session)


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
    order = read_order(config.run_order) if config.run_order is not None else None
    if three_axis_files(config.train + config.tests):
        trains, tests = _load_three_axis(config, say)
    else:
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
        run_order=order,
    )
    result["files"] = {"train": [str(p) for p in config.train], "tests": list(config.tests)}
    say(f"writing {out}")
    if "diagnoses" in result:  # records of several coordinates
        from bushenv.diagnose.coordinates_report import write_coordinates_report

        write_coordinates_report(result, out)
    else:
        write_report(result, out)
    return result


def three_axis_files(paths: tuple[str, ...]) -> bool:
    """True when every record file is three-axis, False when none is; a mix is refused
    naming a file of each kind."""
    kinds = {p: record_coordinates(p) == 3 for p in paths}
    three = [p for p, k in kinds.items() if k]
    one = [p for p, k in kinds.items() if not k]
    if three and one:
        from bushenv.record_columns import THREE_AXES

        raise DiagnoseError(
            f"{three[0]} is a three-axis record but {one[0]} is a one-axis record ({len(three)} "
            f"three-axis, {len(one)} one-axis): one diagnosis takes records of one kind; "
            f"three-axis records have the header '{THREE_AXES.header_text}'"
        )
    return bool(three)


def _load_three_axis(config: DiagnoseConfig, say: Say) -> tuple[list, list]:
    from bushenv.record_files import load_record

    if config.max_displacement_m is not None or config.max_force_n is not None:
        raise DiagnoseError(
            "--max-displacement and --max-force are the one-axis loader's limits; a three-axis "
            "record states a column's unit in its header instead (e.g. 'displacement_radial "
            "[m]', 'moment [N m]'), which lifts the limit for that column"
        )
    if config.resample is not None:
        raise DiagnoseError(
            f"--resample {config.resample}: three-axis records are diagnosed at one shared "
            "rate (the baseline's matrices are identified at it); resample them first"
        )
    out = []
    for paths in (config.train, config.tests):
        recs = []
        for p in paths:
            say(f"loading {p} (three-axis)")
            recs.append(load_record(p, coords=3))
        out.append(recs)
    return out[0], out[1]


def check_out_dir(out: Path, force: bool) -> None:
    if out.exists() and not out.is_dir():
        raise DiagnoseError(f"--out {out}: exists and is not a folder; refusing to touch it")
    if out.exists() and not force:
        raise DiagnoseError(
            f"--out {out}: folder already exists; refusing to write into it (pass --force to "
            "replace the report's own files there; nothing else is touched)"
        )
