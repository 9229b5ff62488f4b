"""Excitation families for the search: a bounded vector u in [0, 1]^d -> one physical profile.

Searchers work in the unit cube; each family maps its coordinates onto physical parameters
within the test machine's limits (``bushenv.excitation``: |x| <= 12.5 mm, |dx/dt| <= 1.257 m/s,
0.1-80 Hz) and builds the signal with the generators of ``bushenv.excitation``. Every rig
profile starts at rest (x[0] = 0), ends in a hold (x constant, so the free response after the
input stops is judged, seed 000 §5.2) and lasts at most ``max_s`` seconds. Road families
(target ``quartercar``) give road height under the wheel instead.

| family      | d | parameters (physical range)                                                 |
|-------------|---|-----------------------------------------------------------------------------|
| step        | 4 | size +-12.5 mm, start 0.1-1 s, rise 0-0.3 s (>= the velocity limit allows), |
|             |   | hold 0.5 s to the rest of ``max_s``                                          |
| ramp        | 4 | end +-12.5 mm, start 0-1 s, ramp 0.02-3 s, hold 0.5 s-rest                   |
| pulse       | 4 | size +-12.5 mm, width 0.01-2 s, edge 0-50 % of width, rest after 0.5 s-rest  |
| sine        | 5 | 0.1-80 Hz (log), amplitude 0.1-12.5 mm (velocity-capped), offset, 0.5-8 s,  |
|             |   | hold after 0.5-4 s                                                           |
| chirp       | 6 | f0, f1 0.1-80 Hz (log), amplitude (capped by the faster end), 1-8 s, linear |
|             |   | or logarithmic sweep, hold after                                             |
| random_ood  | 7 | amplitude index n 1-6.25 (peak 2n mm), band low 0.5-40 Hz, band high up to   |
|             |   | 80 Hz (beyond the 20 Hz training band), offset +-(12.5 mm - peak), 1-8 s,   |
|             |   | seed 0-9999, hold after 0.5-4 s; scaled down if it would exceed 1.257 m/s   |
| sequence    |3x8| three slots, each picks one of the above and its parameters, joined by      |
|             |   | velocity-limited ramps                                                       |
| any         | 8 | u[0] picks the family, u[1:] its parameters (CMA-ES searches over families) |
| bump        | 4 | road bump length 0.2-2 m, height 5-150 mm, speed 1-30 m/s, rest after       |
| pothole     | 5 | length 0.2-2 m, depth 5-150 mm, speed 1-30 m/s, edge 10-45 % of length,     |
|             |   | rest after                                                                   |
|             |   | (road speeds are capped so the road height changes at most 9.7 m/s,         |
|             |   | inside QuarterCar-v0's 0.05 m per step)                                      |

The rig over three coordinates (target ``rig3``, ``families_rig.py``): a (T, 3) profile (axial m,
radial m, rotation rad) within a stroke and rate per coordinate (``limits.CoordinateLimits``: the
rig's, or a user's bushing's from its records):

| family         | d  | parameters                                                               |
|----------------|----|--------------------------------------------------------------------------|
| preload_step   | 6  | preload axis, step axis (one of the other two), preload +-80 % stroke,   |
|                |    | step +-95 % stroke, wait 0.5-2 s after the preload, hold 0.5 s-rest      |
| rotation_sweep | 6  | radial preload +-80 % stroke, rotation 3.3-100 % of its stroke (log),    |
|                |    | f0, f1 0.5-40 Hz (log, linear sweep), 1-6 s, hold 0.5-3 s                |
| orbit          | 6  | axial-radial ellipse: size 5-100 % stroke, minor/major 0-1 (1: circle),  |
|                |    | orientation 0-pi, 0.5-20 Hz (log), sense (ccw/cw), 1-6 s; faded in/out   |
| random3        | 9  | amplitude split (3 weights), peak 10-90 % stroke, band 0.5 to 2-40 Hz,   |
|                |    | radial and rotation lag behind axial 0-1 period of the band's centre,    |
|                |    | seed 0-9999, 1-8 s; one common drive, phase-shifted, then a hold         |
| any3           | 10 | u[0] picks one of the above, u[1:] its parameters (CMA-ES over families) |
| one_axis       | 9  | u[0] picks a coordinate, u[1:] the one-axis ``any`` family's parameters  |
|                |    | (scaled to that coordinate's stroke and rate): a single-axis test, not   |
|                |    | drawn by random search over the planar families                          |

``family.profile(u, dt)`` returns the profile; ``family.describe(u)`` its physical parameters
as a dict (for reports and the corpus). Both are pure functions of ``u``. The families of other
targets are registered by their target's module (``target_halfcar.py``).
"""

