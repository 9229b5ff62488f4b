"""Multi-axis test records as CSV files: one record per file, the one-axis format's rules.

    time,displacement_axial,displacement_radial,rotation,force_axial,force_radial,moment
    0.0,0.0,0.0,0.0,0.0,0.0,0.0
    0.0048828125,1.2e-05,-3.0e-06,0.0011,4.61,-2.3,3.3
    ...

Columns are s, m, m, rad, N, N, N m unless a unit is written after a name in brackets, e.g.
``displacement_axial [mm]``, ``rotation [deg]``, ``moment [N mm]`` (``UNITS``), converted to SI
on load. The seven names may come in any order (a rig that writes each axis's displacement
beside its force is read as it is); each once, nothing else. As for one-axis records
(``bushenv.records``): finite decimal numbers (plain ones read by numpy's parser, the rest line
by line to name a problem), blank lines only at the end, time strictly
increasing with a uniform step (1 % of dt + 1 ns), at least two samples, plausibility limits
for columns without a stated unit. Every problem raises ``RecordError`` naming the file, the
line and the value, and the fix.
"""

from __future__ import annotations

import csv
import difflib
import io
import os
import re
import warnings
from pathlib import Path

import numpy as np

from bushenv.persist import atomic_write
from bushenv.records import HEADER as ONE_AXIS_HEADER
from bushenv.records import (
    NAME_UNIT,
    STEP_ATOL_S,
    STEP_RTOL,
    Record,
    RecordError,
    check_rate,
    is_plausible_rate,
)
from bushenv.records import UNITS as ONE_AXIS_UNITS

HEADER = (
    "time",
    "displacement_axial",
    "displacement_radial",
    "rotation",
    "force_axial",
    "force_radial",
    "moment",
)
HEADER_TEXT = ",".join(HEADER)
_KIND = {  # column -> unit table
    "time": "time",
    "displacement_axial": "displacement",
    "displacement_radial": "displacement",
    "rotation": "rotation",
    "force_axial": "force",
    "force_radial": "force",
    "moment": "moment",
}
UNITS = {
    **ONE_AXIS_UNITS,
    "rotation": {"rad": 1.0, "mrad": 1e-3, "deg": np.pi / 180.0},
    "moment": {"N m": 1.0, "Nm": 1.0, "N mm": 1e-3, "Nmm": 1e-3, "kN m": 1e3, "kNm": 1e3},
}
SI = {"displacement": "m", "rotation": "rad", "force": "N", "moment": "N m"}
# Plain-header plausibility (SI): beyond these the unit is almost surely wrong. Rotation: 0.5
# rad (29 deg) is over three times the rig's 0.15 rad; a column in degrees passes only if
# it never leaves +-0.5 deg.
PLAUSIBLE = {"displacement": 0.1, "rotation": 0.5, "force": 1.0e6, "moment": 1.0e5}
_HINT = {
    "displacement": "millimetres? write 'displacement_axial [mm]' in the header",
    "rotation": "degrees? write 'rotation [deg]' in the header ('rotation [rad]' if it really "
    "is radians)",
    "force": "write the force unit in the header, e.g. 'force_axial [N]'",
    "moment": "N mm? write 'moment [N mm]' in the header",
}


# the one record type (``bushenv.records.Record``) over these three coordinates: time (T,) s;
# q (T, 3) m, m, rad; f (T, 3) N, N, N m; ``source`` the file
PlanarRecord = Record


def header_names(fields: list[str]) -> list[str]:
    """The column names of a header row, units in brackets dropped."""
    names = []
    for text in fields:
        m = NAME_UNIT.match(text)
        names.append((m.group(1) if m else text).strip())
    return names


def looks_planar(fields: list[str]) -> bool:
    """Whether a header row is meant as a planar one: seven columns, or a name only planar
    records have (so a misspelt planar header gets the planar loader's message)."""
    own = set(HEADER) - set(ONE_AXIS_HEADER)
    sep = _other_separator(fields)
    fields = fields[0].split(sep) if sep else fields
    return len(fields) == len(HEADER) or bool(own & set(header_names(fields)))


