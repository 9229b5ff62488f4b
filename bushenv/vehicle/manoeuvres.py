"""The standard manoeuvres as HalfCar-v0 inputs: road heights per side and a lateral load.

Each manoeuvre is one of the papers' or the standards' events (seed 000 §5.3: pulse steer and a
pothole at 30 km/h, a fishhook; seed 001 §5.1: a bump; ISO 8608, ISO 7401, NHTSA, ISO 3888-1),
built from ``roads`` and ``steering`` at a stated speed: a road manoeuvre gives the two wheel
tracks, a steering one the single-track model's lateral acceleration (the half car feels it as
d'Alembert's load, docs/vehicle-inputs.md). ``standard_manoeuvres(dt_s, seed)`` lists them;
every array is time-major at ``dt_s`` (HalfCar-v0's 1/204.8 s).

The linear single-track model has no tyre saturation: the NHTSA fishhook's 6.5 A would reach
19.2 m/s^2 on it, beyond any tyre and HalfCar-v0's 8 m/s^2, so its factor is lowered until
the peak is ``FISHHOOK_PEAK_M_PER_S2`` (7 m/s^2, 0.71 g); its 720 deg/s steering rate stays.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bushenv.vehicle import roads, single_track, steering
from bushenv.vehicle.checks import VehicleInputError

KMH = 1 / 3.6
PAPER_SPEED_M_PER_S = 30 * KMH  # seed 000 §5.3.1-5.3.2: pulse steer and pothole at 30 km/h
ROAD_CLASS = "C"  # ISO 8608 class of the random road ("average" in the standard's Annex)
ROAD_SPEED_M_PER_S = 60 * KMH
FADE_IN_S = 0.5  # the random road's start, faded in from flat
FISHHOOK_PEAK_M_PER_S2 = 7.0  # the fishhook's factor is lowered to reach this on the model


@dataclass(frozen=True)
class Manoeuvre:
    """One manoeuvre as HalfCar-v0 replays it.

    ``road_m`` (T, 2): left, right road height under the wheel, m (zeros for a steering
    event); ``lateral_accel_m_per_s2`` (T,): the single-track model's a_y, positive in a left
    turn (zeros on a road). ``params`` states what made it (units in the keys).
    """

    name: str
    title: str
    source: str
    dt_s: float
    road_m: np.ndarray
    lateral_accel_m_per_s2: np.ndarray
    params: dict[str, Any] = field(default_factory=dict)

    @property
    def samples(self) -> int:
        return int(self.lateral_accel_m_per_s2.size)

    @property
    def duration_s(self) -> float:
        return self.samples * self.dt_s

    def reset_options(self) -> dict[str, np.ndarray]:
        """``HalfCar-v0.reset(options=...)`` replaying this manoeuvre."""
        return {
            "road_left": self.road_m[:, 0],
            "road_right": self.road_m[:, 1],
            "lateral_accel": self.lateral_accel_m_per_s2,
        }

    def largest_steps(self) -> tuple[float, float]:
        """(road m, a_y m/s^2): the largest change from one sample to the next (from rest)."""
        road = np.diff(self.road_m, axis=0, prepend=0.0)
        ay = np.diff(self.lateral_accel_m_per_s2, prepend=0.0)
        return float(np.abs(road).max()), float(np.abs(ay).max())

    def describe(self) -> dict[str, Any]:
        """Plain values for a report: the parameters and the input's peaks."""
        return {
            "name": self.name, "title": self.title, "source": self.source,
            "duration_s": self.duration_s, "samples": self.samples, **self.params,
            "peak_road_m": float(np.abs(self.road_m).max()),
            "peak_lateral_accel_m_per_s2": float(np.abs(self.lateral_accel_m_per_s2).max()),
        }  # fmt: skip


def _road(name, title, source, dt_s, road, params) -> Manoeuvre:
    return Manoeuvre(name, title, source, dt_s, road, np.zeros(len(road)), params)


