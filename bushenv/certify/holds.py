"""The free run after a step to a held displacement: where it settles, whether it departs.

Profiles are the machine's step test (``machine.step_item``, seed 000 §5.2): ``STEP_PRE_S`` at
rest, a one-sample step (or the shortest half-cosine rise the velocity limit allows), then the
hold. The model runs free (``model.simulate``) on all holds as one batch; its trace in the hold
is compared with the fixed points and ghosts of the analysis (``fixed_points``, ``ghosts``).

Departure (in the network's scaled output y; thresholds are fractions of ``f_scale``):
the run *lingers* when y moves less than ``PLATEAU_RANGE`` within ``LINGER_S``; it *departs*
when, after lingering at a level more than ``JUMP`` from where it ends, it later moves more than
``JUMP`` from that level faster than it moved while lingering (a slow exponential approach to
a weakly stable fixed point only slows down, so it is not a departure). The departure time is
that first sample more than ``JUMP`` away, counted from the step. A run still lingering at the
end of the horizon away from every fixed point gets a *predicted* departure time from the
slow-flow integral (``ghosts.slow_flow_time``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.certify.fixed_points import FixedPoints
from bushenv.certify.ghosts import Ghosts, slow_flow_time
from bushenv.certify.network import NarxNet, diagonal
from bushenv.machine import STEP_PRE_S, step_item

# 20 s: twice the papers' 10 s hold (so a departure like their 7.3 s one is seen, not only
# predicted); and the reference rubber's slowest relaxation (tau = 3 s) is 99.9 % done.
HOLD_S = 20.0
AVERAGE_S = 1.0  # the reference's static force: mean of the last second (averages its noise)
LINGER_S = 0.5
PLATEAU_RANGE = 0.01  # of f_scale, within LINGER_S
JUMP = 0.05  # of f_scale
REACH_TOL = 0.01  # of f_scale: the last second stays this close to a fixed point
ACCELERATION = 3.0  # leaving: the fastest sample after the plateau vs its mean speed on it


def step_profiles(x_m: np.ndarray, hold_s: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(T, M) step-and-hold profiles (shorter ones padded with their hold) and (M,) indices
    of the first sample at the held value."""
    # the machine's step with a short hold, then the rest of the hold: the same samples as
    # step_item(x, hold_s, ...) without building a whole profile per hold
    short = min(0.1, hold_s)
    heads = [step_item(float(x), short, dt, pre_s=STEP_PRE_S).x for x in np.atleast_1d(x_m)]
    T = max(h.size for h in heads) + int(round((hold_s - short) / dt))
    prof = np.empty((T, len(heads)))
    for i, (h, x) in enumerate(zip(heads, np.atleast_1d(x_m), strict=True)):
        prof[: h.size, i] = h
        prof[h.size :, i] = x
    start = np.argmax(prof == prof[-1], axis=0)
    return prof, start


def reference_static_force(
    reference, x_m: np.ndarray, hold_s: float = HOLD_S, average_s: float = AVERAGE_S
) -> np.ndarray:
    """(M,) the reference's settled force, N: mean of its last ``average_s`` of a ``hold_s``
    hold after the machine's step from rest (the same profile the model runs)."""
    prof, _ = step_profiles(x_m, hold_s, reference.dt)
    f = reference.copy().simulate(prof)
    n = max(1, int(round(average_s / reference.dt)))
    return f[-n:].mean(axis=0)


@dataclass(frozen=True)
class HoldRun:
    """The free run at one hold. ``reached``: index among that hold's fixed points (by
    increasing y) where the run ends, or the one it will reach after a
    predicted departure; None when it oscillates or no fixed point is in its way.
    ``departure_s`` counts from the step; ``observed`` False means predicted.
    ``departs_from``: "ghost", "unstable fixed point" or None (not explained).
    ``linger_force_n``: where a departing run sat before it left (else None), N."""

    reached: int | None
    departs: bool
    departure_s: float | None
    observed: bool
    departs_from: str | None
    oscillates: bool
    final_force_n: float
    linger_force_n: float | None = None