def _other_separator(fields: list[str]) -> str | None:
    """';' or a tab when a header row read with commas is one field split by it, else None."""
    if len(fields) == 1:
        for sep in (";", "\t"):
            if len(fields[0].split(sep)) > 1:
                return sep
    return None


def _header(path: Path, fields: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """(column of each ``HEADER`` name in the file, SI factor per ``HEADER`` name); the names
    may come in any order. ``RecordError`` naming the header problem."""
    names = header_names(fields)
    shown = ",".join(f.strip() for f in fields)
    sep = _other_separator(fields)
    if sep:
        sep = "tab" if sep == "\t" else repr(sep)
        raise RecordError(
            f"{path} line 1: header '{shown}' looks {sep}-separated; save the file with commas "
            f"between values and a point as the decimal mark ('{HEADER_TEXT}')"
        )
    if tuple(names) == ONE_AXIS_HEADER:
        raise RecordError(
            f"{path} line 1: header '{shown}' is a one-axis record's; expected '{HEADER_TEXT}' "
            "(give one-axis records to a one-axis fit, 3-axis ones to a 3-axis fit)"
        )
    for j, name in enumerate(names):
        if name not in _KIND:
            close = difflib.get_close_matches(name, HEADER, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise RecordError(
                f"{path} line 1: header '{shown}': column {j + 1} {name!r} is not a planar "
                f"record column{hint}; expected '{HEADER_TEXT}', the names in any order, each "
                "once (units in brackets allowed, e.g. 'rotation [deg]')"
            )
        if names.index(name) != j:
            raise RecordError(
                f"{path} line 1: {name} appears twice in the header '{shown}' (columns "
                f"{names.index(name) + 1} and {j + 1}); name each column once"
            )
    missing = [n for n in HEADER if n not in names]
    if missing:
        raise RecordError(
            f"{path} line 1: header '{shown}' lacks {', '.join(missing)}; a planar record has "
            f"the seven columns {HEADER_TEXT}: write an axis the test held still as columns of "
            "zeros"
        )
    order = np.array([names.index(n) for n in HEADER])
    factors = np.ones(len(HEADER))
    for k, name in enumerate(HEADER):
        m = NAME_UNIT.match(fields[order[k]])
        if m:
            unit, table = m.group(2), UNITS[_KIND[name]]
            if unit not in table:
                raise RecordError(
                    f"{path} line 1: unknown unit {unit!r} for {name}; known: {', '.join(table)}"
                )
            factors[k] = table[unit]
    return order, factors


def load_planar_csv(path: str | os.PathLike) -> PlanarRecord:
    """Read and check one multi-axis record (see the module docstring)."""
    path = Path(path)
    if not path.is_file():
        raise RecordError(
            f"{path}: no such record file" if not path.exists() else f"{path}: not a regular file"
        )
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise RecordError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    head, _, body = text.partition("\n")
    fields = next(csv.reader([head]), [])
    if not text.strip():
        raise RecordError(f"{path}: empty file; expected the header '{HEADER_TEXT}' and data")
    order, factors = _header(path, fields)
    a = _plain_rows(body)
    a = _parse_rows(path, text, order) if a is None else a[:, order]
    stated = np.array([bool(NAME_UNIT.match(fields[j])) for j in order])
    _check_plausible(path, a, stated)
    a = a * factors
    _check_time(path, a[:, 0])
    if not stated[0]:
        check_rate(a[:, 0], str(path), lambda i: f"{path} line {i + 2}")
    return Record(
        a[:, 0],
        np.ascontiguousarray(a[:, 1:4]),
        np.ascontiguousarray(a[:, 4:7]),
        name=path.stem,
        path=path,
        coords=("axial", "radial", "rotation"),
    )


_PLAIN = str.maketrans("", "", "0123456789+-.eE,\n\r \t")  # what numpy reads as float does
_BLANK_LINE = re.compile(r"(?:^|\n)[ \t\r]*(?:\n|$)")


def _plain_rows(body: str) -> np.ndarray | None:
    """The data through numpy's parser when they are plain numbers, seven a line, no blank
    line before the end (the common case, 20x faster); None: the line-by-line parser then
    reads them and names any problem."""
    body = body.rstrip()
    if body.translate(_PLAIN) or _BLANK_LINE.search(body):
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = np.loadtxt(io.StringIO(body), delimiter=",", comments=None, ndmin=2)
    except ValueError:
        return None
    ok = a.shape[0] >= 2 and a.shape[1] == len(HEADER) and np.isfinite(a).all()
    return a if ok else None


def _parse_rows(path: Path, text: str, order: np.ndarray) -> np.ndarray:
    """(T, 7) in ``HEADER`` order, line by line; ``RecordError`` naming the first bad line."""
    rows = list(csv.reader(io.StringIO(text)))
    data = []
    end = len(rows)
    while end > 1 and not "".join(rows[end - 1]).strip():
        end -= 1
    for i in range(1, end):
        row, line = rows[i], i + 1
        if len(row) != len(HEADER):
            raise RecordError(
                f"{path} line {line}: {len(row)} values, expected {len(HEADER)} as the header "
                f"has ({','.join(f.strip() for f in rows[0])})"
            )
        vals = []
        for name, cell in zip(HEADER, (row[j] for j in order), strict=True):
            try:
                x = float(cell)
            except ValueError:
                raise RecordError(
                    f"{path} line {line}: {name} {cell.strip()!r} is not a number"
                    + (" (units go into the header, e.g. 'rotation [deg]')" if line == 2 else "")
                ) from None
            if not np.isfinite(x):
                raise RecordError(
                    f"{path} line {line}: {name} is {cell.strip()}; values must be finite"
                )
            vals.append(x)
        data.append(vals)
    if len(data) < 2:
        raise RecordError(f"{path}: {len(data)} sample(s); a record needs at least two")
    return np.array(data)


def _check_plausible(path: Path, a: np.ndarray, stated: np.ndarray) -> None:
    for j, name in enumerate(HEADER[1:], start=1):
        kind = _KIND[name]
        i = int(np.argmax(np.abs(a[:, j])))
        if not stated[j] and abs(a[i, j]) > PLAUSIBLE[kind]:
            raise RecordError(
                f"{path} line {i + 2}: {name} {float(a[i, j])!r} exceeds {PLAUSIBLE[kind]:g} "
                f"{SI[kind]}: "
                f"{_HINT[kind]}"
            )


def _check_time(path: Path, t: np.ndarray) -> None:
    step = np.diff(t)
    back = np.flatnonzero(step <= 0)
    if back.size:
        i = int(back[0])
        raise RecordError(
            f"{path} line {i + 3}: time goes {'backwards' if step[i] < 0 else 'nowhere'} "
            f"({float(t[i + 1])!r} after {float(t[i])!r}); time must strictly increase"
        )
    dt = float(np.median(step))
    off = np.flatnonzero(np.abs(step - dt) > STEP_RTOL * dt + STEP_ATOL_S)
    if off.size:
        i = int(off[0])
        raise RecordError(
            f"{path} line {i + 3}: time step {float(step[i])!r} s differs from the record's "
            f"{dt!r} s; records are sampled uniformly (resample it, or split it at the gap)"
        )


START_S = 0.01  # the start a record is judged on
OFFSET_SHARE = 0.03  # force at rest above this share of the record's largest |f|: an offset
NOISE_SIGMAS = 5  # a column within this many noise sigmas carries sensor noise only
REST_SHARE = 0.02  # at rest: |q| over the start below this share of its largest value
DEFLECTED_SHARE = 0.05  # start deflection above this share of the record's largest |q|


def start_notes(record: PlanarRecord) -> list[str]:
    """What the models cannot follow at the record's start, one line each (empty if none).

    Every planar model runs free from rest (zero deflection, zero force). A record that starts
    deflected (a preload applied before the recording began) makes its first samples a step
    from rest; a force that reads clearly non-zero while the bushing is at rest (no deflection
    over the start) is an offset (a load cell not zeroed), which no model at rest produces and
    which biases a fit.
    """
    n = max(2, int(round(START_S / record.dt)))
    q0, f0 = record.q[:n].mean(axis=0), record.f[:n].mean(axis=0)
    # a floor of NOISE_SIGMAS noise sigmas (from sample-to-sample steps) keeps an axis that only
    # carries sensor noise from counting as deflected or loaded
    q_floor, f_floor = NOISE_SIGMAS * noise_sigma(record.q), NOISE_SIGMAS * noise_sigma(record.f)
    q_peak = np.abs(record.q).max(axis=0)
    name = record.source or "record"
    deflected = np.abs(q0) > np.maximum(DEFLECTED_SHARE * q_peak, q_floor)
    notes = []
    if deflected.any():
        shown = ", ".join(f"{HEADER[1 + i]} {_si(q0[i], UNIT_OF[i])}"
                          for i in np.flatnonzero(deflected))  # fmt: skip
        notes.append(
            f"{name} line 2: starts deflected ({shown}), not at rest: the models run free "
            "from rest, so its first samples are a step to that deflection; record from rest "
            "(before the preload) for a fair comparison"
        )
    at_rest = np.all(np.abs(record.q[:n]) <= np.maximum(REST_SHARE * q_peak, q_floor))
    offset = np.abs(f0) > np.maximum(OFFSET_SHARE * np.abs(record.f).max(axis=0), f_floor)
    if at_rest and offset.any():
        shown = ", ".join(f"{HEADER[4 + i]} {_si(f0[i], FORCE_UNIT_OF[i])}"
                          for i in np.flatnonzero(offset))  # fmt: skip
        notes.append(
            f"{name} line 2: reads {shown} at rest (mean of the first {n} samples, no "
            "deflection): a load-cell offset? Models give zero force at rest; "
            "subtract the offset from the column (zero the load cell) before fitting"
        )
    return notes


def only_noise(q: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(3,) per coordinate of a record (T, 3): held at rest (its deflection moves within
    ``NOISE_SIGMAS`` noise sigmas) and its force within that of its sensor's noise, as a preload
    sweep's axial axis: a ratio to noise judges nothing, so such a coordinate gets none."""
    still = np.ptp(q, axis=0) <= NOISE_SIGMAS * noise_sigma(q)
    quiet = np.sqrt(np.mean(f**2, axis=0)) <= NOISE_SIGMAS * noise_sigma(f)
    return still & quiet


def noise_sigma(a: np.ndarray) -> np.ndarray:
    """Per column, the white-noise sigma a smooth record's sample-to-sample steps show."""
    return np.std(np.diff(a, axis=0), axis=0) / np.sqrt(2.0)


UNIT_OF = ("m", "m", "rad")
FORCE_UNIT_OF = ("N", "N", "N m")


def _si(x: float, unit: str) -> str:
    if unit == "m":
        return f"{1e3 * x:.3g} mm"
    if unit == "rad":
        return f"{x:.3g} rad ({np.degrees(x):.3g} deg)"
    return f"{x:.4g} {unit}"


def save_planar_csv(
    path: str | os.PathLike,
    time: np.ndarray,
    q: np.ndarray,
    f: np.ndarray,
    overwrite: bool = False,
) -> Path:
    """Write a record in SI (header without units), atomically; reads back bit for bit."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise RecordError(f"{path}: exists; pass overwrite=True to replace it")
    t = np.asarray(time, dtype=np.float64).reshape(-1)
    q = np.asarray(q, dtype=np.float64)
    f = np.asarray(f, dtype=np.float64)
    if q.shape != (t.size, 3) or f.shape != (t.size, 3):
        raise RecordError(f"{path}: q and f must be ({t.size}, 3), got {q.shape} and {f.shape}")
    a = np.column_stack([t, q, f])
    if not np.all(np.isfinite(a)):
        raise RecordError(f"{path}: NaN or inf in the data; refusing to write it")
    _check_time(path, t)
    # a plain time column must read as a dynamic test's rate; state seconds when it does not
    head = HEADER_TEXT if is_plausible_rate(t) else HEADER_TEXT.replace("time", "time [s]", 1)
    lines = [head] + [",".join(repr(float(x)) for x in row) for row in a]
    atomic_write(path, lambda fh: fh.write(("\n".join(lines) + "\n").encode()))
    return path