from __future__ import annotations

import math

import numpy as np

from bushenv import excitation as ex
from bushenv.registry import Registry
from bushenv.search.families_rig import COMBINED, ONE_COORDINATE
from bushenv.search.family_base import (
    ROAD_MAX_HEIGHT_M,
    ROAD_MAX_RATE_M_PER_S,
    Family,
    FamilyError,
    _lin,
    _log,
)


# ----- road families (quarter car): road height under the wheel, m -------------------------------
def _bump(u, dt, max_s, lim):
    length = _lin(u[0], 0.2, 2.0)
    height = _lin(u[1], 0.005, ROAD_MAX_HEIGHT_M)
    # (1 - cos) bump: peak road rate pi h V / L
    speed = min(_log(u[2], 1.0, 30.0), ROAD_MAX_RATE_M_PER_S * length / (math.pi * height))
    post = _lin(u[3], 1.0, max(1.0, max_s - 0.5 - length / speed))
    x = ex.bump(length, height, speed, dt, pre_s=0.5, post_s=post)
    return x, {"length_m": length, "height_m": height, "speed_m_per_s": speed, "post_s": post}


def _pothole(u, dt, max_s, lim):
    length = _lin(u[0], 0.2, 2.0)
    depth = _lin(u[1], 0.005, ROAD_MAX_HEIGHT_M)
    edge = _lin(u[3], 0.1, 0.45) * length
    # half-cosine edge: peak road rate pi d V / (2 edge)
    speed = min(_log(u[2], 1.0, 30.0), ROAD_MAX_RATE_M_PER_S * 2 * edge / (math.pi * depth))
    post = _lin(u[4], 1.0, max(1.0, max_s - 0.5 - length / speed))
    x = ex.pothole(length, depth, speed, dt, edge_m=edge, pre_s=0.5, post_s=post)
    return x, {
        "length_m": length,
        "depth_m": depth,
        "speed_m_per_s": speed,
        "edge_m": edge,
        "post_s": post,
    }


FAMILIES: Registry[Family] = Registry("excitation family", FamilyError)
ROADS = [Family("bump", 4, "quartercar", _bump), Family("pothole", 5, "quartercar", _pothole)]
for _family in (*ONE_COORDINATE, *ROADS, *COMBINED):
    FAMILIES.add(_family.name, _family)


def get_family(name: str) -> Family:
    return FAMILIES[name]


def pad_batch(profiles: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Stack (T_i,) profiles into a (T, B) array (or (T_i, k) ones into (T, B, k)), each padded
    by holding its last value.

    Returns (x, lengths). Models are causal, so the first T_i samples of column i are exactly
    what profile i alone would give; ``divergence.judge(..., lengths=lengths)`` ignores the rest.
    """
    if not profiles:
        raise FamilyError("pad_batch: no profiles")
    lengths = np.array([len(p) for p in profiles], dtype=np.int64)
    if np.any(lengths < 1):
        raise FamilyError("pad_batch: empty profile")
    T = int(lengths.max())
    x = np.empty((T, len(profiles), *np.shape(profiles[0])[1:]))  # (T, B, 3) for planar
    for i, p in enumerate(profiles):
        x[: len(p), i] = p
        x[len(p) :, i] = p[-1]
    return x, lengths
