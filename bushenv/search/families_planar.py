"""Excitation families in three coordinates for the ``rig3`` target: [0, 1]^d -> a (T, 3) profile.

Columns are (axial m, radial m, rotation rad), within BushRig3-v0's stroke and rate (read from
its spec, ``envs/BushRig3-v0.toml``, as the env reads them; a one-axis bushing's ``limits``
do not apply here). Every profile starts at rest in all coordinates and ends in a hold.
Directions, phases and how the amplitude is split between the axes are cube coordinates, so
random search and CMA-ES draw them like any other parameter.

| family         | d  | parameters                                                               |
|----------------|----|--------------------------------------------------------------------------|
| preload_step   | 6  | preload axis, step axis (one of the other two), preload +-80 % stroke,   |
|                |    | step +-95 % stroke, wait 0.5-2 s after the preload, hold 0.5 s-rest      |
| rotation_sweep | 6  | radial preload +-80 % stroke, rotation amplitude 0.005-0.15 rad (log),   |
|                |    | f0, f1 0.5-40 Hz (log, linear sweep), 1-6 s, hold 0.5-3 s                |
| orbit          | 6  | axial-radial ellipse: size 5-100 % stroke, minor/major 0-1 (1: circle),  |
|                |    | orientation 0-pi, 0.5-20 Hz (log), sense (ccw/cw), 1-6 s; faded in/out   |
| random3        | 9  | amplitude split (3 weights), peak 10-90 % stroke, band 0.5 to 2-40 Hz,   |
|                |    | radial and rotation lag behind axial 0-1 period of the band's centre,    |
|                |    | seed 0-9999, 1-8 s; one common drive, phase-shifted, then a hold         |
| any3           | 10 | u[0] picks one of the above, u[1:] its parameters (CMA-ES over families) |
| one_axis       | 9  | u[0] picks a coordinate, u[1:] the one-axis ``any`` family's parameters  |
|                |    | (scaled to that coordinate's stroke): a single-axis test, not drawn by   |
|                |    | random search over the planar families                                   |
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from bushenv import excitation as ex
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


def clip3(q: np.ndarray, dt: float) -> np.ndarray:
    """Each coordinate clipped to its stroke and slew-limited to its rate."""
    stroke, rate = rig3_limits()
    q = np.asarray(q, dtype=np.float64)
    return np.stack([ex.clip_to_limits(q[:, i], dt, stroke[i], rate[i]) for i in range(3)], axis=1)


def finish3(q: np.ndarray, dt: float, max_s: float, lim=None) -> np.ndarray:
    """Start at rest, trim to ``max_s`` keeping a final hold, keep the rig's limits."""
    q = np.asarray(q, dtype=np.float64).reshape(-1, 3)
    if q.shape[0] == 0 or np.any(q[0] != 0.0):
        q = np.concatenate([np.zeros((1, 3)), q])
    n_max = _n(max_s, dt)
    if q.shape[0] > n_max:
        n_hold = _n(MIN_HOLD_S, dt)
        last = q[n_max - n_hold - 1 : n_max - n_hold]
        q = np.concatenate([q[: n_max - n_hold], np.repeat(last, n_hold, axis=0)])
    q = clip3(q, dt)
    q[0] = 0.0
    return q


def _speeds() -> np.ndarray:
    return rig3_limits()[1] * SPEED_MARGIN


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
    stroke, v = rig3_limits()[0], _speeds()
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
    stroke, v = rig3_limits()[0], _speeds()
    pre = _lin(u[0], -0.8, 0.8) * stroke[1]
    f0, f1 = _log(u[2], 0.5, 40.0), _log(u[3], 0.5, 40.0)
    amp = min(_log(u[1], 0.005, stroke[2]), v[2] / (2 * math.pi * max(f0, f1)))
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
    stroke, v = rig3_limits()[0], _speeds()
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
    stroke, v = rig3_limits()[0], _speeds()
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
    the axial stroke and rate and scaled to the chosen coordinate's (the rate limits are in
    the same ratio as the strokes, so the scaled profile keeps both)."""
    stroke = rig3_limits()[0]
    i = _pick(u[0], 3)
    x = FAMILIES["any"].profile(u[1:], dt, max_s) * (stroke[i] / stroke[0])
    q = np.zeros((x.size, 3))
    q[:, i] = x
    return q, {"axis": COORDS[i], **FAMILIES["any"].describe(u[1:], dt, max_s)}


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
