"""What ``HalfCarBatch`` reads off its cars each step, as arrays: ``halfcar_outputs``' body,
wheel and geometry outputs and its bounds, for every column at once, and the step's result
under the env's ``info`` keys."""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.rigs.halfcar_batch_kernels import ANG, PX, PY, VX, VY, W, bounds_kernel
from bushenv.rigs.halfcar_batch_layout import UPRIGHT
from bushenv.rigs.halfcar_car import SIGN
from bushenv.rigs.halfcar_outputs import PIVOT_KEYS
from bushenv.rigs.halfcar_params import SIDES, HalfCarParameters

CAR_KEYS = (
    "body_y_m", "body_x_m", "body_vx_m_per_s", "body_vy_m_per_s",
    "body_vertical_accel_m_per_s2", "body_lateral_accel_m_per_s2", "roll_rad",
    "roll_rate_rad_per_s",
    *(f"{k}_{side}{u}" for side in SIDES
      for k, u in (("wheel_load", "_n"), ("wheel_lift", ""), ("camber", "_rad"),
                   ("travel", "_m"), ("wheel", "_y_m"))),
    "track_change_m",
)  # fmt: skip
INPUT_KEYS = ("road_left_m", "road_right_m", "lateral_accel_m_per_s2")
RESULT_KEYS = (
    *INPUT_KEYS,
    *CAR_KEYS,
    *("reference_" + k for k in CAR_KEYS),
    *(k for force_keys, _, _ in PIVOT_KEYS for pair in force_keys for k in pair),
    *(k for _, motion, reference in PIVOT_KEYS for k in (*motion, *reference)),
    "error_n", "roll_error_rad", "reference_outside_range", "diverged", "physical_limit",
)  # fmt: skip


def car_outputs(
    p: HalfCarParameters, S: np.ndarray, contact: np.ndarray, roads, road_v, prev_v, ay
) -> dict[str, np.ndarray]:
    """``halfcar_outputs.car_outputs`` of every column of state ``S`` after a step: ``roads``,
    ``road_v`` (2, N) the road heights and their speeds over the step, ``prev_v`` (2, N) the
    bodies' (vx, vy) a step ago (updated), ``ay`` (N,) the lateral load."""
    x, y, vx, vy = S[PX, 0], S[PY, 0], S[VX, 0], S[VY, 0]
    phi = S[ANG, 0]
    out = {
        "body_y_m": y - p.h_cg, "body_x_m": x.copy(), "body_vx_m_per_s": vx.copy(),
        "body_vy_m_per_s": vy.copy(), "body_vertical_accel_m_per_s2": (vy - prev_v[1]) / p.dt,
        "body_lateral_accel_m_per_s2": ay + (vx - prev_v[0]) / p.dt,
        "roll_rad": phi.copy(), "roll_rate_rad_per_s": S[W, 0].copy(),
    }  # fmt: skip
    prev_v[0], prev_v[1] = vx, vy
    cos, sin = np.cos(phi), np.sin(phi)
    contact_x = []
    for k, side in enumerate(SIDES):
        u = UPRIGHT[side]
        psi = S[ANG, u]
        wx, wy = S[PX, u], S[PY, u]
        sp, cp = np.sin(psi), np.cos(psi)
        cx, cy = wx + sp * p.r_w, wy - cp * p.r_w
        cvy = S[VY, u] + S[W, u] * sp * p.r_w
        contact_x.append(cx)
        load = p.k_t * (roads[k] - cy) + np.where(contact[k] > 0, p.c_t * (road_v[k] - cvy), 0.0)
        load = np.maximum(p.tyre_static_n + load, 0.0)
        out[f"wheel_load_{side}_n"] = load
        out[f"wheel_lift_{side}"] = load <= 0.0
        out[f"camber_{side}_rad"] = -SIGN[side] * psi
        out[f"travel_{side}_m"] = -sin * (wx - x) + cos * (wy - y) - (p.r_w - p.h_cg)
        out[f"wheel_{side}_y_m"] = wy - p.r_w
    out["track_change_m"] = contact_x[0] - contact_x[1] - p.track
    return out


def out_of_bounds(p: HalfCarParameters, out: dict[str, np.ndarray], q: np.ndarray) -> np.ndarray:
    """(N,) bool: ``halfcar_outputs.out_of_bounds`` of every column (``q`` (N, 4, 3) the
    pivots' deflections at the step's start)."""
    body = np.stack([out["body_x_m"], out["body_y_m"], out["wheel_left_y_m"],
                     out["wheel_right_y_m"]])  # fmt: skip
    travel = np.stack([out[f"travel_{side}_m"] for side in SIDES])
    bad = np.empty(len(q), dtype=bool)
    bounds_kernel(body, out["roll_rad"], travel, q, p.max_body, p.max_roll, p.max_travel,
                  p.max_deflection, bad)  # fmt: skip
    return bad


def _sources() -> dict[str, tuple]:
    """Where each result key is read, in the order a step's result lists them: ("input", row),
    ("car", output key, role), ("pivot", array, pivot, coordinate, role) with role 0 the model
    car and 1 its twin, ("twins",) the keys that compare the two, ("flag", attribute)."""
    src: dict[str, tuple] = {k: ("input", i) for i, k in enumerate(INPUT_KEYS)}
    for k in CAR_KEYS:
        src[k], src["reference_" + k] = ("car", k, 0), ("car", k, 1)
    for i, (force_keys, motion, reference) in enumerate(PIVOT_KEYS):
        for c, (key_m, key_r) in enumerate(force_keys):
            src[key_m], src[key_r] = ("pivot", "forces", i, c, 0), ("pivot", "forces", i, c, 1)
        for c in range(3):
            src[motion[c]], src[reference[c]] = ("pivot", "q", i, c, 0), ("pivot", "q", i, c, 1)
    for k in ("error_n", "roll_error_rad", "reference_outside_range"):
        src[k] = ("twins",)
    src["diverged"], src["physical_limit"] = ("flag", "diverged"), ("flag", "reference_out")
    return src


SOURCES = _sources()
# a step's keys without twins: none of the twin's nor those that compare the two
MODEL_KEYS = tuple(
    k for k, s in SOURCES.items() if s[0] != "twins" and not (s[0] in ("car", "pivot") and s[-1])
)


def result(batch: Any, now: np.ndarray, out: dict[str, np.ndarray], q, forces, keys=None) -> dict:
    """The step's (B,) arrays under ``keys`` (default every key of ``RESULT_KEYS`` the batch
    has: the reference keys only with twins)."""
    n = batch.num_cars
    if keys is None:
        keys = SOURCES if batch.with_reference else MODEL_KEYS
    cols = (slice(None, n), slice(n, None))
    pivots = {"forces": forces, "q": q}
    res: dict[str, np.ndarray] = {}
    for k in keys:
        s = SOURCES[k]
        if s[0] == "input":
            res[k] = now[s[1]].copy()
        elif s[0] == "car":
            res[k] = out[s[1]][cols[s[2]]]
        elif s[0] == "pivot":
            res[k] = pivots[s[1]][cols[s[4]], s[2], s[3]]
        elif s[0] == "flag":
            res[k] = getattr(batch, s[1]).copy()
        elif k == "error_n":
            d = forces[:n, :, :2] - forces[n:, :, :2]
            res[k] = np.hypot(d[..., 0], d[..., 1]).max(axis=1)
        elif k == "roll_error_rad":
            res[k] = out["roll_rad"][:n] - out["roll_rad"][n:]
        else:
            res[k] = (np.abs(q[n:, :, 2]) > batch.calibrated_rotation).any(1)
    return res
