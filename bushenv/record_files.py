"""Record files of any number of coordinates C: the header decides the columns.

One record type (``bushenv.records.Record``) over C coordinates; its CSV has a time column, C
displacement columns and C force columns (``bushenv.record_columns``): ``time,displacement,
force`` for one coordinate, read by ``bushenv.records.load_csv`` (exactly that order); the
three-axis header for the in-plane three, its names in any order. Every file follows the same
rules: finite decimal numbers (plain ones read by numpy's parser, the rest line by line to name
a problem), blank lines only at the end, time strictly increasing with a uniform step (1 % of
dt + 1 ns), at least two samples, a plain time column at a dynamic test's rate, plausibility
limits for columns without a stated unit. Every problem raises ``RecordError`` naming the file,
the line and the value, and the fix.
"""

from __future__ import annotations

import csv
import io
import os
import re
import warnings
from pathlib import Path

import numpy as np

from bushenv.persist import atomic_write
from bushenv.record_columns import (
    HINT,
    NAME_UNIT,
    ONE_AXIS,
    PLAUSIBLE,
    SI,
    Columns,
    column_order,
    columns_of,
    header_coordinates,
)
from bushenv.records import (
    STEP_ATOL_S,
    STEP_RTOL,
    Record,
    RecordError,
    check_rate,
    is_plausible_rate,
    load_csv,
    save_csv,
)


def record_coordinates(path: str | os.PathLike) -> int:
    """How many coordinates the record file's header is meant for (``header_coordinates``;
    an unreadable file: 1, and the one-axis loader then names its problem)."""
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            first = next(csv.reader(fh), [])
    except (OSError, UnicodeDecodeError, csv.Error):
        return 1
    return header_coordinates(first)


def load_record(path: str | os.PathLike, coords: int | None = None) -> Record:
    """A record of any number of coordinates, the checks of the module doc applied; ``coords``:
    the number wanted (a file of another is refused, saying what it holds)."""
    found = record_coordinates(path)
    c = found if coords is None else coords
    if c == 1 and found != 1:  # the reverse says so in ``column_order``
        cols = columns_of(found)
        raise RecordError(
            f"{path} line 1: a {found}-axis record ({', '.join(cols.coords)}: header "
            f"'{cols.header_text}'); this needs a one-axis record ('{ONE_AXIS.header_text}'): "
            f"give one-axis records to a one-axis fit, {found}-axis ones to a {found}-axis fit"
        )
    return load_csv(path) if c == 1 else load_columns(path, columns_of(c))


def save_record(record: Record, path: str | os.PathLike, overwrite: bool = False) -> Path:
    """Write ``record`` with the header of its number of coordinates, in SI (no units in the
    header), atomically; reads back bit for bit."""
    if record.n_coords == 1:
        return save_csv(record, path, overwrite=overwrite)
    return save_columns(path, record.time, record.q, record.f, overwrite=overwrite)


def load_columns(path: str | os.PathLike, cols: Columns) -> Record:
    """Read and check one record of the columns ``cols`` (names in any order)."""
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
        raise RecordError(f"{path}: empty file; expected the header '{cols.header_text}' and data")
    order, factors = column_order(path, fields, cols)
    a = _plain_rows(body, len(cols.names))
    a = _parse_rows(path, text, order, cols) if a is None else a[:, order]
    stated = np.array([bool(NAME_UNIT.match(fields[j])) for j in order])
    _check_plausible(path, a, stated, cols)
    a = a * factors
    _check_time(path, a[:, 0])
    if not stated[0]:
        check_rate(a[:, 0], str(path), lambda i: f"{path} line {i + 2}")
    c = len(cols.coords)
    return Record(
        a[:, 0],
        np.ascontiguousarray(a[:, 1 : 1 + c]),
        np.ascontiguousarray(a[:, 1 + c :]),
        name=path.stem,
        path=path,
        coords=cols.coords,
    )


_PLAIN = str.maketrans("", "", "0123456789+-.eE,\n\r \t")  # what numpy reads as float does
_BLANK_LINE = re.compile(r"(?:^|\n)[ \t\r]*(?:\n|$)")


def _plain_rows(body: str, width: int) -> np.ndarray | None:
    """The data through numpy's parser when they are plain numbers, ``width`` a line, no blank
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
    ok = a.shape[0] >= 2 and a.shape[1] == width and np.isfinite(a).all()
    return a if ok else None


def _parse_rows(path: Path, text: str, order: np.ndarray, cols: Columns) -> np.ndarray:
    """(T, 1 + 2C) in ``cols.names`` order, line by line; ``RecordError`` naming the first bad
    line."""
    rows = list(csv.reader(io.StringIO(text)))
    width = len(cols.names)
    data = []
    end = len(rows)
    while end > 1 and not "".join(rows[end - 1]).strip():
        end -= 1
    for i in range(1, end):
        row, line = rows[i], i + 1
        if len(row) != width:
            raise RecordError(
                f"{path} line {line}: {len(row)} values, expected {width} as the header "
                f"has ({','.join(f.strip() for f in rows[0])})"
            )
        vals = []
        for name, cell in zip(cols.names, (row[j] for j in order), strict=True):
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


def _check_plausible(path: Path, a: np.ndarray, stated: np.ndarray, cols: Columns) -> None:
    for j, (name, kind) in enumerate(zip(cols.names, cols.kinds, strict=True)):
        if j == 0:
            continue
        i = int(np.argmax(np.abs(a[:, j])))
        if not stated[j] and abs(a[i, j]) > PLAUSIBLE[kind]:
            raise RecordError(
                f"{path} line {i + 2}: {name} {float(a[i, j])!r} exceeds {PLAUSIBLE[kind]:g} "
                f"{SI[kind]}: {HINT[kind]}"
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


def save_columns(
    path: str | os.PathLike,
    time: np.ndarray,
    q: np.ndarray,
    f: np.ndarray,
    overwrite: bool = False,
) -> Path:
    """Write a record of C coordinates ((T,) time, (T, C) q and f) in SI (header without
    units), atomically; reads back bit for bit."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise RecordError(f"{path}: exists; pass overwrite=True to replace it")
    t = np.asarray(time, dtype=np.float64).reshape(-1)
    q = np.asarray(q, dtype=np.float64)
    f = np.asarray(f, dtype=np.float64)
    c = q.shape[1] if q.ndim == 2 else 0
    if q.shape != (t.size, c) or f.shape != (t.size, c) or c < 2:
        raise RecordError(
            f"{path}: q and f must be ({t.size}, C) with C >= 2, got {q.shape} and {f.shape}"
        )
    cols = columns_of(c)
    a = np.column_stack([t, q, f])
    if not np.all(np.isfinite(a)):
        raise RecordError(f"{path}: NaN or inf in the data; refusing to write it")
    _check_time(path, t)
    # a plain time column must read as a dynamic test's rate; state seconds when it does not
    head = cols.header_text
    head = head if is_plausible_rate(t) else head.replace("time", "time [s]", 1)
    lines = [head] + [",".join(repr(float(x)) for x in row) for row in a]
    atomic_write(path, lambda fh: fh.write(("\n".join(lines) + "\n").encode()))
    return path