def _windows(y: np.ndarray, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Range (max - min) and mean of every window of ``w`` samples of (T, M) ``y``, each
    (T - w + 1, M); row k is the window [k, k + w)."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    half = w // 2
    rng = maximum_filter1d(y, w, axis=0) - minimum_filter1d(y, w, axis=0)
    c = np.concatenate([np.zeros((1, y.shape[1])), np.cumsum(y, axis=0)])
    return rng[half : y.shape[0] - w + 1 + half], (c[w:] - c[:-w]) / w


def _explain(level: float, ys: np.ndarray, stable: np.ndarray, ghost_y: np.ndarray) -> str | None:
    near = JUMP
    if ghost_y.size and np.min(np.abs(ghost_y - level)) < near:
        return "ghost"
    unstable = ys[~stable]
    if unstable.size and np.min(np.abs(unstable - level)) < near:
        return "unstable fixed point"
    return None


def _observed_departure(
    y: np.ndarray, r: np.ndarray, level_all: np.ndarray, w: int
) -> tuple[int, float] | None:
    """(sample of departure, plateau level) of the last lingering that was left, or None.
    ``r``, ``level_all``: range and mean of the windows of ``y`` (``_windows``)."""
    if y.size <= 2 * w:
        return None
    calm = np.flatnonzero((r < PLATEAU_RANGE) & (np.abs(level_all - y[-1]) > JUMP))
    if calm.size == 0:
        return None
    start = int(calm[-1])  # window [start, start + w)
    level = float(level_all[start])
    after = np.flatnonzero(np.abs(y[start + w :] - level) > JUMP)
    if after.size == 0:
        return None
    leave = start + w + int(after[0])
    speed_on = np.mean(np.abs(np.diff(y[start : start + w]))) + 1e-15
    speed_after = np.max(np.abs(np.diff(y[start + w - 1 : leave + 1])))
    if speed_after < ACCELERATION * speed_on:
        return None
    return leave, level


def hold_run(
    net: NarxNet,
    fp: FixedPoints,
    gh: Ghosts,
    i: int,
    y: np.ndarray,
    step: int,
    windows: tuple[np.ndarray, np.ndarray],
) -> HoldRun:
    """Classify hold ``i``'s free-run trace ``y`` (T,) (scaled output; the step at ``step``;
    ``windows``: its ``_windows`` of ``LINGER_S``)."""
    idx = fp.of_hold(i)
    ys, stable = fp.y[idx], fp.stable[idx]
    ghost_y = gh.y[gh.hold == i]
    dt, x = net.dt_s, float(fp.x_m[i])
    w = max(2, int(round(LINGER_S / dt)))
    tail = y[-max(2, int(round(1.0 / dt))) :]
    final = float(net.force_n(x, y[-1]))
    dist = np.max(np.abs(tail[:, None] - ys[None, :]), axis=0)
    # an unstable fixed point is "reached" only by a run that sits exactly on it (from rest)
    at = np.flatnonzero(dist < REACH_TOL)
    if at.size:
        reached = int(at[np.argmin(dist[at] + 1e3 * ~stable[at])])
        dep = _observed_departure(y[step:], windows[0][step:], windows[1][step:], w)
        if dep is None:
            return HoldRun(reached, False, None, True, None, False, final)
        leave, level = dep
        why = _explain(level, ys, stable, ghost_y)
        linger = float(net.force_n(x, level))
        return HoldRun(reached, True, leave * dt, True, why, False, final, linger)
    last = tail[-w:]
    reversals = np.count_nonzero(np.diff(np.sign(np.diff(last))) != 0)
    if np.ptp(last) >= PLATEAU_RANGE and reversals > 2:
        return HoldRun(None, False, None, True, None, True, final)
    # still on its way, away from every fixed point: predict when it leaves and where to
    remaining, moves = slow_flow_time(net, x, float(y[-1]), JUMP)
    if not moves:
        return HoldRun(None, False, None, False, None, False, final)
    direction = np.sign(_phi(net, x, float(y[-1])))
    ahead = np.flatnonzero((ys - y[-1]) * direction > JUMP)
    reached = None
    if ahead.size:
        reached = int(ahead[0] if direction > 0 else ahead[-1])
    level = float(np.mean(y[-w:]))
    why = _explain(level, ys, stable, ghost_y)
    departure = (y.size - 1 - step) * dt + remaining
    return HoldRun(reached, True, departure, False, why, False, final, float(net.force_n(x, level)))


def _phi(net: NarxNet, x: float, y: float) -> float:
    phi, _ = diagonal(net, net.held_preactivation(np.array([x])), np.array([y]))
    return float(phi[0])


def free_runs(
    model, net: NarxNet, fp: FixedPoints, gh: Ghosts, hold_s: float = HOLD_S
) -> tuple[list[HoldRun], np.ndarray, np.ndarray]:
    """Every hold of ``fp`` run free after the machine's step: (runs, profiles (T, M),
    forces (T, M)). The model is copied (its state is not touched)."""
    prof, start = step_profiles(fp.x_m, hold_s, net.dt_s)
    f = model.copy().simulate(prof)
    y = net.output_of_force(prof, f)  # v = 0 in a hold, so the backbone is k x alone
    w = max(2, int(round(LINGER_S / net.dt_s)))
    rng, mean = _windows(y, w)
    runs = [
        hold_run(net, fp, gh, i, y[:, i], int(start[i]), (rng[:, i], mean[:, i]))
        for i in range(fp.x_m.size)
    ]
    return runs, prof, f
