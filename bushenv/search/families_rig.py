"""The test rig's excitation families, over its number of coordinates: [0, 1]^d -> a profile of
bushing deflection (``families.py`` lists them with their parameters and registers them).

One coordinate (target ``rig``, a (T,) profile in m): steps, ramps, pulses, sines, chirps,
random beyond the training band, sequences of those, and ``any`` (CMA-ES over them), within the
bushing's ``BushingScales`` (stroke, velocity: the papers' machine by default). Several
coordinates (target ``rig3``, a (T, 3) profile: axial m, radial m, rotation rad) within a stroke
and rate per coordinate (``limits.CoordinateLimits``): a preload in one coordinate with a step in
another, a rotation sweep under a radial preload, an axial-radial orbit, one random drive
phase-shifted into all three, ``any3`` (CMA-ES over them), and ``one_axis`` (the one-coordinate
``any`` in one coordinate, the others at rest: what a single-axis rig drives). Directions,
phases and how the amplitude is split between the axes are cube coordinates, so random search
and CMA-ES draw them like any other parameter. Every profile starts at rest and ends in a hold.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from bushenv import excitation as ex
from bushenv.scales import MACHINE, BushingScales
from bushenv.search.family_base import (
    MIN_HOLD_S,
    SPEED_MARGIN,
    Family,
    _hold,
    _lin,
    _log,
    _move,
    _n,
)
from bushenv.search.limits import COORDS, TARGET, finish_coords, limits_arrays, rig3_limits

FADE_S = 0.25  # orbits fade in and out over this long, so they start and end at rest


# ----- one coordinate: u -> (x, params) ---------------------------------------------------------
def _limits(lim: BushingScales) -> tuple[float, float]:
    """The stroke and the speed (inside the velocity limit by ``SPEED_MARGIN``) profiles use."""
    return lim.stroke_m, lim.velocity_m_per_s * SPEED_MARGIN


def _finish(x: np.ndarray, dt: float, max_s: float, lim: BushingScales) -> np.ndarray:
    """Trim to ``max_s`` keeping a final hold, guarantee the bushing's limits and x[0] = 0."""
    x = np.asarray(x, dtype=np.float64)
    n_max = _n(max_s, dt)
    if x.size == 0 or x[0] != 0.0:
        x = np.concatenate([[0.0], x])
    if x.size > n_max:  # cut, then hold where the cut fell so the profile still ends in a hold
        n_hold = _n(MIN_HOLD_S, dt)
        x = np.concatenate([x[: n_max - n_hold], np.full(n_hold, x[n_max - n_hold - 1])])
    # the slew limiter only acts where a generator rounded past the limit
    return ex.clip_to_limits(x, dt, lim.stroke_m, lim.velocity_m_per_s)


# ----- rig families: u -> (x, params) ---------------------------------------------------------
def _step(u, dt, max_s, lim):
    XMAX, VMAX = _limits(lim)  # noqa: N806
    size = _lin(u[0], -XMAX, XMAX)
    pre = _lin(u[1], 0.1, 1.0)
    rise_min = math.pi / 2 * abs(size) / VMAX  # half-cosine peak speed = pi/2 * mean speed
    rise = max(_lin(u[2], 0.0, 0.3), rise_min)
    rise = 0.0 if rise < dt else rise
    if rise == 0.0 and abs(size) / dt > VMAX:
        rise = rise_min
    hold = _lin(u[3], MIN_HOLD_S, max(MIN_HOLD_S, max_s - pre - rise))
    x = ex.step_hold(size, hold, dt, pre_s=pre, rise_s=rise)
    return x, {"size_m": size, "pre_s": pre, "rise_s": rise, "hold_s": hold}


def _ramp(u, dt, max_s, lim):
    XMAX, VMAX = _limits(lim)  # noqa: N806
    end = _lin(u[0], -XMAX, XMAX)
    pre = _lin(u[1], 0.0, 1.0)
    ramp_s = max(_lin(u[2], 0.02, 3.0), abs(end) / VMAX, dt)
    hold = _lin(u[3], MIN_HOLD_S, max(MIN_HOLD_S, max_s - pre - ramp_s))
    x = ex.ramp(end, ramp_s, dt, pre_s=pre, hold_s=hold)
    return x, {"end_m": end, "pre_s": pre, "ramp_s": ramp_s, "hold_s": hold}


