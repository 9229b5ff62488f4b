"""Records read together by one command: one sample rate, or the resampling the user asked for.

``bushenv fit`` and ``bushenv diagnose`` refuse records at different sample rates unless
``--resample HZ`` says how to bring them to one rate (linear interpolation onto HZ,
``records.resample``: no anti-alias filter, so going coarser than a record's own rate folds
its content above the new Nyquist frequency back -- low-pass such a record first). For
``diagnose``, whose default linear baseline and candidates are continuous-time,
``--resample keep`` judges each record at its own rate instead. A mixed-rate set is refused
because a record whose time column is in the wrong unit looks exactly like one (a 20 kHz
record in milliseconds reads as 20 Hz).
"""

from __future__ import annotations

from collections.abc import Sequence

from bushenv.records import Record, RecordError, resample

RATE_RTOL = 1e-6  # two records whose sample times differ by less are at the same rate
KEEP = "keep"


def _where(rec: Record) -> str:
    # data start on line 2 of a record file (no blank line before the data), so the step
    # that sets the rate is first seen on line 3
    return f"{rec.path} line 3" if rec.path is not None else f"{rec.label} sample 1"


def one_rate(
    groups: Sequence[Sequence[Record]], how: float | str | None, command: str
) -> list[list[Record]]:
    """``groups`` of records (e.g. training and held-out) at one sample rate.

    ``how`` is ``--resample``'s value: None refuses records at different rates (``RecordError``
    naming both files, their rates and the fix), a rate in Hz resamples every record not
    already at it, ``"keep"`` returns them as they are.
    """
    records = [r for g in groups for r in g]
    if how == KEEP or not records:
        return [list(g) for g in groups]
    if how is None:
        first = records[0]
        for rec in records[1:]:
            if abs(rec.dt - first.dt) > RATE_RTOL * first.dt:
                keep = (
                    f", or --resample {KEEP} (each judged at its own rate)"
                    if command == "diagnose"
                    else ""
                )
                raise RecordError(
                    f"{_where(rec)}: sampled at {rec.sample_rate_hz:.6g} Hz (time step "
                    f"{rec.dt:.6g} s), {first.label} at {first.sample_rate_hz:.6g} Hz: records "
                    f"at different sample rates in one {command}; check both time columns' "
                    f"units, then say how to bring them to one rate: --resample "
                    f"{first.sample_rate_hz:.6g} (linear interpolation){keep}, or resample "
                    "them yourself first"
                )
        return [list(g) for g in groups]
    dt = 1.0 / float(how)
    return [[_at(rec, dt) for rec in g] for g in groups]


def _at(rec: Record, dt: float) -> Record:
    if abs(rec.dt - dt) <= RATE_RTOL * dt:
        return rec
    out = resample(rec, dt)
    out.name = f"{rec.name or rec.label} (resampled {rec.sample_rate_hz:.6g} -> {1 / dt:.6g} Hz)"
    out.info["resampled_from"] = {
        "file": str(rec.path) if rec.path else None,
        "hz": rec.sample_rate_hz,
    }
    return out