def _steer(name, title, source, dt_s, wheel_rad, speed, params) -> Manoeuvre:
    ay = single_track.single_track_response(wheel_rad, dt_s, speed).lateral_acceleration_m_per_s2
    params = {"speed_km_per_h": speed / KMH, **params,
              "peak_steering_wheel_deg": math.degrees(float(np.abs(wheel_rad).max()))}  # fmt: skip
    return Manoeuvre(name, title, source, dt_s, np.zeros((ay.size, 2)), ay, params)


def bump(dt_s: float, seed: int, duration_s: float = 3.0) -> Manoeuvre:
    """Seed 001 §5.1's shortest bump (400 mm, 50 mm high, 1 - cos) under both wheels, 30 km/h."""
    v, length, height = PAPER_SPEED_M_PER_S, 0.4, 0.05
    road = roads.bump_tracks(v, dt_s, duration_s, length_m=length, height_m=height)
    return _road("bump", "bump, both wheels", "seed 001 §5.1 (Fig. 19)", dt_s, road,
                 {"speed_km_per_h": v / KMH, "length_m": length, "height_m": height,
                  "start_m": 5.0, "shape": "cosine"})  # fmt: skip


def pothole(dt_s: float, seed: int, duration_s: float = 3.0) -> Manoeuvre:
    """Seed 000 §5.3.2's pothole at 30 km/h under the left wheel: 600 mm long, 50 mm deep."""
    v = PAPER_SPEED_M_PER_S
    road = roads.pothole_tracks(v, dt_s, duration_s, side="left")
    return _road("pothole", "pothole, left wheel", "seed 000 §5.3.2 (Fig. 20)", dt_s, road,
                 {"speed_km_per_h": v / KMH, "length_m": 0.6, "depth_m": 0.05, "edge_m": 0.05,
                  "start_m": 5.0, "side": "left"})  # fmt: skip


def iso8608_road(dt_s: float, seed: int, duration_s: float = 5.0) -> Manoeuvre:
    """Two correlated ISO 8608 class C tracks at 60 km/h, drawn from ``seed``, faded in."""
    v = ROAD_SPEED_M_PER_S
    road = roads.two_tracks(ROAD_CLASS, v, dt_s, duration_s, np.random.default_rng(seed))
    # faded in over the first FADE_IN_S (half cosine): the car starts at rest on a flat road
    n = min(len(road), int(round(FADE_IN_S / dt_s)))
    road[:n] *= 0.5 * (1 - np.cos(np.pi * np.arange(n) / n))[:, None]
    return _road("iso8608", f"ISO 8608 class {ROAD_CLASS} road", "ISO 8608:2016", dt_s, road,
                 {"speed_km_per_h": v / KMH, "road_class": ROAD_CLASS, "rng_seed": seed,
                  "fade_in_s": FADE_IN_S,
                  "class_rms_m": roads.class_rms_m(ROAD_CLASS)})  # fmt: skip


def pulse_steer(dt_s: float, seed: int, duration_s: float = 4.0) -> Manoeuvre:
    """ISO 7401 pulse steer at 80 km/h: a 0.4 s triangle to the 4 m/s^2 steady angle."""
    v = steering.ISO7401_SPEED_M_PER_S
    amp = steering.iso7401_amplitude_deg(v)
    u = steering.pulse_steer_rad(dt_s, duration_s, amplitude_deg=amp, width_s=0.4)
    return _steer("pulse_steer", "pulse steer", "ISO 7401:2011", dt_s, u, v,
                  {"amplitude_deg": amp, "width_s": 0.4, "start_s": 1.0})  # fmt: skip


