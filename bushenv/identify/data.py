"""What identification trains on: one or several records, each its own history, at one rate.

``training_set(records)`` checks the records where they enter (finite, same sample rate, same
number of coordinates C, long enough, not constant) and returns a ``TrainingSet``: per record
the displacement x (m, or rad for a rotation), force f (N, or N m) and velocity v (the central
difference of x unless given), (T_r,) each for one coordinate and (T_r, C) each for C, as
``bushenv.records.Record`` holds them. Every method treats each record as starting from rest
and never lets a sample's history reach into another record.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bushenv.errors import BadInput
from bushenv.models.base import velocity_of

MIN_SAMPLES = 10  # a record shorter than this identifies nothing
RATE_RTOL = 1e-6  # two records whose sample times differ by less are at the same rate


class IdentificationError(BadInput):
    """Identification data or options are unusable; the message names the record or option."""


@dataclass(frozen=True)
class Segment:
    """One record's arrays, (T,) or (T, C) each: x, f, v; ``label`` names it in messages."""

    x: np.ndarray
    f: np.ndarray
    v: np.ndarray
    label: str

    def __len__(self) -> int:
        return int(self.x.shape[0])


@dataclass(frozen=True)
class TrainingSet:
    """Records of one bushing sampled every ``dt`` s (``segments`` in the given order), all
    of its ``coords`` (``bushenv.records.Record.coords``)."""

    segments: tuple[Segment, ...]
    dt: float
    coords: tuple[str, ...] = ("deflection",)

    @property
    def n_coords(self) -> int:
        return len(self.coords)

    def histories(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(q (T, C), f (T, C)) of every record, whatever C."""
        return [(s.x.reshape(len(s), -1), s.f.reshape(len(s), -1)) for s in self.segments]

    @property
    def labels(self) -> list[str]:
        return [s.label for s in self.segments]

    def concatenated(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """x, f, v of every record end to end: for fits without memory (least squares)."""
        return tuple(np.concatenate([getattr(s, k) for s in self.segments]) for k in "xfv")


def check_record(x, f, dt: float, v=None, label: str = "record") -> Segment:
    """Validate one displacement/force record, (T,) each or (T, C) each; the velocity
    defaults to the central difference of x. Raises ``IdentificationError`` naming ``label``
    and the bad value."""
    x = np.asarray(x, dtype=np.float64)
    f = np.asarray(f, dtype=np.float64)
    if x.ndim not in (1, 2) or f.shape != x.shape:
        raise IdentificationError(
            f"{label}: x and f must be (T,) or (T, C) arrays of equal length and shape, got "
            f"{x.shape} and {f.shape}"
        )
    if x.shape[0] < MIN_SAMPLES:
        raise IdentificationError(
            f"{label}: record too short: {x.shape[0]} samples (need at least {MIN_SAMPLES})"
        )
    if not (np.isfinite(dt) and dt > 0):
        raise IdentificationError(f"dt must be a positive number of seconds, got {dt!r}")
    for name, a in (("x", x), ("f", f)):
        bad = np.argwhere(~np.isfinite(a))
        if bad.size:
            at = tuple(int(i) for i in bad[0])
            where = ", ".join(map(str, at))
            raise IdentificationError(f"{label}: {name}[{where}] is {a[at]}: record holds NaN/inf")
    if v is None:
        v = velocity_of(x, dt)
    else:
        v = np.asarray(v, dtype=np.float64)
        if v.shape != x.shape or not np.all(np.isfinite(v)):
            raise IdentificationError(
                f"{label}: v must be finite with shape {x.shape}, got {v.shape}"
            )
    if np.all(np.ptp(x, axis=0) == 0):
        raise IdentificationError(f"{label}: x is constant: nothing to identify")
    return Segment(x, f, v, label)


def record_label(record, index: int) -> str:
    """How a record is named in messages: its file, its name, or its position."""
    path = getattr(record, "path", None)
    if path is not None:
        return os.fspath(path)
    return getattr(record, "name", "") or f"record {index + 1}"


def rate_of(record, label: str) -> float:
    """The record's sample time, s (``Record.dt``)."""
    try:
        return float(record.dt)
    except ValueError as exc:
        raise IdentificationError(f"{label}: {exc}") from None


def check_same_rate(records: Sequence, what: str = "records") -> float:
    """The common sample time of ``records``, s; refuses records at different rates, naming
    both files and both rates."""
    first_label, first_dt = "", 0.0
    for i, rec in enumerate(records):
        label = record_label(rec, i)
        rdt = rate_of(rec, label)
        if i == 0:
            first_label, first_dt = label, rdt
        elif abs(rdt - first_dt) > RATE_RTOL * first_dt:
            raise IdentificationError(
                f"{what} at different sample rates: {label} at {1 / rdt:.6g} Hz, "
                f"{first_label} at {1 / first_dt:.6g} Hz; resample them to one rate "
                "(bushenv.records.resample)"
            )
    if not first_label:
        raise IdentificationError(f"no {what} given")
    return first_dt


def check_model_rate(record, dt: float, index: int = 0) -> None:
    """Refuse a record at another rate than a model's ``dt``, naming both rates."""
    label = record_label(record, index)
    rdt = rate_of(record, label)
    if abs(rdt - dt) > RATE_RTOL * dt:
        raise IdentificationError(
            f"{label} is sampled at {1 / rdt:.6g} Hz, the model at {1 / dt:.6g} Hz (the rate "
            "of its training records); resample it (bushenv.records.resample)"
        )


def training_set(records: Sequence, velocities: Sequence | None = None) -> TrainingSet:
    """Check ``records`` (objects with ``displacement``, ``force``, ``dt``: ``bushenv.records.
    Record``, of any one number of coordinates) and return their arrays; ``velocities`` (one
    array shaped as the displacement, or None, per record) replace the central-difference
    velocity."""
    records = list(records)
    if not records:
        raise IdentificationError("no training records given")
    coords = check_same_coordinates(records, what="training records")
    dt = check_same_rate(records, what="training records")
    velocities = list(velocities) if velocities is not None else [None] * len(records)
    if len(velocities) != len(records):
        raise IdentificationError(f"{len(velocities)} velocity arrays for {len(records)} records")
    segments = tuple(
        check_record(r.displacement, r.force, dt, v, record_label(r, i))
        for i, (r, v) in enumerate(zip(records, velocities, strict=True))
    )
    return TrainingSet(segments, dt, coords)


def coordinates_of(record) -> tuple[str, ...]:
    """The coordinates a record holds (``Record.coords``; one deflection for plain arrays)."""
    coords = getattr(record, "coords", None)
    if coords:
        return tuple(coords)
    shape = np.shape(record.displacement)
    return ("deflection",) if len(shape) == 1 else tuple(f"coordinate {i}" for i in
                                                         range(shape[1]))  # fmt: skip


def coordinate_text(coords: Sequence[str]) -> str:
    """How messages name a record's kind: one-axis, or C-axis with its coordinates."""
    if len(coords) == 1:
        return "a one-axis record"
    return f"a {len(coords)}-axis record ({', '.join(coords)})"


def check_same_coordinates(records: Sequence, what: str = "records") -> tuple[str, ...]:
    """The coordinates every record of ``records`` holds; refuses a mix, naming one record of
    each kind."""
    first = coordinates_of(records[0])
    for i, rec in enumerate(records[1:], start=1):
        other = coordinates_of(rec)
        if other != first:
            raise IdentificationError(
                f"{what} of different kinds: {record_label(records[0], 0)} is "
                f"{coordinate_text(first)}, {record_label(rec, i)} is {coordinate_text(other)}; "
                "give records of one kind to one fit"
            )
    return first
