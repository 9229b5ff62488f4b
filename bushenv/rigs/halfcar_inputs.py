"""HalfCar-v0's inputs: an action cleaned to (3,) (road left, road right, lateral load) and
the replayed manoeuvre of ``reset(options=...)`` checked against the same limits."""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.rigs.actions import _array, check_profile, describe
from bushenv.rigs.common import RigError
from bushenv.rigs.halfcar_params import ENV_ID, HalfCarParameters

REPLAY_KEYS = ("road_left", "road_right", "lateral_accel")


def unit_actions3(action: Any) -> np.ndarray:
    """A (3,) action cleaned as the other rigs' (NaN -> 0, clipped to [-1, 1]); anything that is
    not three real numbers is refused naming the action space."""
    arr = action if action.__class__ is np.ndarray else _array(action)
    if arr is None or arr.dtype.kind not in "fiu" or arr.shape != (3,):
        raise RigError(
            f"{ENV_ID}: action {describe(action)} does not fit the action space Box(-1.0, 1.0, "
            "(3,), float32): expected three real numbers (road left, road right, lateral load)"
        )
    a = arr.astype(np.float64)
    a[np.isnan(a)] = 0.0
    return np.clip(a, -1.0, 1.0)


def replay_inputs(p: HalfCarParameters, options: dict[str, Any]) -> np.ndarray | None:
    """(T, 3) replayed inputs (road left, road right, a_y) from ``reset`` options, or None."""
    unknown = sorted(set(options) - set(REPLAY_KEYS))
    if unknown:
        raise RigError(f"{ENV_ID}: unknown reset option(s) {unknown}; known: {list(REPLAY_KEYS)}")
    given = {k: v for k, v in options.items() if v is not None}
    if not given:
        return None
    cols = {}
    for k, v in given.items():
        if k == "lateral_accel":
            a = check_profile(k, v, k, p.max_ay, "|a_y| = {value:.6g} m/s^2 exceeds "
                              f"max_lateral_accel_m_per_s2 {p.max_ay:.6g}", p.max_ay_step,
                              "a change of {value:.6g} m/s^2 exceeds "
                              f"max_lateral_accel_step_m_per_s2 {p.max_ay_step:.6g}")  # fmt: skip
        else:
            a = check_profile(k, v, k, p.max_road, "|h| = {value:.6g} m exceeds "
                              f"max_road_height_m {p.max_road:.6g} m", p.max_road_step,
                              "a change of {value:.6g} m exceeds "
                              f"max_road_step_m {p.max_road_step:.6g} m")  # fmt: skip
        if a.ndim != 1:
            raise RigError(f"{ENV_ID}: reset option {k} must be (T,), got {a.shape}")
        cols[k] = a
    lengths = {k: len(a) for k, a in cols.items()}
    if len(set(lengths.values())) > 1:
        raise RigError(f"{ENV_ID}: replayed inputs differ in length: {lengths}")
    t = next(iter(lengths.values()))
    return np.stack([cols.get(k, np.zeros(t)) for k in REPLAY_KEYS], axis=1)
