"""Measured or simulated test records as CSV files: load, validate, save, resample.

One record type (``Record``) and one reader (``load_csv``) for a bushing of C coordinates: a
time column, C displacement columns and C force columns (``bushenv.record_columns``). One
coordinate (one record per file):

    time,displacement,force
    0.0,0.0,0.0
    0.0048828125,1.2e-05,4.61
    ...

The three in-plane coordinates: ``time,displacement_axial,displacement_radial,rotation,
force_axial,force_radial,moment`` (s, m, m, rad, N, N, N m), its names in any order, units in
brackets (``rotation [deg]``, ``moment [N mm]``), plausibility per kind of column; every other
rule below holds for it too.

- The one-axis header is exactly ``time,displacement,force`` (spaces around names are
  tolerated, nothing else: no extra columns, no other order). Columns are s, m, N, unless a
  column's unit is
  written after its name in brackets, ``displacement [mm]`` or ``force (kN)`` (``UNITS``): the
  values are then converted to SI on load.
- Values are decimal numbers (anything Python's ``float`` reads except NaN and inf), comma
  separated, one sample per line; blank lines are allowed only at the end.
- Time strictly increases with a uniform step, at any rate: the step dt is read from the time
  column (the median step). Every step must be within ``STEP_RTOL`` (1 %) of dt plus
  ``STEP_ATOL_S`` (1e-9 s). At least two samples.
- A time column under a plain ``time`` header must sample at ``PLAUSIBLE_RATE_HZ`` (10 Hz to
  100 kHz: a dynamic test; a time column in milliseconds reads 1000 times slower). A record
  outside it states its time unit in the header: ``time [ms]``, ``time [us]``, or ``time [s]``
  for a slow creep record that really is in seconds (``save_csv`` writes ``time [s]`` then).
- No units row under the header: the units go into the header (``displacement [mm]``).
- Plausibility: ``max |displacement| <= MAX_PLAUSIBLE_DISPLACEMENT_M`` (0.1 m, eight times the
  test machine's stroke; larger values are almost always millimetres) and
  ``max |force| <= MAX_PLAUSIBLE_FORCE_N`` (1 MN, forty times the machine's 25 kN). These are
  overridable checks: ``load_csv(..., max_displacement_m=0.5)`` raises a limit, and a column
  whose unit is written in the header is taken as stated (no limit).
- Files larger than ``MAX_RECORD_BYTES`` (256 MiB, about five million samples) are refused
  before reading. A file of plain numbers (the common case, and what ``save_csv`` writes) is
  read by numpy's parser after one scan for anything unusual; any other file is parsed line by
  line, which finds and names the problem. Both keep ~24-32 bytes per sample.

Every problem raises ``RecordError`` (a ``ValueError``) naming the file, the line and the value,
e.g. ``train.csv line 17: time goes backwards (0.123 after 0.1235)``. ``save_csv`` applies the
same checks before writing, so whatever it writes ``load_csv`` reads back bit for bit (floats
are written with Python's shortest round-trip ``repr``). Saving is atomic (temp file, then
rename) and refuses to replace an existing file unless ``overwrite=True``.
"""

from __future__ import annotations

import array
import csv
import io
import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.persist import atomic_write
from bushenv.record_checks import (  # noqa: F401  (the format's constants, by their names)
    HEADER,
    HEADER_TEXT,
    MAX_PLAUSIBLE_DISPLACEMENT_M,
    MAX_PLAUSIBLE_FORCE_N,
    MAX_RECORD_BYTES,
    NAME_UNIT,
    PLAUSIBLE_RATE_HZ,
    STEP_ATOL_S,
    STEP_RTOL,
    UNITS,
    check_columns,
    check_rate,
    header_problem,
    header_units,
    is_plausible_rate,
    units_row_problem,
)
from bushenv.record_columns import (
    ONE_AXIS,
    Columns,
    RecordError,
    column_order,
    columns_of,
    header_coordinates,
)

