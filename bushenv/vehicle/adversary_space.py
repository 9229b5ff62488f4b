"""The adversary's search space: the standard manoeuvres with their parameters free within the
standards' bounds, each a map from the unit cube to HalfCar-v0's inputs.

A profile is (T, 3): road height under the left and right wheel (m) and the single-track
model's lateral acceleration (m/s^2), at HalfCar-v0's sample time; it starts at rest. The
generators are ``roads``, ``steering`` and ``single_track``'s, as ``manoeuvres`` uses them.

| family          | d | parameters (physical range; source of the bound)                          |
|-----------------|---|---------------------------------------------------------------------------|
| car_road        | 3 | ISO 8608 class A-H, speed 20-130 km/h, road seed 0-9999; 5 s, faded in    |
| car_bump        | 3 | 1 - cos bump under both wheels: length 0.2-2 m, height 10-100 mm, speed    |
|                 |   | 10-80 km/h (seed 001 §5.1's 0.4-1 m bumps, speed bumps to 100 mm)          |
| car_pothole     | 4 | left wheel: length 0.2-1.5 m, depth 10-100 mm, speed 10-80 km/h, edges    |
|                 |   | 10-45 % of the length (seed 000 §5.3.2's 30 km/h pothole within)          |
| car_step_steer  | 3 | ISO 7401: speed 60-120 km/h (80, 100, 120 in the standard), steady level   |
|                 |   | 1-7 m/s^2 (4 in the standard), steering rate 200-500 deg/s                |
| car_pulse_steer | 3 | ISO 7401: speed 60-120 km/h, level 1-7 m/s^2, triangle 0.3-0.5 s wide      |
| car_fishhook    | 4 | NHTSA: speed 35-50 mph, factor 1-6.5 times A (A: 0.3 g at 50 mph), dwell  |
|                 |   | 0.1-0.5 s (the roll-rate feedback's range), left or right first, 720 deg/s |
| car_lane_change | 1 | ISO 3888-1 course, preview driver, speed 60-100 km/h                      |
| car_any         | 5 | u[0] picks one of the above, u[1:] its parameters                         |

The single-track model has no tyre saturation (``manoeuvres``' note on the fishhook): a steering
input whose lateral acceleration would pass ``AY_CAP_M_PER_S2`` (0.71 g, the study's fishhook)
is scaled down to it, and ``params["ay_scaled_by"]`` says by how much. Roads are clipped to
HalfCar-v0's +-150 mm (1 mm inside) and 50 mm per step (5 % inside; ``params["clipped"]``):
ISO 8608's rough classes at speed exceed what the car can take, and then its reference twin
leaves its bounds too.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from bushenv import excitation as ex
from bushenv.vehicle import roads, single_track, steering
from bushenv.vehicle.checks import VehicleInputError
from bushenv.vehicle.manoeuvres import FADE_IN_S, KMH, Manoeuvre

AY_CAP_M_PER_S2 = 7.0  # the linear single-track model's lateral acceleration capped here
ROAD_MAX_M = 0.149  # 1 mm inside HalfCar-v0's 150 mm: a case's float32 encoding stays inside
ROAD_STEP_M = 0.95 * 0.05  # 5 % inside HalfCar-v0's max_road_step_m
AY_MAX_M_PER_S2 = 8.0  # HalfCar-v0's max_lateral_accel_m_per_s2
# a_y change per step the searched car accepts: NHTSA's 720 deg/s at the cap needs ~0.4
AY_STEP_M_PER_S2 = 0.5
CLASSES = "ABCDEFGH"
ROAD_S = 5.0  # the standard road manoeuvre's length
SETTLE_S = 2.0  # after a bump or pothole, the car's free response
START_S = 0.5  # flat road or straight ahead before any input
MPH = 0.44704


def _lin(u: float, lo: float, hi: float) -> float:
    return lo + (hi - lo) * float(min(max(u, 0.0), 1.0))


def _pick(u: float, n: int) -> int:
    return min(int(float(u) * n), n - 1)


def clip_inputs(x: np.ndarray, dt_s: float) -> np.ndarray:
    """(T, 3) inputs kept within HalfCar-v0's limits (the roads' 5 % inside them), from rest."""
    x = np.asarray(x, dtype=np.float64).reshape(-1, 3)
    if x.shape[0] == 0 or np.any(x[0] != 0.0):
        x = np.concatenate([np.zeros((1, 3)), x])
    bounds = ((ROAD_MAX_M, ROAD_STEP_M), (ROAD_MAX_M, ROAD_STEP_M),
              (AY_MAX_M_PER_S2, AY_STEP_M_PER_S2))  # fmt: skip
    out = np.stack(
        [ex.clip_to_limits(x[:, i], dt_s, h, s / dt_s) for i, (h, s) in enumerate(bounds)], axis=1
    )
    out[0] = 0.0
    return out


def _road(road: np.ndarray, dt_s: float, params: dict) -> tuple[np.ndarray, dict]:
    x = np.column_stack([road, np.zeros(len(road))])
    out = clip_inputs(x, dt_s)
    clipped = out.shape != x.shape or not np.allclose(out, x, rtol=0, atol=1e-12)
    return out, {**params, "clipped": bool(clipped)}


def _steer(wheel_rad: np.ndarray, speed: float, dt_s: float, params: dict):
    ay = single_track.single_track_response(wheel_rad, dt_s, speed).lateral_acceleration_m_per_s2
    peak = float(np.abs(ay).max())
    scale = min(1.0, AY_CAP_M_PER_S2 / peak) if peak > 0 else 1.0
    x = np.column_stack([np.zeros((ay.size, 2)), ay * scale])
    params = {"speed_km_per_h": speed / KMH, **params, "ay_scaled_by": scale,
              "peak_steering_wheel_deg": math.degrees(float(np.abs(wheel_rad).max())) * scale,
              "peak_lateral_accel_m_per_s2": peak * scale}  # fmt: skip
    return clip_inputs(x, dt_s), params


def car_road(u, dt_s):
    cls = CLASSES[_pick(u[0], len(CLASSES))]
    v = _lin(u[1], 20, 130) * KMH
    seed = int(round(_lin(u[2], 0, 9999)))
    road = roads.two_tracks(cls, v, dt_s, ROAD_S, np.random.default_rng(seed))
    n = min(len(road), int(round(FADE_IN_S / dt_s)))
    road[:n] *= 0.5 * (1 - np.cos(np.pi * np.arange(n) / n))[:, None]
    return _road(road, dt_s, {"road_class": cls, "speed_km_per_h": v / KMH, "rng_seed": seed,
                              "duration_s": ROAD_S, "fade_in_s": FADE_IN_S})  # fmt: skip


def car_bump(u, dt_s):
    length, height = _lin(u[0], 0.2, 2.0), _lin(u[1], 0.01, 0.1)
    v = _lin(u[2], 10, 80) * KMH
    duration = START_S + length / v + SETTLE_S
    road = roads.bump_tracks(v, dt_s, duration, length, height, start_m=START_S * v)
    return _road(road, dt_s, {"length_m": length, "height_m": height,
                              "speed_km_per_h": v / KMH, "shape": "cosine"})  # fmt: skip


def car_pothole(u, dt_s):
    length, depth = _lin(u[0], 0.2, 1.5), _lin(u[1], 0.01, 0.1)
    v, edge = _lin(u[2], 10, 80) * KMH, _lin(u[3], 0.10, 0.45) * length
    duration = START_S + length / v + SETTLE_S
    road = roads.pothole_tracks(v, dt_s, duration, length, depth, edge, START_S * v, "left")
    return _road(road, dt_s, {"length_m": length, "depth_m": depth, "edge_m": edge,
                              "speed_km_per_h": v / KMH, "side": "left"})  # fmt: skip


def car_step_steer(u, dt_s):
    v, level, rate = _lin(u[0], 60, 120) * KMH, _lin(u[1], 1, 7), _lin(u[2], 200, 500)
    amp = steering.iso7401_amplitude_deg(v, level)
    w = steering.step_steer_rad(dt_s, 4.0, amp, rate, start_s=1.0)
    return _steer(w, v, dt_s, {"level_m_per_s2": level, "amplitude_deg": amp,
                               "rate_deg_per_s": rate})  # fmt: skip


def car_pulse_steer(u, dt_s):
    v, level, width = _lin(u[0], 60, 120) * KMH, _lin(u[1], 1, 7), _lin(u[2], 0.3, 0.5)
    amp = steering.iso7401_amplitude_deg(v, level)
    w = steering.pulse_steer_rad(dt_s, 4.0, amp, width, start_s=1.0)
    return _steer(w, v, dt_s, {"level_m_per_s2": level, "amplitude_deg": amp,
                               "width_s": width})  # fmt: skip


def car_fishhook(u, dt_s):
    v, factor, dwell = _lin(u[0], 35, 50) * MPH, _lin(u[1], 1.0, 6.5), _lin(u[2], 0.1, 0.5)
    direction = 1 if u[3] < 0.5 else -1
    a_ref = steering.fishhook_reference_angle_deg()
    rate = steering.FISHHOOK_RATE_DEG_PER_S
    hold, unwind, start = 3.0, 2.0, START_S
    duration = start + 3 * factor * a_ref / rate + dwell + hold + unwind + 0.5
    w = steering.fishhook_rad(dt_s, duration, a_ref, dwell, rate, factor, hold, unwind, start,
                              direction)  # fmt: skip
    return _steer(w, v, dt_s, {"factor": factor, "reference_angle_deg": a_ref, "dwell_s": dwell,
                               "rate_deg_per_s": rate, "direction": "left first" if direction
                               > 0 else "right first", "speed_mph": v / MPH})  # fmt: skip


def car_lane_change(u, dt_s):
    v = _lin(u[0], 60, 100) * KMH
    run = steering.iso3888_1_lane_change(dt_s, v)
    return _steer(run.steering_wheel_angle_rad, v, dt_s,
                  {"preview_s": 0.5, "offset_m": steering.ISO3888_OFFSET_M})  # fmt: skip


Builder = Callable[[np.ndarray, float], tuple[np.ndarray, dict]]
BUILDERS: dict[str, tuple[int, Builder, str]] = {
    "car_road": (3, car_road, "ISO 8608:2016"),
    "car_bump": (3, car_bump, "seed 001 §5.1"),
    "car_pothole": (4, car_pothole, "seed 000 §5.3.2"),
    "car_step_steer": (3, car_step_steer, "ISO 7401:2011"),
    "car_pulse_steer": (3, car_pulse_steer, "ISO 7401:2011"),
    "car_fishhook": (4, car_fishhook, "NHTSA NCAP rollover (68 FR 59250)"),
    "car_lane_change": (1, car_lane_change, "ISO 3888-1:2018"),
}
ANY_DIM = 1 + max(d for d, _, _ in BUILDERS.values())


def car_any(u, dt_s):
    name = list(BUILDERS)[_pick(u[0], len(BUILDERS))]
    dim, build, _ = BUILDERS[name]
    x, params = build(np.asarray(u[1 : 1 + dim]), dt_s)
    return x, {"family": name, **params}


def build(family: str, u, dt_s: float) -> tuple[np.ndarray, dict]:
    """(profile (T, 3), physical parameters) of ``family`` at unit-cube point ``u``."""
    if family == "car_any":
        return car_any(np.asarray(u, dtype=np.float64), dt_s)
    if family not in BUILDERS:
        raise VehicleInputError(f"unknown family {family!r}; known: car_any, {', '.join(BUILDERS)}")
    x, params = BUILDERS[family][1](np.asarray(u, dtype=np.float64), dt_s)
    return x, {"family": family, **params}


def as_manoeuvre(x: np.ndarray, dt_s: float, name: str = "searched", params=None) -> Manoeuvre:
    """A (T, 3) profile as a ``Manoeuvre`` HalfCar-v0 replays (``compare.run_car``)."""
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3 or x.shape[0] < 2:
        raise VehicleInputError(f"a half-car profile is (T >= 2, 3), got {x.shape}")
    p = dict(params or {})
    source = BUILDERS.get(str(p.get("family")), (0, None, "the adversary"))[2]
    return Manoeuvre(name, str(p.get("family", name)), source, dt_s, x[:, :2].copy(),
                     x[:, 2].copy(), p)  # fmt: skip
