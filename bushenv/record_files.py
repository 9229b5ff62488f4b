"""Record files of any number of coordinates C: the header decides the columns.

One record type (``bushenv.records.Record``) over C coordinates; its CSV has a time column, C
displacement columns and C force columns (``bushenv.record_columns``): ``time,displacement,
force`` for one coordinate (exactly that order), the three-axis header for the in-plane three
(its names in any order), both read by the one reader, ``bushenv.records.load_csv``, and
written by ``save_csv``. Every file follows the same
rules: finite decimal numbers (plain ones read by numpy's parser, the rest line by line to name
a problem), blank lines only at the end, time strictly increasing with a uniform step (1 % of
dt + 1 ns), at least two samples, a plain time column at a dynamic test's rate, plausibility
limits for columns without a stated unit. Every problem raises ``RecordError`` naming the file,
the line and the value, and the fix.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from bushenv.record_columns import header_coordinates
from bushenv.records import Record, header_fields, load_csv, save_csv


def record_coordinates(path: str | os.PathLike) -> int:
    """How many coordinates the record file's header is meant for (``header_coordinates``;
    an unreadable file: 1, and the reader then names its problem)."""
    return header_coordinates(header_fields(path))


def load_record(path: str | os.PathLike, coords: int | None = None) -> Record:
    """A record of any number of coordinates (``bushenv.records.load_csv``, the one reader);
    ``coords``: the number wanted (a file of another is refused, saying what it holds)."""
    return load_csv(path, coords=coords)


def save_record(record: Record, path: str | os.PathLike, overwrite: bool = False) -> Path:
    """Write ``record`` with the header of its number of coordinates, in SI, atomically;
    reads back bit for bit."""
    return save_csv(record, path, overwrite=overwrite)


def save_columns(
    path: str | os.PathLike,
    time: np.ndarray,
    q: np.ndarray,
    f: np.ndarray,
    overwrite: bool = False,
) -> Path:
    """Write the record of ``time`` (T,), ``q`` and ``f`` ((T,) or (T, C)) (``save_record``)."""
    return save_csv(Record(time, q, f, name=Path(path).stem), path, overwrite=overwrite)