_SNIFF_BYTES = 8192
# What numpy's parser reads exactly as the line-by-line parser does (digits, signs, points,
# exponents, commas, blanks, LF and CRLF); a file holding anything else takes the slow path.
_PLAIN_BYTES = b"0123456789+-.eE,\n\r \t"
_BOM = b"\xef\xbb\xbf"
_SCAN_CHUNK_BYTES = 8 * 2**20
_BLANK_LINE = re.compile(rb"(?m)^[ \t\r]*\n")
# First bytes of files people hand over by mistake, so the message can say what it is.
_BINARY_MAGIC = (
    (b"PK\x03\x04", "a zip archive (an .npz model, an .xlsx workbook or a zipped CSV?)"),
    (b"\x89PNG", "a PNG image"),
    (b"\xff\xd8\xff", "a JPEG image"),
    (b"%PDF", "a PDF document"),
    (b"\x1f\x8b", "a gzip-compressed file (decompress it first)"),
    (b"PAR1", "a Parquet file"),
    (b"\x93NUMPY", "a NumPy .npy array"),
    (b"\xd0\xcf\x11\xe0", "an old Excel/Office file"),
    (b"\xff\xfe", "UTF-16 text (save it as UTF-8)"),
    (b"\xfe\xff", "UTF-16 text (save it as UTF-8)"),
)


@dataclass(eq=False)
class Record:
    """One uniformly sampled record of a bushing of C coordinates: ``time`` (T,) s, and
    ``displacement`` and ``force``, (T,) for one coordinate (m, N), (T, C) for several (the
    three in-plane ones: m, m, rad and N, N, N m; ``coords`` names them, read from the shape
    when not given).

    ``name`` labels it in messages (defaults to the file stem on load); ``path`` is the file it
    came from, if any; ``info`` carries notes that are not written to the CSV (e.g. the machine's
    force-limit flag).
    """

    time: np.ndarray
    displacement: np.ndarray
    force: np.ndarray
    name: str = ""
    path: Path | None = None
    info: dict[str, Any] = field(default_factory=dict)
    coords: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        arrays = {k: np.ascontiguousarray(getattr(self, k), dtype=np.float64) for k in HEADER}
        if arrays["time"].ndim != 1:
            raise RecordError(f"{self.label}: time has shape {arrays['time'].shape}, expected (T,)")
        if self.coords is None:
            self.coords = _coords_of(arrays["displacement"])
        c = len(self.coords)
        want = "(T,)" if c == 1 else f"(T, {c}) ({', '.join(self.coords)})"
        for key in HEADER[1:]:
            a = arrays[key]
            if (c == 1 and a.ndim != 1) or (c > 1 and (a.ndim != 2 or a.shape[1] != c)):
                raise RecordError(f"{self.label}: {key} has shape {a.shape}, expected {want}")
        lengths = {k: a.shape[0] for k, a in arrays.items()}
        if len(set(lengths.values())) != 1:
            raise RecordError(f"{self.label}: columns differ in length: {lengths}")
        self.time, self.displacement, self.force = (arrays[k] for k in HEADER)
        self.coords = tuple(self.coords)

    @property
    def n_coords(self) -> int:
        return len(self.coords)

    @property
    def q(self) -> np.ndarray:
        """The displacement as (T, C), whatever C."""
        return self.displacement.reshape(len(self.time), -1)

    @property
    def f(self) -> np.ndarray:
        """The force as (T, C), whatever C."""
        return self.force.reshape(len(self.time), -1)

    @property
    def source(self) -> str:
        """The file it came from, else its name ("" for neither)."""
        return str(self.path) if self.path is not None else self.name

    @classmethod
    def from_arrays(
        cls,
        displacement: np.ndarray,
        force: np.ndarray,
        dt: float,
        t0: float = 0.0,
        name: str = "",
        info: dict[str, Any] | None = None,
    ) -> Record:
        """A record with time ``t0 + i * dt`` for the (T,) ``displacement`` and ``force``."""
        if not (np.isfinite(dt) and dt > 0):
            raise RecordError(f"{name or 'record'}: dt must be a positive number, got {dt!r}")
        n = np.asarray(displacement).shape[0] if np.ndim(displacement) else 0
        return cls(
            time=t0 + np.arange(n) * float(dt),
            displacement=displacement,
            force=force,
            name=name,
            info=dict(info or {}),
        )

    @property
    def label(self) -> str:
        if self.path is not None:
            return str(self.path)
        return self.name or "record"

    def __len__(self) -> int:
        return int(self.time.size)

    @property
    def dt(self) -> float:
        """Mean sample time, s: (last time - first time) / (T - 1)."""
        if self.time.size < 2:
            raise RecordError(f"{self.label}: fewer than two samples, no sample time")
        return float((self.time[-1] - self.time[0]) / (self.time.size - 1))

    @property
    def sample_rate_hz(self) -> float:
        return 1.0 / self.dt

    @property
    def duration_s(self) -> float:
        """T * dt: the span the samples stand for (last time - first time + dt)."""
        return len(self) * self.dt

    def validate(self) -> Record:
        """Apply the file format's checks to the arrays; raise ``RecordError`` or return self."""
        check_columns(
            self.time,
            self.displacement,
            self.force,
            self.label,
            where=lambda i: f"{self.label} sample {i}",
            cols=columns_of(self.n_coords, self.coords),
        )
        return self


