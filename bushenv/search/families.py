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

``family.profile(u, dt)`` returns the (T,) profile; ``family.describe(u)`` its physical
parameters as a dict (for reports and the corpus). Both are pure functions of ``u``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bushenv import excitation as ex
from bushenv.errors import BadInput
from bushenv.models.base import PAPER_DT
from bushenv.registry import Registry
from bushenv.scales import MACHINE, BushingScales

MAX_PROFILE_S = 12.0  # the papers' step is held 10 s; 12 s covers their 7.3 s departure
MIN_HOLD_S = 0.5
SPEED_MARGIN = 0.98  # stay 2 % inside the machine's velocity limit
VMAX = ex.MAX_VELOCITY_M_PER_S * SPEED_MARGIN  # the papers' machine; a bushing's own: _limits
ROAD_MAX_HEIGHT_M = 0.15  # QuarterCar-v0's max_road_height_m: kerbs, potholes, the papers' bumps
# QuarterCar-v0 lets the road move at most max_road_step_m = 0.05 m per 1/204.8 s step
# (10.24 m/s); road profiles stay 5 % inside that so the env can replay them.
ROAD_MAX_RATE_M_PER_S = 0.95 * 0.05 * 204.8


class FamilyError(BadInput):
    """Bad family name or parameter vector."""


def _lin(u: float, lo: float, hi: float) -> float:
    return lo + (hi - lo) * float(np.clip(u, 0.0, 1.0))


def _log(u: float, lo: float, hi: float) -> float:
    return float(math.exp(_lin(u, math.log(lo), math.log(hi))))


def _n(duration_s: float, dt: float) -> int:
    return max(0, int(round(duration_s / dt)))


def _hold(value: float, duration_s: float, dt: float) -> np.ndarray:
    return np.full(_n(duration_s, dt), float(value))


def _move(start_m: float, end_m: float, dt: float, speed: float) -> np.ndarray:
    """Half-cosine move from start (excluded) to end at mean ``speed`` (peak pi/2 times it)."""
    dist = abs(end_m - start_m)
    if dist == 0.0:
        return np.zeros(0)
    n = max(1, math.ceil(dist * math.pi / 2 / (speed * dt)))
    s = np.arange(1, n + 1) / n
    return start_m + (end_m - start_m) * 0.5 * (1.0 - np.cos(np.pi * s))


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


def _pick(u0: float) -> str:
    return _SLOT_NAMES[min(len(_SLOT_NAMES) - 1, int(np.clip(u0, 0, 1) * len(_SLOT_NAMES)))]


def _any(u, dt, max_s, lim):
    name = _pick(u[0])
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


@dataclass(frozen=True)
class Family:
    """One excitation family: ``dim`` unit-cube coordinates -> a (T,) profile."""

    name: str
    dim: int
    target: str  # the TARGETS name: "rig" (bushing displacement, m), "quartercar" (road, m)
    build: Callable[[np.ndarray, float, float, BushingScales], tuple[np.ndarray, dict]]
    random: bool = True  # drawn by random search (not so the meta-family "any")
    finish: Callable[[np.ndarray, float, float, BushingScales], np.ndarray] | None = None

    def _check(self, u) -> np.ndarray:
        u = np.asarray(u, dtype=np.float64).reshape(-1)
        if u.shape != (self.dim,):
            raise FamilyError(f"family {self.name!r} takes {self.dim} parameters, got {u.shape}")
        if not np.all(np.isfinite(u)):
            raise FamilyError(f"family {self.name!r}: parameters hold NaN or inf: {u}")
        return np.clip(u, 0.0, 1.0)

    def profile(
        self,
        u,
        dt: float = PAPER_DT,
        max_s: float = MAX_PROFILE_S,
        limits: BushingScales = MACHINE,
    ) -> np.ndarray:
        """The (T,) profile for parameters ``u`` (clipped to [0, 1]) within ``limits`` (the
        bushing's stroke and velocity; default the papers' machine)."""
        x, _ = self.build(self._check(u), dt, max_s, limits)
        if self.finish is not None:
            return self.finish(x, dt, max_s, limits)
        return np.asarray(x, dtype=np.float64)[: _n(max_s, dt)]

    def describe(
        self,
        u,
        dt: float = PAPER_DT,
        max_s: float = MAX_PROFILE_S,
        limits: BushingScales = MACHINE,
    ) -> dict:
        """The physical parameters ``u`` maps to (plain JSON values)."""
        _, params = self.build(self._check(u), dt, max_s, limits)
        return {"family": self.name, **_plain(params)}


def _plain(v):
    if isinstance(v, dict):
        return {k: _plain(w) for k, w in v.items()}
    if isinstance(v, list | tuple):
        return [_plain(w) for w in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


FAMILIES: Registry[Family] = Registry("excitation family", FamilyError)
for _name, (_d, _b) in _RIG_BUILDERS.items():
    FAMILIES.add(_name, Family(_name, _d, "rig", _b, finish=_finish))
FAMILIES.add(
    "sequence", Family("sequence", SEQUENCE_SLOTS * _SLOT_DIM, "rig", _sequence, finish=_finish)
)
FAMILIES.add("any", Family("any", _SLOT_DIM, "rig", _any, random=False, finish=_finish))
FAMILIES.add("bump", Family("bump", 4, "quartercar", _bump))
FAMILIES.add("pothole", Family("pothole", 5, "quartercar", _pothole))


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
