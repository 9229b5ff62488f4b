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

from bushenv import excitation as ex
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


def _rise_s(q: np.ndarray, units: tuple[str, ...], dt: float) -> float | None:
    """The machine's rise to the hold ``q`` (C,): None for one coordinate (``step_item``'s own
    rule); over several, the shortest half-cosine rise that keeps every translation within the
    machine's velocity, so that all coordinates arrive together."""
    if len(q) == 1:
        return None
    rise = 0.0
    for x, u in zip(q, units, strict=True):
        if u == "m" and abs(x) / dt > ex.MAX_VELOCITY_M_PER_S:
            rise = max(rise, 0.5 * np.pi * abs(x) / ex.MAX_VELOCITY_M_PER_S * (1 + 1e-6))
    return rise


def step_profiles(
    q: np.ndarray, hold_s: float, dt: float, units: tuple[str, ...] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Step-and-hold profiles to each hold (shorter ones padded with their hold) and (M,)
    indices of the first sample at the held value: ``q`` (M,) one coordinate -> (T, M);
    ``q`` (M, C) -> (T, M, C) (``units`` of the coordinates, default m)."""
    q = np.asarray(q, dtype=np.float64)
    one = q.ndim <= 1
    q = q.reshape(-1, 1) if one else q
    units = units or ("m",) * q.shape[1]
    # the machine's step with a short hold, then the rest of the hold: the same samples as
    # step_item(x, hold_s, ...) without building a whole profile per hold
    short = min(0.1, hold_s)
    heads = []
    for row in q:
        rise = _rise_s(row, units, dt)
        heads.append(
            np.stack(
                [step_item(float(x), short, dt, pre_s=STEP_PRE_S, rise_s=rise).x for x in row], -1
            )
        )
    T = max(len(h) for h in heads) + int(round((hold_s - short) / dt))
    prof = np.empty((T, len(heads), q.shape[1]))
    for i, (h, row) in enumerate(zip(heads, q, strict=True)):
        prof[: len(h), i] = h
        prof[len(h) :, i] = row
    start = np.argmax(np.all(prof == prof[-1], axis=-1), axis=0)
    return (prof[..., 0], start) if one else (prof, start)


def reference_static_force(
    reference, q: np.ndarray, hold_s: float = HOLD_S, average_s: float = AVERAGE_S
) -> np.ndarray:
    """The reference's settled force at each hold, N (N m for a rotation): mean of its last
    ``average_s`` of a ``hold_s`` hold after the machine's step from rest (the same profile
    the model runs). ``q`` (M,) one coordinate -> (M,); (M, C) -> (M, C)."""
    prof, _ = step_profiles(q, hold_s, reference.dt, tuple(reference.units))
    f = reference.copy().simulate(prof)
    n = max(1, int(round(average_s / reference.dt)))
    return f[-n:].mean(axis=0)


@dataclass(frozen=True, eq=False)
class HoldRun:
    """The free run at one hold. ``reached``: index among that hold's fixed points (in the
    order of ``FixedPoints.of_hold``) where the run ends, or the one it will reach after a
    predicted departure; None when it oscillates or no fixed point is in its way.
    ``departure_s`` counts from the step; ``observed`` False means predicted.
    ``departs_from``: "ghost", "unstable fixed point" or None (not explained).
    ``final_force`` (C,) the force at the end of the hold; ``linger_force`` (C,) where a
    departing run sat before it left (else None), N or N m."""

    reached: int | None
    departs: bool
    departure_s: float | None
    observed: bool
    departs_from: str | None
    oscillates: bool
    final_force: np.ndarray
    linger_force: np.ndarray | None = None

    @property
    def linger_force_n(self) -> float | None:
        """``linger_force`` of a one-coordinate run, N."""
        return None if self.linger_force is None else float(self.linger_force[0])


def _windows(y: np.ndarray, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Range (max - min) and mean of every window of ``w`` samples of (T, M) ``y``, each
    (T - w + 1, M); row k is the window [k, k + w)."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    half = w // 2
    rng = maximum_filter1d(y, w, axis=0) - minimum_filter1d(y, w, axis=0)
    c = np.concatenate([np.zeros((1, y.shape[1])), np.cumsum(y, axis=0)])
    return rng[half : y.shape[0] - w + 1 + half], (c[w:] - c[:-w]) / w


def _explain(level: np.ndarray, ys: np.ndarray, stable: np.ndarray, ghost_y: np.ndarray):
    """What a run lingered at, ``level`` (C,): a ghost or an unstable fixed point (each (k, C))
    within ``JUMP`` in every coordinate, or None."""
    if ghost_y.size and np.min(np.max(np.abs(ghost_y - level), axis=-1)) < JUMP:
        return "ghost"
    unstable = ys[~stable]
    if unstable.size and np.min(np.max(np.abs(unstable - level), axis=-1)) < JUMP:
        return "unstable fixed point"
    return None


def _observed_departure(
    y: np.ndarray, r: np.ndarray, level_all: np.ndarray, w: int
) -> tuple[int, int] | None:
    """(sample of departure, first sample of the plateau) of the last lingering that was left
    by the one-coordinate trace ``y``, or None. ``r``, ``level_all``: range and mean of the
    windows of ``y`` (``_windows``)."""
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
    return leave, start


def _departure(y, windows, w) -> tuple[int, int] | None:
    """The earliest observed departure over the coordinates of ``y`` (T, C)."""
    found = [_observed_departure(y[:, j], windows[0][:, j], windows[1][:, j], w)
             for j in range(y.shape[1])]  # fmt: skip
    found = [d for d in found if d is not None]
    return min(found) if found else None


def hold_run(
    net: NarxNet,
    fp: FixedPoints,
    gh: Ghosts,
    i: int,
    y: np.ndarray,
    step: int,
    windows: tuple[np.ndarray, np.ndarray],
) -> HoldRun:
    """Classify hold ``i``'s free-run trace ``y`` (T, C) (scaled output; the step at ``step``;
    ``windows``: its ``_windows`` of ``LINGER_S``, each (T', C)). A run still moving at the end,
    away from every fixed point, gets a predicted departure from the slow flow along the
    diagonal (``ghosts``: one coordinate); over several coordinates it is left unsettled."""
    idx = fp.of_hold(i)
    ys, stable = fp.y[idx], fp.stable[idx]
    ghost_y = gh.y[gh.hold == i][:, None] if fp.q.shape[1] == 1 else np.zeros((0, fp.q.shape[1]))
    dt, q = net.dt_s, fp.q[i]
    w = max(2, int(round(LINGER_S / dt)))
    tail = y[-max(2, int(round(1.0 / dt))) :]
    final = net.force(q, y[-1])
    dist = np.max(np.abs(tail[:, None, :] - ys[None, :, :]), axis=(0, 2))
    # an unstable fixed point is "reached" only by a run that sits exactly on it (from rest)
    at = np.flatnonzero(dist < REACH_TOL)
    if at.size:
        reached = int(at[np.argmin(dist[at] + 1e3 * ~stable[at])])
        dep = _departure(y[step:], (windows[0][step:], windows[1][step:]), w)
        if dep is None:
            return HoldRun(reached, False, None, True, None, False, final)
        leave, start = dep
        level = windows[1][step + start]
        why = _explain(level, ys, stable, ghost_y)
        return HoldRun(reached, True, leave * dt, True, why, False, final, net.force(q, level))
    last = tail[-w:]
    reversals = np.count_nonzero(np.diff(np.sign(np.diff(last, axis=0)), axis=0) != 0, axis=0)
    if np.any((np.ptp(last, axis=0) >= PLATEAU_RANGE) & (reversals > 2)):
        return HoldRun(None, False, None, True, None, True, final)
    if fp.q.shape[1] > 1:
        return HoldRun(None, False, None, False, None, False, final)
    # still on its way, away from every fixed point: predict when it leaves and where to
    x, y1 = float(q[0]), y[:, 0]
    remaining, moves = slow_flow_time(net, x, float(y1[-1]), JUMP)
    if not moves:
        return HoldRun(None, False, None, False, None, False, final)
    direction = np.sign(_phi(net, x, float(y1[-1])))
    ahead = np.flatnonzero((ys[:, 0] - y1[-1]) * direction > JUMP)
    reached = None
    if ahead.size:
        reached = int(ahead[0] if direction > 0 else ahead[-1])
    level = np.mean(y[-w:], axis=0)
    why = _explain(level, ys, stable, ghost_y)
    departure = (y1.size - 1 - step) * dt + remaining
    return HoldRun(reached, True, departure, False, why, False, final, net.force(q, level))


def _phi(net: NarxNet, x: float, y: float) -> float:
    phi, _ = diagonal(net, net.held_preactivation(np.array([x])), np.array([y]))
    return float(phi[0])


def free_runs(
    model, net: NarxNet, fp: FixedPoints, gh: Ghosts, hold_s: float = HOLD_S
) -> tuple[list[HoldRun], np.ndarray, np.ndarray]:
    """Every hold of ``fp`` run free after the machine's step: (runs, profiles, forces), each
    (T, M, C). The model is copied (its state is not touched)."""
    prof, start = step_profiles(fp.q, hold_s, net.dt_s, net.units)
    run_in = prof[..., 0] if net.n_coords == 1 else prof
    f = model.copy().simulate(run_in).reshape(prof.shape)
    # v = 0 in a hold, so the backbone is K q alone
    y = (f - np.sum(prof[..., None, :] * net.k, axis=-1) - net.f_offset) / net.f_scale
    T, M, C = y.shape
    w = max(2, int(round(LINGER_S / net.dt_s)))
    rng, mean = _windows(y.reshape(T, M * C), w)
    rng, mean = rng.reshape(-1, M, C), mean.reshape(-1, M, C)
    runs = [
        hold_run(net, fp, gh, i, y[:, i], int(start[i]), (rng[:, i], mean[:, i])) for i in range(M)
    ]
    return runs, prof, f