def _coords_of(displacement: np.ndarray) -> tuple[str, ...]:
    """The coordinates a displacement array's shape says: one, or the three in-plane ones."""
    if displacement.ndim < 2:
        return ("deflection",)
    if displacement.shape[1] == 3:
        return ("axial", "radial", "rotation")
    return tuple(f"q{i}" for i in range(displacement.shape[1]))


# ----- load ------------------------------------------------------------------------------------
def load_csv(
    path: str | os.PathLike,
    max_bytes: int = MAX_RECORD_BYTES,
    max_displacement_m: float = MAX_PLAUSIBLE_DISPLACEMENT_M,
    max_force_n: float = MAX_PLAUSIBLE_FORCE_N,
    coords: int | None = 1,
) -> Record:
    """Read and validate one record file; refuse anything off-format with ``RecordError``.

    The one reader of record files of C coordinates (``bushenv.record_columns``): the header
    says which columns; ``coords`` the number wanted (1 by default; None: any), a file of
    another number is refused saying which it is.

    Files above ``max_bytes`` are refused before reading. A file of plain numbers under the
    plain header goes through numpy's parser (``_load_plain``: within 2x of ``np.loadtxt``,
    scripts/bench.py); anything else line by line (``_load_line_by_line``), which names the
    first problem's line. Both give the same values and the same messages
    (tests/test_records.py). ``max_displacement_m`` and ``max_force_n`` are the plausibility
    limits; a column whose unit the header states is converted to SI and not limited.
    """
    path = Path(path)
    if not path.exists():
        raise RecordError(f"{path}: no such record file")
    if not path.is_file():
        raise RecordError(f"{path}: not a regular file")
    size = path.stat().st_size
    if size > max_bytes:
        raise RecordError(
            f"{path}: {size / 2**20:.1f} MiB is larger than the {max_bytes / 2**20:.0f} MiB limit "
            "for one record; split it into shorter records"
        )
    if size == 0:
        want = columns_of(coords or 1).header_text
        raise RecordError(f"{path}: empty file; expected the header '{want}' and data")
    with open(path, "rb") as fh:
        head = fh.read(_SNIFF_BYTES)
    for magic, what in _BINARY_MAGIC:
        if head.startswith(magic):
            raise RecordError(f"{path}: binary data ({what}); expected a text CSV file")
    nul = head.find(b"\x00")
    if nul >= 0:
        raise RecordError(f"{path}: binary data (NUL byte at byte {nul}); expected a text CSV file")

    cols = _columns_wanted(path, coords)
    limits = {"max_displacement_m": max_displacement_m, "max_force_n": max_force_n}
    if _plain_numbers(path, cols):
        record = _load_plain(path, cols, **limits)
        if record is not None:
            return record
    return _load_line_by_line(path, cols, **limits)


def header_fields(path: str | os.PathLike) -> list[str]:
    """The record file's first row as fields ([] when unreadable: the reader names why)."""
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            return next(csv.reader(fh), [])
    except (OSError, UnicodeDecodeError, csv.Error):
        return []


