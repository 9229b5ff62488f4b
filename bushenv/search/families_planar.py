"""Excitation families in three coordinates for the ``rig3`` target: [0, 1]^d -> a (T, 3) profile.

Columns are (axial m, radial m, rotation rad), within a stroke and rate per coordinate: the
``limits`` a family is given when they are ``Rig3Limits`` (a user's bushing: from its card's
records, ``limits_of_records``), else BushRig3-v0's (read from its spec,
``envs/BushRig3-v0.toml``, as the env reads them; a one-axis bushing's ``BushingScales`` do not
apply here). Every profile starts at rest in all coordinates and ends in a hold.
Directions, phases and how the amplitude is split between the axes are cube coordinates, so
random search and CMA-ES draw them like any other parameter.

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
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from bushenv import excitation as ex
from bushenv.scales import MACHINE, RECORD_MARGIN
from bushenv.search.base import SearchError
from bushenv.search.families import (
    FAMILIES,
    MIN_HOLD_S,
    SPEED_MARGIN,
    Family,
    _lin,
    _log,
    _move,
    _n,
)

TARGET = "rig3"
ENV_ID = "BushRig3-v0"
COORDS = ("axial", "radial", "rotation")
FADE_S = 0.25  # orbits fade in and out over this long, so they start and end at rest


@lru_cache(maxsize=1)
def rig3_limits() -> tuple[np.ndarray, np.ndarray]:
    """BushRig3-v0's stroke and rate per coordinate (m, m, rad; m/s, m/s, rad/s)."""
    from bushenv.rigs.specs import load_spec

    kw = load_spec(ENV_ID)["kwargs"]
    stroke = np.array([float(kw["stroke"][c]) for c in COORDS])
    rate = np.array([float(kw["rate"][c]) for c in COORDS])
    stroke.setflags(write=False)
    rate.setflags(write=False)
    return stroke, rate


UNITS = ("mm", "mm", "mrad")  # how reports show each coordinate (x 1e3 of m, m, rad)
RATE_UNITS = ("m_per_s", "m_per_s", "rad_per_s")  # and its rate (SI)


@dataclass(frozen=True)
class Rig3Limits:
    """Stroke and rate per coordinate a rig3 search drives (the ``limits`` its families, its
    ``finish`` and its shrinking take, in the evaluator's ``scales`` slot).

    Attributes
    ----------
    stroke : tuple of 3 floats
        Largest |q| per coordinate: m, m, rad.
    rate : tuple of 3 floats
        Largest |dq/dt| per coordinate: m/s, m/s, rad/s.
    source : str
        Where these numbers come from, for reports.
    records_peak : tuple of 3 floats or None
        Largest |q| per coordinate of the records the limits were taken from (m, m, rad);
        None when they come from none.
    """

    stroke: tuple[float, float, float]
    rate: tuple[float, float, float]
    source: str = "BushRig3-v0's stroke and rate (the machine's)"
    records_peak: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        top_stroke, top_rate = rig3_limits()
        rates = [r.replace("_per_s", "/s") for r in RATE_UNITS]
        for name, vals, top, units, k in (("stroke", self.stroke, top_stroke, UNITS, 1e3),
                                          ("rate", self.rate, top_rate, rates, 1.0)):  # fmt: skip
            if len(vals) != 3:
                raise SearchError(f"rig3 {name} needs 3 values (axial, radial, rotation): {vals}")
            for c, v, t, u in zip(COORDS, vals, top, units, strict=True):
                if not (np.isfinite(v) and 0 < v <= t * (1 + 1e-9)):
                    raise SearchError(
                        f"the {c} {name} must be in (0, {k * t:.6g}] {u} (BushRig3-v0's), "
                        f"got {k * v:.6g} {u}"
                    )

    def to_json(self) -> dict:
        """Per coordinate with its unit in the key (mm, mm, mrad), and the source."""
        out: dict = {}
        for i, (c, u) in enumerate(zip(COORDS, UNITS, strict=True)):
            out[c] = {f"stroke_{u}": round(1e3 * self.stroke[i], 6),
                      f"rate_{RATE_UNITS[i]}": round(self.rate[i], 6)}  # fmt: skip
            if self.records_peak is not None:
                out[c][f"records_peak_{u}"] = round(1e3 * self.records_peak[i], 6)
        out["source"] = self.source
        return out


