"""Multi-axis test records as CSV files: one record per file, the one-axis format's rules.

    time,displacement_axial,displacement_radial,rotation,force_axial,force_radial,moment
    0.0,0.0,0.0,0.0,0.0,0.0,0.0
    0.0048828125,1.2e-05,-3.0e-06,0.0011,4.61,-2.3,3.3
    ...

Columns are s, m, m, rad, N, N, N m unless a unit is written after a name in brackets, e.g.
``displacement_axial [mm]``, ``rotation [deg]``, ``moment [N mm]`` (``UNITS``), converted to SI
on load. As for one-axis records (``bushenv.records``): the header exactly so (spaces around
names tolerated), finite decimal numbers, blank lines only at the end, time strictly
increasing with a uniform step (1 % of dt + 1 ns), at least two samples, plausibility limits
for columns without a stated unit. Every problem raises ``RecordError`` naming the file, the
line and the value, and the fix.
"""

from __future__ import annotations

import csv
import io
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bushenv.persist import atomic_write
from bushenv.records import _NAME_UNIT, STEP_ATOL_S, STEP_RTOL, RecordError
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
# Plain-header plausibility (SI): beyond these the unit is almost surely wrong.
PLAUSIBLE = {"displacement": 0.1, "rotation": np.pi, "force": 1.0e6, "moment": 1.0e5}
_HINT = {
    "displacement": "millimetres? write 'displacement_axial [mm]' in the header",
    "rotation": "degrees? write 'rotation [deg]' in the header",
    "force": "write the force unit in the header, e.g. 'force_axial [N]'",
    "moment": "N mm? write 'moment [N mm]' in the header",
}


@dataclass(frozen=True)
class PlanarRecord:
    """time (T,) s; q (T, 3) m, m, rad; f (T, 3) N, N, N m; ``source`` names the file."""

    time: np.ndarray
    q: np.ndarray
    f: np.ndarray
    source: str = ""

    @property
    def dt(self) -> float:
        return float(np.median(np.diff(self.time)))


def _header(path: Path, fields: list[str]) -> np.ndarray:
    """The SI factor per column; ``RecordError`` naming the header problem."""
    factors = np.ones(len(HEADER))
    names = []
    for j, text in enumerate(fields):
        m = _NAME_UNIT.match(text)
        name = (m.group(1) if m else text).strip()
        names.append(name)
        if m and name in _KIND:
            unit, table = m.group(2), UNITS[_KIND[name]]
            if unit not in table:
                raise RecordError(
                    f"{path} line 1: unknown unit {unit!r} for {name}; known: {', '.join(table)}"
                )
            factors[j] = table[unit]
    if tuple(names) != HEADER:
        raise RecordError(
            f"{path} line 1: header '{','.join(fields)}' is not a planar record header; "
            f"expected '{HEADER_TEXT}' (units in brackets allowed, e.g. 'rotation [deg]')"
        )
    return factors


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
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        raise RecordError(f"{path}: empty file; expected the header '{HEADER_TEXT}' and data")
    factors = _header(path, rows[0])
    data = []
    end = len(rows)
    while end > 1 and not "".join(rows[end - 1]).strip():
        end -= 1
    for i in range(1, end):
        row, line = rows[i], i + 1
        if len(row) != len(HEADER):
            raise RecordError(
                f"{path} line {line}: {len(row)} values, expected {len(HEADER)} ({HEADER_TEXT})"
            )
        vals = []
        for name, cell in zip(HEADER, row, strict=True):
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
    a = np.array(data)
    stated = np.array([bool(_NAME_UNIT.match(c)) for c in rows[0]])
    _check_plausible(path, a, stated)
    a = a * factors
    _check_time(path, a[:, 0])
    return PlanarRecord(
        a[:, 0], np.ascontiguousarray(a[:, 1:4]), np.ascontiguousarray(a[:, 4:7]), str(path)
    )


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
    lines = [HEADER_TEXT] + [",".join(repr(float(x)) for x in row) for row in a]
    atomic_write(path, lambda fh: fh.write(("\n".join(lines) + "\n").encode()))
    return path