def _columns_wanted(path: Path, coords: int | None) -> Columns:
    """The columns to read ``path`` with: those its header is meant for, or those of
    ``coords`` (the reverse direction is named by ``column_order``)."""
    found = header_coordinates(header_fields(path))
    if coords == 1 and found != 1:
        cols = columns_of(found)
        raise RecordError(
            f"{path} line 1: a {found}-axis record ({', '.join(cols.coords)}: header "
            f"'{cols.header_text}'); this needs a one-axis record ('{HEADER_TEXT}'): give "
            f"one-axis records to a one-axis fit, {found}-axis ones to a {found}-axis fit"
        )
    return columns_of(found if coords is None else coords)


def _plain_numbers(path: Path, cols: Columns = ONE_AXIS) -> bool:
    """Whether numpy's parser reads ``path`` exactly as ``_parse`` would: the header on line 1,
    then only plain-number bytes, LF or CRLF line ends, no blank line before the end and no
    line beyond the csv module's field limit. Scanned in chunks of whole lines (memory flat)."""
    limit = csv.field_size_limit()
    with open(path, "rb") as fh:
        head = fh.readline()
        head = head[len(_BOM) :] if head.startswith(_BOM) else head
        if not head.endswith(b"\n") or b'"' in head or not head.isascii():
            return False
        fields = head.decode("ascii").removesuffix("\n").removesuffix("\r")
        if "\r" in fields or tuple(n.strip() for n in fields.split(",")) != cols.names:
            return False  # units in the header, or a header to complain about: line by line
        blank_seen = False
        while chunk := fh.read(_SCAN_CHUNK_BYTES) + fh.readline():
            if chunk.translate(None, _PLAIN_BYTES) or chunk.count(b"\r") != chunk.count(b"\r\n"):
                return False
            blank = _first_blank_line(chunk)
            if blank_seen or blank >= 0:  # blank lines only at the end
                if chunk[max(blank, 0) :].strip():
                    return False
                blank_seen = True
            ends = np.flatnonzero(np.frombuffer(chunk, np.uint8) == 10)
            if np.diff(ends, prepend=-1, append=len(chunk)).max() > limit:
                return False
    return True


def _first_blank_line(chunk: bytes) -> int:
    """Where the first blank (empty or blanks-only) line of ``chunk`` starts, -1 if none;
    ``chunk`` starts at a line start."""
    if b" " in chunk or b"\t" in chunk:  # rare in record files: the slower regex
        m = _BLANK_LINE.search(chunk)
        return m.start() if m else -1
    if chunk.startswith((b"\n", b"\r\n")):
        return 0
    hits = [i + 1 for i in (chunk.find(b"\n\n"), chunk.find(b"\n\r\n")) if i >= 0]
    return min(hits, default=-1)