@lru_cache(maxsize=1)
def machine_limits() -> Rig3Limits:
    """BushRig3-v0's stroke and rate as ``Rig3Limits``."""
    stroke, rate = rig3_limits()
    return Rig3Limits(tuple(stroke.tolist()), tuple(rate.tolist()))


def limits3(lim=None) -> tuple[np.ndarray, np.ndarray]:
    """(stroke, rate) (3,) arrays of ``lim`` when it is ``Rig3Limits``, else the machine's."""
    if isinstance(lim, Rig3Limits):
        return np.array(lim.stroke), np.array(lim.rate)
    return rig3_limits()


def limits_of_records(q: list[np.ndarray], dt: float, what: str) -> Rig3Limits:
    """Limits from (T, 3) displacement records ``q``: per coordinate their largest |q| and
    |dq/dt| times ``scales.RECORD_MARGIN`` (the one-axis rule, ``scales.scales_of_card``),
    within the machine. A coordinate the records never move keeps the machine's limits (the
    source says so). ``what`` names the records in the source."""
    top_stroke, top_rate = rig3_limits()
    peak = np.max([np.max(np.abs(a), axis=0) for a in q], axis=0)
    speed = np.max([np.max(np.abs(np.diff(a, axis=0)), axis=0) / dt for a in q], axis=0)
    moved = peak > 0
    stroke = np.where(moved, np.minimum(RECORD_MARGIN * peak, top_stroke), top_stroke)
    rate = np.where(moved, np.minimum(RECORD_MARGIN * speed, top_rate), top_rate)
    seen = ", ".join(
        f"{c} {1e3 * p:.4g} {u} at {v:.4g} {r.replace('_per_s', '/s')}"
        for c, u, r, p, v in zip(COORDS, UNITS, RATE_UNITS, peak, speed, strict=True)
    )
    source = f"{RECORD_MARGIN:g} x the peak |q| and |dq/dt| of {what} ({seen})"
    if not moved.all():
        still = ", ".join(c for c, m in zip(COORDS, moved, strict=True) if not m)
        source += f"; {still}: never moved there, the machine's"
    return Rig3Limits(tuple(stroke.tolist()), tuple(rate.tolist()), source, tuple(peak.tolist()))


def limits_text(limits: dict) -> str:
    """``axial +-3 mm at 0.2 m/s, ...`` from ``Rig3Limits.to_json``, and the source."""
    parts = []
    for c, u, r in zip(COORDS, UNITS, RATE_UNITS, strict=True):
        row = limits[c]
        rate = r.replace("_per_s", "/s")
        parts.append(f"{c} +-{row[f'stroke_{u}']:.4g} {u} at {row[f'rate_{r}']:.4g} {rate}")
    return f"{', '.join(parts)} ({limits['source']})"


def clip3(q: np.ndarray, dt: float, lim=None) -> np.ndarray:
    """Each coordinate clipped to its stroke and slew-limited to its rate (``limits3``)."""
    stroke, rate = limits3(lim)
    q = np.asarray(q, dtype=np.float64)
    return np.stack([ex.clip_to_limits(q[:, i], dt, stroke[i], rate[i]) for i in range(3)], axis=1)


def finish3(q: np.ndarray, dt: float, max_s: float, lim=None) -> np.ndarray:
    """Start at rest, trim to ``max_s`` keeping a final hold, keep the limits (``limits3``)."""
    q = np.asarray(q, dtype=np.float64).reshape(-1, 3)
    if q.shape[0] == 0 or np.any(q[0] != 0.0):
        q = np.concatenate([np.zeros((1, 3)), q])
    n_max = _n(max_s, dt)
    if q.shape[0] > n_max:
        n_hold = _n(MIN_HOLD_S, dt)
        last = q[n_max - n_hold - 1 : n_max - n_hold]
        q = np.concatenate([q[: n_max - n_hold], np.repeat(last, n_hold, axis=0)])
    q = clip3(q, dt, lim)
    q[0] = 0.0
    return q


def _strokes_speeds(lim) -> tuple[np.ndarray, np.ndarray]:
    stroke, rate = limits3(lim)
    return stroke, rate * SPEED_MARGIN


