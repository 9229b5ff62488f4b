"""Record files of any number of coordinates: the header decides which reader and writer.

One record type (``bushenv.records.Record``) over C coordinates; its CSV is
``time,displacement,force`` for one (``bushenv.records``) and the three-axis header for the
in-plane three (``bushenv.planar.records``). This module sits above both, so neither reader
imports the other.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

from bushenv.planar.records import load_planar_csv, looks_planar, save_planar_csv
from bushenv.records import Record, load_csv, save_csv


def record_coordinates(path: str | os.PathLike) -> int:
    """How many coordinates the record file's header is meant for: 3 for the three-axis header
    (any order, units in brackets, or a misspelt one: ``looks_planar``), else 1 (an unreadable
    file too: the one-axis loader then names its problem)."""
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            first = next(csv.reader(fh), [])
    except (OSError, UnicodeDecodeError, csv.Error):
        return 1
    return 3 if looks_planar(first) else 1


def load_record(path: str | os.PathLike) -> Record:
    """A record of any number of coordinates, each reader's checks applied."""
    return load_planar_csv(path) if record_coordinates(path) == 3 else load_csv(path)


def save_record(record: Record, path: str | os.PathLike, overwrite: bool = False) -> Path:
    """Write ``record`` with the header of its number of coordinates; reads back bit for bit."""
    if record.n_coords == 1:
        return save_csv(record, path, overwrite=overwrite)
    return save_planar_csv(path, record.time, record.q, record.f, overwrite=overwrite)
