"""What HalfCar-v0 reads off its two cars each step: the pivots' forces judged and held
(``sample``), each car's body, wheel and geometry outputs (``car_outputs``) and why a car left
its bounds (``out_of_bounds``); the info keys are built once here."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bushenv.rigs.car_verdict import MODEL_ERROR_PREFIX
from bushenv.rigs.common import MODEL_ERRORS, model_error_text
from bushenv.rigs.halfcar_car import SIGN, HalfCar, step_models
from bushenv.rigs.halfcar_params import POSITIONS, SIDES, HalfCarParameters

COORD_KEYS = (("axial", "n"), ("radial", "n"), ("moment", "nm"))
# per pivot: the (model, reference) keys of axial, radial, moment, then the deflection keys of
# the model car and of the reference twin
PIVOT_KEYS = tuple(
    (
        tuple(
            tuple(f"{f'force_{k}_{name}' if c < 2 else f'moment_{k}'}_{role}_{unit}"
                  for role in ("model", "reference"))
            for c, (name, unit) in enumerate(COORD_KEYS)
        ),
        (f"deflection_{k}_axial_m", f"deflection_{k}_radial_m", f"rotation_{k}_rad"),
        (f"reference_deflection_{k}_axial_m", f"reference_deflection_{k}_radial_m",
         f"reference_rotation_{k}_rad"),
    )
    for k in POSITIONS
)  # fmt: skip


def sample(car: HalfCar, models: Any, p: HalfCarParameters):
    """(q, v, forces, why) of a car's four pivots at t_k: forces judged before they are applied
    (not finite, beyond ``force_limit_n`` / ``moment_limit_nm``, the model raised) and held
    only when they can be; why is "" if they were."""
    car.update_damping()
    q, v = car.bushing_motion()
    try:
        f = step_models(models, q, v)
    except MODEL_ERRORS as exc:
        return q, v, np.full((4, 3), np.nan), f"model raised {type(exc).__name__}: {exc}"
    except Exception as exc:  # the model's own bug: ends the episode, not a divergence
        return q, v, np.full((4, 3), np.nan), MODEL_ERROR_PREFIX + model_error_text(exc)
    why = force_reason(p, f)
    if not why:
        car.hold(f, q, v)
    return q, v, f, why


def force_reason(p: HalfCarParameters, f: np.ndarray) -> str:
    """Why sampled (4, 3) pivot forces cannot be applied ("" if they can)."""
    limits = (p.force_limit, p.force_limit, p.moment_limit)
    for i, k in enumerate(POSITIONS):
        for c, (name, _) in enumerate(COORD_KEYS):
            x = f[i, c]
            if not math.isfinite(x):
                return f"{k} bushing {name} {x!r} is not finite"
            if abs(x) > limits[c]:
                u = "N m" if c == 2 else "N"
                return f"{k} bushing |{name}| = {abs(x):.6g} {u} exceeds {limits[c]:.6g} {u}"
    return ""


def car_outputs(
    p: HalfCarParameters, car: HalfCar, roads, road_v, prev_v, ay: float
) -> dict[str, Any]:
    """One car's body, wheel and geometry outputs after a step (plain floats and bools):
    ``roads`` the road heights (left, right; m), ``road_v`` their speeds over the step (the
    tyre dampers' input), ``prev_v`` the body's (vx, vy) a step ago, ``ay`` the lateral load."""
    c = car.chassis
    (x, y), (vx, vy) = c.position, c.velocity
    phi = c.angle
    out = {
        "body_y_m": y - p.h_cg, "body_x_m": x, "body_vx_m_per_s": vx, "body_vy_m_per_s": vy,
        "body_vertical_accel_m_per_s2": (vy - prev_v[1]) / p.dt,
        "body_lateral_accel_m_per_s2": ay + (vx - prev_v[0]) / p.dt,
        "roll_rad": phi, "roll_rate_rad_per_s": c.angular_velocity,
    }  # fmt: skip
    contact_x = []
    cos, sin = math.cos(phi), math.sin(phi)
    for side, h, vh in zip(SIDES, roads, road_v, strict=True):
        corner = car.corners[side]
        u = corner["upright"]
        psi = u.angle
        (wx, wy), wvy = u.position, u.velocity.y
        cx, cy = wx + math.sin(psi) * p.r_w, wy - math.cos(psi) * p.r_w
        cvy = wvy + u.angular_velocity * math.sin(psi) * p.r_w
        contact_x.append(cx)
        load = p.k_t * (h - cy) + (p.c_t * (vh - cvy) if corner["contact"] else 0.0)
        load = max(p.tyre_static_n + load, 0.0)
        out[f"wheel_load_{side}_n"] = load
        out[f"wheel_lift_{side}"] = load <= 0.0
        out[f"camber_{side}_rad"] = -SIGN[side] * psi
        dx, dy = wx - x, wy - y  # the wheel centre in the body frame, its height change
        out[f"travel_{side}_m"] = -sin * dx + cos * dy - (p.r_w - p.h_cg)
        out[f"wheel_{side}_y_m"] = wy - p.r_w
    out["track_change_m"] = contact_x[0] - contact_x[1] - p.track
    return out


def out_of_bounds(p: HalfCarParameters, out: dict[str, Any], q: np.ndarray) -> str:
    """Why a car left its physical bounds after a step ("" if it did not), from its
    ``car_outputs`` and its (4, 3) bushing deflections."""
    body = (out["body_x_m"], out["body_y_m"], out["wheel_left_y_m"], out["wheel_right_y_m"])
    if not (all(math.isfinite(v) for v in body) and math.isfinite(out["roll_rad"])):
        return "state is not finite"
    if not np.isfinite(q).all():
        return "bushing deflection is not finite"
    defl = float(np.abs(q[:, :2]).max())
    if defl > p.max_deflection:
        return f"bushing deflection {defl * 1e3:.4g} mm exceeds {p.max_deflection * 1e3:.4g} mm"
    if abs(out["roll_rad"]) > p.max_roll:
        return f"body roll {out['roll_rad']:.4g} rad exceeds {p.max_roll:.4g} rad"
    for side in SIDES:
        travel = out[f"travel_{side}_m"]
        if abs(travel) > p.max_travel:
            return f"{side} suspension travel {travel:.4g} m exceeds {p.max_travel:.4g} m"
    worst = max(abs(v) for v in body)
    if worst > p.max_body:
        return f"body or wheel displacement {worst:.4g} m exceeds {p.max_body:.4g} m"
    return ""


def observation_values(p: HalfCarParameters, info: dict[str, Any], hypot: Any) -> tuple:
    """HalfCar-v0's 16 observation entries before clipping, from one step's ``info`` (floats
    with ``math.hypot``, or the vector env's (N,) arrays with ``np.hypot``)."""
    f = [hypot(info[f"force_{k}_axial_model_n"], info[f"force_{k}_radial_model_n"])
         for k in POSITIONS]  # fmt: skip
    return (
        info["road_left_m"] / p.max_road, info["road_right_m"] / p.max_road,
        info["lateral_accel_m_per_s2"] / p.max_ay, info["body_y_m"] / p.max_body,
        info["body_vy_m_per_s"] / p.v_scale, info["body_x_m"] / p.max_body,
        info["roll_rad"] / p.max_roll, info["roll_rate_rad_per_s"] / p.roll_rate_scale,
        (info["wheel_load_left_n"] - p.tyre_static_n) / p.tyre_static_n,
        (info["wheel_load_right_n"] - p.tyre_static_n) / p.tyre_static_n,
        *(x / p.force_limit for x in f), info["error_n"] / p.force_limit,
        info["roll_error_rad"] / p.max_roll,
    )  # fmt: skip