def _join(cols: list[np.ndarray]) -> np.ndarray:
    """Coordinates of different lengths -> (T, 3), each held at its last value."""
    T = max(c.size for c in cols)
    out = np.zeros((T, 3))
    for i, c in enumerate(cols):
        if c.size:
            out[: c.size, i] = c
            out[c.size :, i] = c[-1]
    return out


def _append(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.concatenate([a, b]) if b.size else a


def _pick(u: float, k: int) -> int:
    return min(k - 1, int(float(u) * k))


def _preload_step(u, dt, max_s, lim):
    stroke, v = _strokes_speeds(lim)
    p_ax = _pick(u[0], 3)
    others = [i for i in range(3) if i != p_ax]
    s_ax = others[_pick(u[1], 2)]
    pre = _lin(u[2], -0.8, 0.8) * stroke[p_ax]
    size = _lin(u[3], -0.95, 0.95) * stroke[s_ax]
    wait = _lin(u[4], 0.5, 2.0)
    p = _append(np.zeros(1), _move(0.0, pre, dt, 0.5 * v[p_ax]))
    t_step = p.size + _n(wait, dt)
    s = np.concatenate([np.zeros(t_step), _move(0.0, size, dt, v[s_ax])])
    hold = _lin(u[5], MIN_HOLD_S, max(MIN_HOLD_S, max_s - s.size * dt))
    s = _append(s, np.full(_n(hold, dt), size))
    cols = [np.zeros(1)] * 3
    cols[p_ax], cols[s_ax] = p, s
    params = {
        "preload_axis": COORDS[p_ax],
        "preload": pre,
        "step_axis": COORDS[s_ax],
        "step": size,
        "wait_s": wait,
        "hold_s": hold,
    }
    return _join(cols), params


def _rotation_sweep(u, dt, max_s, lim):
    stroke, v = _strokes_speeds(lim)
    pre = _lin(u[0], -0.8, 0.8) * stroke[1]
    f0, f1 = _log(u[2], 0.5, 40.0), _log(u[3], 0.5, 40.0)
    low = 0.005 * min(1.0, stroke[2] / rig3_limits()[0][2])  # 0.005 rad of the machine's 0.15
    amp = min(_log(u[1], low, stroke[2]), v[2] / (2 * math.pi * max(f0, f1)))
    dur, hold = _lin(u[4], 1.0, 6.0), _lin(u[5], MIN_HOLD_S, 3.0)
    r = _append(np.zeros(1), _move(0.0, pre, dt, 0.5 * v[1]))
    t = np.arange(_n(dur, dt)) * dt
    phase = 2 * math.pi * (f0 * t + (f1 - f0) * t**2 / (2 * dur))
    rot = np.concatenate([np.zeros(r.size + _n(0.5, dt)), amp * np.sin(phase)])
    rot = _append(rot, np.full(_n(hold, dt), rot[-1]))
    params = {
        "radial_preload": pre,
        "rotation_amplitude": amp,
        "f0_hz": f0,
        "f1_hz": f1,
        "duration_s": dur,
        "hold_s": hold,
    }
    return _join([np.zeros(1), r, rot]), params


def _orbit(u, dt, max_s, lim):
    stroke, v = _strokes_speeds(lim)
    freq = _log(u[3], 0.5, 20.0)
    w = 2 * math.pi * freq
    # the fade's own rate adds at most pi / (2 FADE_S) times the size to the orbit's
    a_max = float(min(stroke[0], stroke[1], min(v[0], v[1]) / (w + math.pi / (2 * FADE_S))))
    major = _lin(u[0], 0.05, 1.0) * a_max
    minor = _lin(u[1], 0.0, 1.0) * major
    angle = _lin(u[2], 0.0, math.pi)
    sense = 1.0 if u[4] < 0.5 else -1.0
    dur = max(_lin(u[5], 1.0, 6.0), 2 * FADE_S)
    t = np.arange(_n(dur, dt) + 1) * dt
    fade = np.ones_like(t)
    nf = _n(FADE_S, dt)
    ramp = 0.5 * (1 - np.cos(np.pi * np.arange(nf) / nf))
    fade[:nf], fade[-nf:] = ramp, ramp[::-1]
    fade[-1] = 0.0
    c, s = major * np.cos(w * t) * fade, sense * minor * np.sin(w * t) * fade
    xa = c * math.cos(angle) - s * math.sin(angle)
    xr = c * math.sin(angle) + s * math.cos(angle)
    hold = np.zeros(_n(MIN_HOLD_S, dt))
    params = {
        "major": major,
        "minor": minor,
        "angle_rad": angle,
        "freq_hz": freq,
        "sense": "ccw" if sense > 0 else "cw",
        "duration_s": dur,
    }
    return _join([_append(xa, hold), _append(xr, hold), np.zeros(1)]), params


def _random3(u, dt, max_s, lim):
    stroke, v = _strokes_speeds(lim)
    weights = np.array([_lin(u[i], 0.0, 1.0) for i in range(3)])
    weights = weights / weights.max() if weights.max() > 0 else np.ones(3)
    level = _lin(u[3], 0.1, 0.9)
    hi = _log(u[4], 2.0, 40.0)
    centre = math.sqrt(0.5 * hi)
    lags = [0.0, _lin(u[5], 0.0, 1.0) / centre, _lin(u[6], 0.0, 1.0) / centre]
    seed = int(round(_lin(u[7], 0, 9999)))
    dur = _lin(u[8], 1.0, 8.0)
    drive = ex.random_band(dur, dt, seed, band_hz=(0.5, hi), peak_m=1.0)
    cols = []
    for i in range(3):
        lag = _n(lags[i], dt)
        x = np.concatenate([np.zeros(lag + 1), drive]) * weights[i] * level * stroke[i]
        fastest = float(np.max(np.abs(np.diff(x)))) / dt if x.size > 1 else 0.0
        if fastest > v[i]:
            x *= v[i] / fastest
        cols.append(_append(x, np.full(_n(MIN_HOLD_S, dt), x[-1])))
    params = {
        "weights": weights.tolist(),
        "peak_fraction": level,
        "band_hz": [0.5, hi],
        "lag_s": lags,
        "seed": seed,
        "duration_s": dur,
    }
    return _join(cols), params


def _one_axis(u, dt, max_s, lim):
    """A one-axis rig profile (the ``any`` family: steps, ramps, pulses, sines, chirps,
    random) in one coordinate, the others at rest: what a single-axis test drives. Built on
    the one-axis machine's stroke, at the chosen coordinate's rate in that proportion (at
    most the machine's), and scaled to the coordinate's stroke; its parameters are the
    one-axis profile's, before that scaling."""
    stroke, rate = limits3(lim)
    i = _pick(u[0], 3)
    scale = stroke[i] / MACHINE.stroke_m
    one = MACHINE
    if rate[i] / scale < MACHINE.velocity_m_per_s * (1 - 1e-9):  # slower than the machine
        one = replace(MACHINE, velocity_m_per_s=rate[i] / scale)
    x = FAMILIES["any"].profile(u[1:], dt, max_s, limits=one) * scale
    q = np.zeros((x.size, 3))
    q[:, i] = x
    params = FAMILIES["any"].describe(u[1:], dt, max_s, limits=one)
    return q, {"axis": COORDS[i], **params}


_BUILDERS = {
    "preload_step": (6, _preload_step),
    "rotation_sweep": (6, _rotation_sweep),
    "orbit": (6, _orbit),
    "random3": (9, _random3),
}
_ANY_DIM = 1 + max(d for d, _ in _BUILDERS.values())


def _any3(u, dt, max_s, lim):
    names = list(_BUILDERS)
    name = names[_pick(u[0], len(names))]
    d, build = _BUILDERS[name]
    q, params = build(u[1 : 1 + d], dt, max_s, lim)
    return q, {"family": name, **params}


for _name, (_d, _b) in _BUILDERS.items():
    FAMILIES.add(_name, Family(_name, _d, TARGET, _b, finish=finish3))
FAMILIES.add("any3", Family("any3", _ANY_DIM, TARGET, _any3, random=False, finish=finish3))
ONE_AXIS_DIM = 1 + FAMILIES["any"].dim
FAMILIES.add(
    "one_axis", Family("one_axis", ONE_AXIS_DIM, TARGET, _one_axis, random=False, finish=finish3)
)
