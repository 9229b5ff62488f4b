"""What only a coupling does: a coordinate's stiffness that follows another coordinate's
deflection, tested where the one-axis candidates leave a gap (diagnosis over C coordinates).

The one-axis candidates see their coordinate's own deflection. An elastic coupling -- radial
deflection stiffening axial shear, a radial force falling under rotation (Kadlowec, Wineman &
Hulbert 2003) -- is to lowest order the gradient of a strain energy ``sum a_ij q_i^2 q_j^2``,
a force ``q_i q_j^2`` on coordinate i for each other coordinate j. The test fits coordinate
i's force (less the baseline's fixed cross-coordinate terms) by least squares on

    own:      k q_i + c v_i + h q_i^3                (spring, damper, the coordinate's own cubic)
    coupled:  own + sum_{j != i} g_j q_i q_j^2

on the engine's folds (each judged record by a fit on the others) and measures what the
coupling terms close beyond ``own``, above the force's noise, as a share of the null's gap
above the noise (``closes``). ``COUPLING_MIN`` of it names ``coupling`` where the one-axis
diagnosis answered ``outside_candidates``, or named an effect whose judged gap is more than
1 / ``COUPLING_BEATS`` times the coupled fit's; the partner coordinates are those whose term
alone closes at least half as much.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.models.base import velocity_of

COUPLING_MIN = 0.5  # share of the null's gap above the noise the coupling terms must close
COUPLING_BEATS = 0.7  # ... and leave less than this share of the named candidate's gap


def _columns(q: np.ndarray, i: int, dt: float, partners: list[int]) -> np.ndarray:
    qi = q[:, i]
    cols = [qi, velocity_of(qi, dt), qi**3] + [qi * q[:, j] ** 2 for j in partners]
    return np.stack(cols, axis=1)


def _judged(records: dict, folds: list[dict], i: int, partners: list[int], n_own: int) -> dict:
    """Per judged record, the prediction fitted on its fold's identification records
    (``n_own`` of the columns: 2 the null, 3 own, all with the partners)."""
    cols = {n: _columns(r["q"], i, r["dt"], partners)[:, :n_own] for n, r in records.items()}
    out = {}
    for fold in folds:
        a = np.vstack([cols[n] for n in fold["identified_on"]])
        y = np.concatenate([records[n]["force"] for n in fold["identified_on"]])
        scale = np.sqrt(np.mean(a * a, axis=0))
        scale[scale == 0] = 1.0
        w = np.linalg.lstsq(a / scale, y, rcond=None)[0] / scale
        for n in fold["judged"]:
            out[n] = cols[n] @ w
    return out


def coupling_test(
    records: dict[str, dict[str, Any]],
    folds: list[dict],
    i: int,
    coords: list[str],
    gap_noise: float,
) -> dict[str, Any]:
    """The coupling test on coordinate ``i``.

    ``records``: per name, ``q`` (T, C), ``force`` (T,) the coordinate's force less the
    baseline's cross-coordinate terms, ``dt``; ``folds``: the engine's ``records.folds``;
    ``gap_noise``: the force's noise as a gap of the judged force. Returns ``closes``,
    ``gap_null``, ``gap_own``, ``gap_coupled`` (judged, as ratios to the judged force's RMS),
    ``partners`` (coordinate names) and ``predictions`` (per judged record, the coupled fit).
    """
    others = [j for j in range(len(coords)) if j != i]
    judged = [n for f in folds for n in f["judged"]]
    force = np.concatenate([records[n]["force"] for n in judged])
    rms = float(np.sqrt(np.mean(force**2)))

    def gap(pred: dict) -> float:
        r = force - np.concatenate([pred[n] for n in judged])
        return float(np.sqrt(np.mean(r**2))) / rms if rms > 0 else 0.0

    def excess(g: float) -> float:
        return float(np.sqrt(max(g * g - gap_noise**2, 0.0)))

    null = gap(_judged(records, folds, i, others, 2))
    own = gap(_judged(records, folds, i, others, 3))
    full_pred = _judged(records, folds, i, others, 3 + len(others))
    coupled = gap(full_pred)
    base = excess(null)
    closes = (excess(own) - excess(coupled)) / base if base > 0 else 0.0
    alone = {}
    for j in others:
        g = gap(_judged(records, folds, i, [j], 4))
        alone[coords[j]] = (excess(own) - excess(g)) / base if base > 0 else 0.0
    best = max(alone.values()) if alone else 0.0
    partners = [c for c, v in alone.items() if best > 0 and v >= 0.5 * best]
    return {
        "closes": closes,
        "closes_alone": alone,
        "gap_null": null,
        "gap_own": own,
        "gap_coupled": coupled,
        "partners": sorted(partners, key=lambda c: -alone[c]),
        "form": "k q_i + c v_i + h q_i^3 + sum_j g_j q_i q_j^2 (j the other coordinates)",
        "predictions": full_pred,
    }