def _load_plain(
    path: Path,
    cols: Columns = ONE_AXIS,
    max_displacement_m: float = MAX_PLAUSIBLE_DISPLACEMENT_M,
    max_force_n: float = MAX_PLAUSIBLE_FORCE_N,
) -> Record | None:
    """A file of plain numbers through numpy's parser (the same correctly rounded values as
    ``float``), checked like any record; None if numpy refuses it (a wrong count of values, an
    empty field, ...), which the line-by-line parser then names."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "input contained no data": the slow path says more
            a = np.loadtxt(
                path, delimiter=",", skiprows=1, comments=None, ndmin=2, encoding="utf-8-sig"
            )
    except ValueError:
        return None
    if a.shape[1] != len(cols.names) or a.shape[0] < 2 or not np.isfinite(a).all():
        return None
    record = _record_of(path, cols, a)
    # no blank lines before the data ends: sample i is on line i + 2
    where = lambda i: f"{path} line {i + 2}"  # noqa: E731
    check_columns(
        record.time,
        record.displacement,
        record.force,
        str(path),
        where=where,
        max_displacement_m=max_displacement_m,
        max_force_n=max_force_n,
        cols=cols,
    )
    check_rate(record.time, str(path), where)
    return record


def _record_of(path: Path, cols: Columns, a: np.ndarray) -> Record:
    """The record of the (T, 1 + 2C) columns ``a`` in ``cols.names`` order."""
    c = len(cols.coords)
    return Record(
        time=a[:, 0].copy(),
        displacement=a[:, 1].copy() if c == 1 else a[:, 1 : 1 + c].copy(),
        force=a[:, 2].copy() if c == 1 else a[:, 1 + c :].copy(),
        name=path.stem,
        path=path,
        coords=cols.coords,
    )


def _load_line_by_line(
    path: Path,
    cols: Columns = ONE_AXIS,
    max_displacement_m: float = MAX_PLAUSIBLE_DISPLACEMENT_M,
    max_force_n: float = MAX_PLAUSIBLE_FORCE_N,
) -> Record:
    """Parse ``path`` line by line (``_parse``), naming the first problem's line."""
    columns = [array.array("d") for _ in cols.names]
    lines = array.array("q")
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            factors, stated = _parse(fh, path, columns, lines, cols)
    except UnicodeDecodeError as exc:
        raise RecordError(
            f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start} of a read block); "
            "expected a text CSV file"
        ) from None
    except csv.Error as exc:
        raise RecordError(f"{path}: not a readable CSV file: {exc}") from None

    values = [np.frombuffer(a, dtype=np.float64) * k for a, k in zip(columns, factors, strict=True)]
    record = _record_of(path, cols, np.column_stack(values))
    line_of = np.frombuffer(lines, dtype=np.int64)
    if len(record) < 2:
        raise RecordError(
            f"{path}: {'header only, no data' if len(record) == 0 else 'only one data row'}; "
            "need at least 2 samples to know the sample time"
        )
    check_columns(
        record.time,
        record.displacement,
        record.force,
        str(path),
        where=lambda i: f"{path} line {int(line_of[i])}",
        max_displacement_m=np.inf if stated[1] else max_displacement_m,
        max_force_n=np.inf if stated[-1] else max_force_n,
        cols=cols,
        stated=stated,
    )
    if not stated[0]:  # a stated unit is taken as stated
        check_rate(record.time, str(path), lambda i: f"{path} line {int(line_of[i])}")
    return record


def _parse(
    fh: io.TextIOBase, path: Path, columns: list, lines, cols: Columns = ONE_AXIS
) -> tuple[np.ndarray, np.ndarray]:
    """Fill ``columns`` (in ``cols.names`` order); returns the factors to SI of the header's
    stated units and which columns state one."""
    reader = csv.reader(fh, strict=True)
    header = None
    for row in reader:
        if not row or all(not s.strip() for s in row):
            continue
        header = row
        break
    if header is None:
        raise RecordError(
            f"{path}: no header and no data (only blank lines); expected '{cols.header_text}'"
        )
    if reader.line_num != 1:
        raise RecordError(f"{path} line {reader.line_num}: blank lines before the header")
    order, factors, stated = _header_columns(path, header, cols)
    t = columns[0]
    width = len(cols.names)
    blank_at = 0
    last_line = 1
    for row in reader:
        line = reader.line_num
        if line != last_line + 1:
            raise RecordError(f"{path} line {last_line + 1}: a quoted value spans several lines")
        last_line = line
        if not row or all(not s.strip() for s in row):
            blank_at = blank_at or line
            continue
        if blank_at:
            raise RecordError(f"{path} line {blank_at}: blank line inside the data")
        if len(row) != width:
            raise RecordError(
                f"{path} line {line}: {len(row)} value(s) {','.join(row)!r}, expected {width} "
                f"({','.join(h.strip() for h in header)})"
            )
        if not t:
            units_row = units_row_problem(row, header)
            if units_row:
                raise RecordError(f"{path} line {line}: {units_row}")
        for key, column, j in zip(cols.names, columns, order, strict=True):
            text = row[j]
            try:
                value = float(text)
            except ValueError:
                raise RecordError(
                    f"{path} line {line}: {key} {text.strip()!r} is not a number"
                ) from None
            if not np.isfinite(value):
                raise RecordError(
                    f"{path} line {line}: {key} is {text.strip()!r}, expected a finite number"
                )
            column.append(value)
        if len(t) >= 2 and t[-1] <= t[-2]:
            if t[-1] == t[-2]:
                raise RecordError(f"{path} line {line}: time repeats ({t[-1]!r} twice)")
            raise RecordError(
                f"{path} line {line}: time goes backwards ({t[-1]!r} after {t[-2]!r})"
            )
        lines.append(line)
    return factors, stated