def step_steer(dt_s: float, seed: int, duration_s: float = 5.0) -> Manoeuvre:
    """ISO 7401 step steer at 80 km/h to the 4 m/s^2 steady angle, 500 deg/s."""
    v = steering.ISO7401_SPEED_M_PER_S
    amp = steering.iso7401_amplitude_deg(v)
    u = steering.step_steer_rad(dt_s, duration_s, amplitude_deg=amp, rate_deg_per_s=500.0)
    return _steer("step_steer", "step steer", "ISO 7401:2011", dt_s, u, v,
                  {"amplitude_deg": amp, "rate_deg_per_s": 500.0, "start_s": 1.0})  # fmt: skip


def fishhook(dt_s: float, seed: int, duration_s: float = 7.0) -> Manoeuvre:
    """NHTSA fishhook at 50 mph, A for 0.3 g, 720 deg/s, 0.25 s dwell, left first; the factor
    lowered from 6.5 so that the single-track model peaks at ``FISHHOOK_PEAK_M_PER_S2``."""
    v = steering.FISHHOOK_SIS_SPEED_M_PER_S
    a_ref = steering.fishhook_reference_angle_deg()

    def peak(factor: float) -> float:
        u = steering.fishhook_rad(dt_s, duration_s, a_ref, factor=factor)
        run = single_track.single_track_response(u, dt_s, v)
        return float(np.abs(run.lateral_acceleration_m_per_s2).max())

    # the peak grows with the factor (linear model): bisect for the target, to 0.1 %
    lo, hi = 0.1, steering.FISHHOOK_FACTOR
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if peak(mid) < FISHHOOK_PEAK_M_PER_S2 else (lo, mid)
    factor = round(lo, 3)
    u = steering.fishhook_rad(dt_s, duration_s, a_ref, factor=factor)
    return _steer("fishhook", "fishhook", "NHTSA NCAP rollover (68 FR 59250)", dt_s, u, v,
                  {"reference_angle_deg": a_ref, "factor": factor,
                   "factor_standard": steering.FISHHOOK_FACTOR, "rate_deg_per_s":
                   steering.FISHHOOK_RATE_DEG_PER_S, "dwell_s": 0.25, "hold_s": 3.0,
                   "unwind_s": 2.0})  # fmt: skip


def lane_change(dt_s: float, seed: int, duration_s: float | None = None) -> Manoeuvre:
    """ISO 3888-1 double lane change at 80 km/h, steered by the preview driver; the whole run
    (30 m approach, the 110 m of lanes, 30 m exit) or its first ``duration_s``."""
    v = steering.ISO3888_SPEED_M_PER_S
    run = steering.iso3888_1_lane_change(dt_s, v)
    u = run.steering_wheel_angle_rad
    if duration_s is not None:
        u = u[: max(2, int(round(duration_s / dt_s)))]
    return _steer("lane_change", "double lane change", "ISO 3888-1:2018", dt_s, u, v,
                  {"preview_s": 0.5, "offset_m": steering.ISO3888_OFFSET_M})  # fmt: skip


BUILDERS: dict[str, Callable[..., Manoeuvre]] = {
    "bump": bump,
    "pothole": pothole,
    "iso8608": iso8608_road,
    "pulse_steer": pulse_steer,
    "step_steer": step_steer,
    "fishhook": fishhook,
    "lane_change": lane_change,
}
NAMES = tuple(BUILDERS)


def standard_manoeuvres(
    dt_s: float,
    seed: int = 0,
    names: tuple[str, ...] | list[str] | None = None,
    duration_s: float | None = None,
) -> list[Manoeuvre]:
    """The manoeuvres ``names`` (default all of ``NAMES``), in that order; ``duration_s``
    shortens (or lengthens) every one to that many seconds (None: each its own)."""
    names = NAMES if names is None else tuple(names)
    unknown = [n for n in names if n not in BUILDERS]
    if unknown:
        raise VehicleInputError(f"unknown manoeuvre(s) {unknown}; known: {', '.join(NAMES)}")
    extra = {} if duration_s is None else {"duration_s": duration_s}
    return [BUILDERS[n](dt_s, seed, **extra) for n in names]