def _pulse(u, dt, max_s, lim):
    XMAX, VMAX = _limits(lim)  # noqa: N806
    size = _lin(u[0], -XMAX, XMAX)
    width = _lin(u[1], 0.01, 2.0)
    edge = _lin(u[2], 0.0, 0.5) * width
    edge = max(edge, math.pi / 2 * abs(size) / VMAX)
    width = max(width, 2 * edge)
    if edge < dt and abs(size) / dt <= VMAX:
        edge = 0.0
    pre = 0.5
    post = _lin(u[3], MIN_HOLD_S, max(MIN_HOLD_S, max_s - pre - width))
    x = ex.pulse(size, width, dt, pre_s=pre, post_s=post, edge_s=edge)
    return x, {"size_m": size, "width_s": width, "edge_s": edge, "pre_s": pre, "post_s": post}


def _sine(u, dt, max_s, lim):
    XMAX, VMAX = _limits(lim)  # noqa: N806
    freq = _log(u[0], ex.MIN_FREQUENCY_HZ, ex.MAX_FREQUENCY_HZ)
    amp_cap = min(XMAX, VMAX / (2 * math.pi * freq))
    amp = _lin(u[1], min(0.1e-3, amp_cap), amp_cap)
    offset = _lin(u[2], -1.0, 1.0) * (XMAX - amp)
    hold = _lin(u[4], MIN_HOLD_S, 4.0)
    lead_in = _move(0.0, offset, dt, VMAX / 2)
    dur = _lin(u[3], 0.5, max(0.5, min(8.0, max_s - hold - lead_in.size * dt)))
    body = ex.sine(freq, amp, dur, dt, offset_m=offset)
    x = np.concatenate([[0.0], lead_in, body])
    x = np.concatenate([x, _hold(x[-1], hold, dt)])
    return x, {
        "freq_hz": freq,
        "amplitude_m": amp,
        "offset_m": offset,
        "duration_s": dur,
        "hold_s": hold,
    }


def _chirp(u, dt, max_s, lim):
    XMAX, VMAX = _limits(lim)  # noqa: N806
    f0 = _log(u[0], ex.MIN_FREQUENCY_HZ, ex.MAX_FREQUENCY_HZ)
    f1 = _log(u[1], ex.MIN_FREQUENCY_HZ, ex.MAX_FREQUENCY_HZ)
    amp_cap = min(XMAX, VMAX / (2 * math.pi * max(f0, f1)))
    amp = _lin(u[2], min(0.1e-3, amp_cap), amp_cap)
    hold = _lin(u[4], MIN_HOLD_S, 4.0)
    dur = _lin(u[3], 1.0, max(1.0, min(8.0, max_s - hold)))
    method = "logarithmic" if u[5] >= 0.5 else "linear"
    body = ex.chirp(f0, f1, amp, dur, dt, method=method)
    x = np.concatenate([body, _hold(body[-1] if body.size else 0.0, hold, dt)])
    return x, {
        "f0_hz": f0,
        "f1_hz": f1,
        "amplitude_m": amp,
        "duration_s": dur,
        "method": method,
        "hold_s": hold,
    }


def _random_ood(u, dt, max_s, lim):
    XMAX, VMAX = _limits(lim)  # noqa: N806
    n_index = _lin(u[0], 1.0, XMAX / ex.PEAK_M_AT_N1)
    lo = _log(u[1], 0.5, 40.0)
    hi = _lin(u[2], min(lo + 5.0, ex.MAX_FREQUENCY_HZ), ex.MAX_FREQUENCY_HZ)
    peak = min(n_index * ex.PEAK_M_AT_N1, XMAX)
    hold = _lin(u[6], MIN_HOLD_S, 4.0)
    dur = _lin(u[4], 1.0, max(1.0, min(8.0, max_s - hold)))
    seed = int(np.clip(u[5], 0.0, 1.0) * 9999)
    noise = ex.random_ood(dur, dt, seed, band_hz=(lo, hi), peak_m=peak, offset_m=0.0)
    speed = np.max(np.abs(np.diff(noise))) / dt if noise.size > 1 else 0.0
    if speed > VMAX * 0.9:  # keep room for the offset's own lead-in
        noise = noise * (VMAX * 0.9 / speed)
    amp = float(np.max(np.abs(noise))) if noise.size else 0.0
    offset = _lin(u[3], -1.0, 1.0) * max(0.0, XMAX - amp)
    lead_in = _move(0.0, offset, dt, speed=VMAX * 0.05)
    body = offset + noise
    x = np.concatenate([[0.0], lead_in, body])
    x = np.concatenate([x, _hold(x[-1], hold, dt)])
    return x, {
        "n_index": n_index,
        "peak_m": amp,
        "band_hz": [lo, hi],
        "offset_m": offset,
        "duration_s": dur,
        "seed": seed,
        "hold_s": hold,
    }