def _header_columns(
    path: Path, header: list[str], cols: Columns
) -> tuple[list[int], np.ndarray, np.ndarray]:
    """(file column of each of ``cols.names``, factor to SI of each, whether its unit is
    stated): the one-axis header exactly in order, the others' names in any order."""
    if cols is not ONE_AXIS:
        order, factors = column_order(path, header, cols)
        stated = np.array([bool(NAME_UNIT.match(header[j])) for j in order])
        return list(order), factors, stated
    problem = header_problem(header)
    if problem:
        raise RecordError(f"{path} line 1: {problem}")
    given = header_units(header)[1]
    factors = np.array([given.get(n, 1.0) for n in HEADER])
    return [0, 1, 2], factors, np.array([n in given for n in HEADER])


# ----- save ------------------------------------------------------------------------------------
def save_csv(record: Record, path: str | os.PathLike, overwrite: bool = False) -> Path:
    """Validate ``record`` and write it to ``path`` atomically; returns the path.

    Refuses (``RecordError``) a record ``load_csv`` would refuse, and an existing ``path``
    unless ``overwrite=True``. Its header is that of its number of coordinates
    (``bushenv.record_columns``), in SI; a record sampled outside ``PLAUSIBLE_RATE_HZ`` gets
    ``time [s]`` there, so that it reads back as it was written. The data go
    to a temporary file in the same folder first, so a crash never leaves a half-written
    record under the final name.
    """
    path = Path(path)
    cols = columns_of(record.n_coords)  # the file format's columns (1 or 3 coordinates)
    record.validate()
    if path.exists() and not overwrite:
        raise RecordError(f"{path} already exists; refusing to overwrite it (pass overwrite=True)")
    head = cols.header_text
    head = (head if is_plausible_rate(record.time) else head.replace("time", "time [s]", 1)) + "\n"
    # tolist() gives Python floats, whose repr is the shortest exact round-trip text.
    rows = np.column_stack([record.time, record.q, record.f]).tolist()
    text = head + "".join(",".join(map(repr, row)) + "\n" for row in rows)
    try:
        atomic_write(path, lambda fh: fh.write(text.encode("utf-8")), replace=overwrite)
    except FileExistsError:  # appeared while writing: never replaced silently
        raise RecordError(
            f"{path} already exists; refusing to overwrite it (pass overwrite=True)"
        ) from None
    return path


# ----- resample --------------------------------------------------------------------------------
def resample(record: Record, dt: float) -> Record:
    """The record linearly interpolated onto times t0, t0 + dt, ... up to its last time.

    For matching the rates of two records before comparing them. No anti-alias filter: when
    going to a coarser step, low-pass the record first if it holds content above the new
    Nyquist frequency.
    """
    if not (np.isfinite(dt) and dt > 0):
        raise RecordError(f"{record.label}: resample dt must be a positive number, got {dt!r}")
    if len(record) < 2:
        raise RecordError(f"{record.label}: fewer than two samples, cannot resample")
    t0, t1 = float(record.time[0]), float(record.time[-1])
    n = int(np.floor((t1 - t0) / dt + 1e-9)) + 1
    if n < 2:
        raise RecordError(
            f"{record.label}: lasts {t1 - t0:.6g} s, shorter than one step of the new dt={dt!r}"
        )
    t = t0 + np.arange(n) * float(dt)
    t[-1] = min(t[-1], t1)

    def interp(a: np.ndarray) -> np.ndarray:  # each coordinate's column on its own
        cols = [np.interp(t, record.time, c) for c in a.reshape(len(record), -1).T]
        return cols[0] if a.ndim == 1 else np.column_stack(cols)

    return Record(
        time=t,
        displacement=interp(record.displacement),
        force=interp(record.force),
        name=record.name,
        info=dict(record.info),
        coords=record.coords,
    )
