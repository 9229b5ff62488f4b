"""What a record holds that the models cannot follow, and which of its coordinates carry only
sensor noise: notes for a fit's card and for judging a model on it, for records of C
coordinates (``bushenv.records.Record``)."""

from __future__ import annotations

import numpy as np

START_S = 0.01  # the start a record is judged on
OFFSET_SHARE = 0.03  # force at rest above this share of the record's largest |f|: an offset
NOISE_SIGMAS = 5  # a column within this many noise sigmas carries sensor noise only
REST_SHARE = 0.02  # at rest: |q| over the start below this share of its largest value
DEFLECTED_SHARE = 0.05  # start deflection above this share of the record's largest |q|


def start_notes(record) -> list[str]:
    """What the models cannot follow at the record's start, one line each (empty if none).

    Every model runs free from rest (zero deflection, zero force). A record that starts
    deflected (a preload applied before the recording began) makes its first samples a step
    from rest; a force that reads clearly non-zero while the bushing is at rest (no deflection
    over the start) is an offset (a load cell not zeroed), which no model at rest produces and
    which biases a fit.
    """
    from bushenv.record_columns import columns_of

    columns = columns_of(record.n_coords)
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
        shown = ", ".join(
            f"{columns.displacement[i]} {_si(q0[i], columns.units[i])}"
            for i in np.flatnonzero(deflected)
        )
        notes.append(
            f"{name} line 2: starts deflected ({shown}), not at rest: the models run free "
            "from rest, so its first samples are a step to that deflection; record from rest "
            "(before the preload) for a fair comparison"
        )
    at_rest = np.all(np.abs(record.q[:n]) <= np.maximum(REST_SHARE * q_peak, q_floor))
    offset = np.abs(f0) > np.maximum(OFFSET_SHARE * np.abs(record.f).max(axis=0), f_floor)
    if at_rest and offset.any():
        shown = ", ".join(
            f"{columns.force[i]} {_si(f0[i], columns.force_units[i])}"
            for i in np.flatnonzero(offset)
        )
        notes.append(
            f"{name} line 2: reads {shown} at rest (mean of the first {n} samples, no "
            "deflection): a load-cell offset? Models give zero force at rest; "
            "subtract the offset from the column (zero the load cell) before fitting"
        )
    return notes


def only_noise(q: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(C,) per coordinate of a record (T, C): held at rest (its deflection moves within
    ``NOISE_SIGMAS`` noise sigmas) and its force within that of its sensor's noise, as a preload
    sweep's axial axis: a ratio to noise judges nothing, so such a coordinate gets none."""
    still = np.ptp(q, axis=0) <= NOISE_SIGMAS * noise_sigma(q)
    quiet = np.sqrt(np.mean(f**2, axis=0)) <= NOISE_SIGMAS * noise_sigma(f)
    return still & quiet


def noise_sigma(a: np.ndarray) -> np.ndarray:
    """Per column, the white-noise sigma a smooth record's sample-to-sample steps show."""
    return np.std(np.diff(a, axis=0), axis=0) / np.sqrt(2.0)


def _si(x: float, unit: str) -> str:
    if unit == "m":
        return f"{1e3 * x:.3g} mm"
    if unit == "rad":
        return f"{x:.3g} rad ({np.degrees(x):.3g} deg)"
    return f"{x:.4g} {unit}"