_RIG_BUILDERS: dict[str, tuple[int, Callable]] = {
    "step": (4, _step),
    "ramp": (4, _ramp),
    "pulse": (4, _pulse),
    "sine": (5, _sine),
    "chirp": (6, _chirp),
    "random_ood": (7, _random_ood),
}
_SLOT_DIM = 1 + max(d for d, _ in _RIG_BUILDERS.values())
_SLOT_NAMES = tuple(_RIG_BUILDERS)


def _pick_name(u0: float) -> str:
    return _SLOT_NAMES[min(len(_SLOT_NAMES) - 1, int(np.clip(u0, 0, 1) * len(_SLOT_NAMES)))]


def _any(u, dt, max_s, lim):
    name = _pick_name(u[0])
    d, build = _RIG_BUILDERS[name]
    x, params = build(u[1 : 1 + d], dt, max_s, lim)
    return x, {"family": name, **params}


SEQUENCE_SLOTS = 3


def _sequence(u, dt, max_s, lim):
    parts: list[np.ndarray] = [np.zeros(1)]
    slots = []
    per_slot = max_s / SEQUENCE_SLOTS
    for k in range(SEQUENCE_SLOTS):
        uk = u[k * _SLOT_DIM : (k + 1) * _SLOT_DIM]
        seg, params = _any(uk, dt, per_slot * 0.9, lim)
        seg = seg[1:] if seg.size and seg[0] == 0.0 else seg
        # join: move from where we are to the segment's start at a moderate speed
        start = parts[-1][-1] if parts[-1].size else 0.0
        parts.append(_move(start, seg[0], dt, _limits(lim)[1] / 2))
        parts.append(seg)
        slots.append(params)
    x = np.concatenate(parts)
    return x, {"slots": slots}


ANY = Family("any", _SLOT_DIM, "rig", _any, random=False, finish=_finish)
ONE_COORDINATE: list[Family] = [
    *(Family(name, d, "rig", build, finish=_finish) for name, (d, build) in _RIG_BUILDERS.items()),
    Family("sequence", SEQUENCE_SLOTS * _SLOT_DIM, "rig", _sequence, finish=_finish),
    ANY,
]


# ----- several coordinates: u -> (q (T, 3), params) ----------------------------------------------
def _strokes_speeds(lim) -> tuple[np.ndarray, np.ndarray]:
    stroke, rate = limits_arrays(lim)
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
    stroke, rate = limits_arrays(lim)
    i = _pick(u[0], 3)
    scale = stroke[i] / MACHINE.stroke_m
    one = MACHINE
    if rate[i] / scale < MACHINE.velocity_m_per_s * (1 - 1e-9):  # slower than the machine
        one = replace(MACHINE, velocity_m_per_s=rate[i] / scale)
    x = ANY.profile(u[1:], dt, max_s, limits=one) * scale
    q = np.zeros((x.size, 3))
    q[:, i] = x
    params = ANY.describe(u[1:], dt, max_s, limits=one)
    return q, {"axis": COORDS[i], **params}


_COMBINED = {
    "preload_step": (6, _preload_step),
    "rotation_sweep": (6, _rotation_sweep),
    "orbit": (6, _orbit),
    "random3": (9, _random3),
}
_ANY_DIM = 1 + max(d for d, _ in _COMBINED.values())


def _any3(u, dt, max_s, lim):
    names = list(_COMBINED)
    name = names[_pick(u[0], len(names))]
    d, build = _COMBINED[name]
    q, params = build(u[1 : 1 + d], dt, max_s, lim)
    return q, {"family": name, **params}


ONE_AXIS_DIM = 1 + ANY.dim
COMBINED: list[Family] = [
    *(
        Family(name, d, TARGET, build, finish=finish_coords)
        for name, (d, build) in _COMBINED.items()
    ),
    Family("any3", _ANY_DIM, TARGET, _any3, random=False, finish=finish_coords),
    Family("one_axis", ONE_AXIS_DIM, TARGET, _one_axis, random=False, finish=finish_coords),
]
