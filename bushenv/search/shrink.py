"""Shrinking: reduce a failing profile to the simplest one that still fails.

Like a property-based test shrinking its counterexample (Hypothesis, QuickCheck), each round
builds candidate simplifications of the current profile, evaluates them all in ONE batch and
keeps the simplest candidate that still diverges; it stops when no candidate is simpler and
still failing, or when the evaluation budget is spent.

Simplicity is the tuple ``(segments, length, peak)`` compared in that order: fewer segments
first (maximal runs in which the profile holds, rises or falls: a held step has three), then
shorter, then a smaller peak |x| (rounded to a micrometre). Segments come first because a
reader understands a three-segment step failing at 2.7 s faster than a fifteen-segment wiggle
failing at 2.6 s; the length stays near its minimum anyway, since every accepted candidate is
cut right after its own failure. Candidate moves:

- truncate right after the first failure sample (free: models are causal, so the prefix fails
  at the same sample; applied after every accepted step);
- delete a chunk (halves, quarters, ... down to ~50 ms) and join the two sides with a
  velocity-limited half-cosine move;
- flatten a chunk: hold the value before it, then move to the value after it (same length,
  fewer segments);
- collapse the start (one move straight to the value at 1/8, 2/8, ... of the profile) or hold
  from there to the end;
- scale the whole profile by 0.5, 0.7, 0.85 or 0.95 (smaller amplitude).

Each candidate is judged with a ``TAIL_S`` hold appended and then cut after its own failure,
so a simplification that fails a little later than the original still counts if it is simpler
once cut. Rig candidates pass ``excitation.clip_to_limits`` (they stay drivable) and start at rest.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.family_base import SPEED_MARGIN

SCALES = (0.5, 0.7, 0.85, 0.95)
MIN_CHUNK_S = 0.05
MAX_CANDIDATES_PER_ROUND = 48
TAIL_S = 2.0  # hold appended to candidates while judging them
MARGIN = 0.1  # robustness a shrunk failure must keep below zero (10 % of a threshold)


def n_segments(x: np.ndarray) -> int:
    """Maximal runs of holding / rising / falling (sign of the sample-to-sample change)."""
    x = np.asarray(x, dtype=np.float64)
    if x.size < 2:
        return 1
    d = np.diff(x)
    s = np.where(np.abs(d) < 1e-9, 0, np.sign(d)).astype(int)
    return 1 + int(np.count_nonzero(s[1:] != s[:-1]))


def complexity(x: np.ndarray) -> tuple[int, int, int]:
    """(segments, length, peak in micrometres): smaller is simpler, compared in order. A
    (T, k) profile counts the segments of its moving coordinates (a coordinate at rest counts
    none), its samples and its largest |x| in micro-units (um, urad)."""
    x = np.asarray(x)
    if x.ndim == 2:
        moving = [x[:, i] for i in range(x.shape[1]) if np.any(x[:, i] != 0.0)]
        segments = sum(n_segments(c) for c in moving)
        return (segments, int(x.shape[0]), int(round(float(np.max(np.abs(x))) * 1e6)))
    return (n_segments(x), int(x.size), int(round(float(np.max(np.abs(x))) * 1e6)))


@dataclass
class ShrinkResult:
    profile: np.ndarray
    verdict: dict
    evaluations: int
    rounds: int
    original: tuple[int, int, int]
    final: tuple[int, int, int]

    def summary(self) -> dict:
        return {
            "evaluations": self.evaluations,
            "rounds": self.rounds,
            "original": dict(zip(("segments", "samples", "peak_um"), self.original, strict=True)),
            "final": dict(zip(("segments", "samples", "peak_um"), self.final, strict=True)),
        }


def _join(a: float, b: float, dt: float, vmax: float) -> np.ndarray:
    """Half-cosine move from a (excluded) to b (included) at half the velocity limit."""
    dist = abs(b - a)
    if dist < 1e-12:
        return np.zeros(0)
    n = max(1, math.ceil(dist * math.pi / 2 / (0.5 * vmax * dt)))
    s = np.arange(1, n + 1) / n
    return a + (b - a) * 0.5 * (1.0 - np.cos(np.pi * s))


def _candidates(x: np.ndarray, dt: float, finish, vmax: float) -> list[np.ndarray]:
    T = x.size
    out: list[np.ndarray] = []
    for k in range(1, 8):  # collapse the start: one move straight to where the profile is at a
        a = k * T // 8
        if 1 < a < T - 1:
            out.append(np.concatenate([[0.0], _join(0.0, x[a], dt, vmax), x[a + 1 :]]))
            out.append(np.concatenate([x[:a], np.full(T - a, x[a - 1])]))  # hold from a on
    min_chunk = max(2, int(round(MIN_CHUNK_S / dt)))
    chunk = T // 2
    while chunk >= min_chunk and len(out) < MAX_CANDIDATES_PER_ROUND:
        for a in range(1, T - 1, chunk):
            b = min(T - 1, a + chunk)
            if b <= a:
                continue
            join = _join(x[a - 1], x[b], dt, vmax)
            out.append(np.concatenate([x[:a], join[:-1], x[b:]]))  # delete [a, b)
            n_join = join.size
            if b - a > n_join:  # flatten [a, b): hold, then move to x[b]
                held = np.full(b - a - n_join + 1, x[a - 1])
                out.append(np.concatenate([x[:a], held, join[:-1], x[b:]]))
        chunk //= 2
    out = out[: MAX_CANDIDATES_PER_ROUND - len(SCALES)]
    out.extend(x * s for s in SCALES)
    fixed = []
    for c in out:
        if c.size < 2:
            continue
        c = c.copy()
        c[0] = 0.0
        fixed.append(finish(c, dt))
    return fixed


def _truncate(c: np.ndarray, r: dict, dt: float) -> np.ndarray:
    """``c`` cut right after its first failure (nothing after it can make it simpler)."""
    t = r.get("first_time_s")
    if t is None:
        return c
    return c[: max(2, int(round(t / dt)) + 1)]


def _default_rule(row: dict) -> Callable[[dict], bool]:
    r0 = row["robustness"]
    margin = MARGIN if r0 is None else min(MARGIN, abs(r0) / 2)

    def still_fails(r: dict) -> bool:
        rob = r["robustness"]
        return bool(r["diverged"]) and (rob is None or rob < -margin)

    return still_fails


def moves(x: np.ndarray, dt: float, target, limits) -> list[np.ndarray]:
    """Every candidate one round of shrinking tries from ``x`` (the moves of the module doc),
    each started at rest and kept within ``target``'s limits (``Target.finish``)."""

    def finish(c: np.ndarray, dt: float) -> np.ndarray:
        return target.finish(c, dt, limits)

    if np.ndim(x) == 2:
        return _axis_candidates(np.asarray(x), dt, finish)
    return _candidates(x, dt, finish, limits.velocity_m_per_s * SPEED_MARGIN)


def _axis_candidates(x: np.ndarray, dt: float, finish) -> list[np.ndarray]:
    """Moves for a (T, k) profile, one coordinate at a time: put a coordinate at rest, scale
    one down; then all together: hold everything from 1/8, 2/8, ... of the profile on, and
    scale the whole (each kept within the limits by ``finish``)."""
    T, k = x.shape
    out: list[np.ndarray] = []
    for i in range(k):
        if np.any(x[:, i] != 0.0):
            zeroed = x.copy()
            zeroed[:, i] = 0.0
            out.append(zeroed)
            for s in (0.5, 0.85):
                scaled = x.copy()
                scaled[:, i] *= s
                out.append(scaled)
    for j in range(1, 8):
        a = j * T // 8
        if 1 < a < T - 1:
            out.append(np.concatenate([x[:a], np.repeat(x[a - 1 : a], T - a, axis=0)]))
    out.extend(x * s for s in SCALES)
    fixed = []
    for c in out[:MAX_CANDIDATES_PER_ROUND]:
        c = c.copy()
        c[0] = 0.0
        fixed.append(finish(c, dt))
    return fixed


def _simplest_failing(x, evaluator, still_fails, room: int):
    """One round: the simplest candidate simpler than ``x`` that still fails (None if none
    does), its verdict row, and whether there was any candidate to try."""
    dt = evaluator.dt
    cands = moves(x, dt, evaluator.target, evaluator.scales)
    cands = [c for c in cands if complexity(c) < complexity(x)][:room]
    if not cands:
        return None, None, False
    # a hold appended to each: a simplification may fail a little later than the original
    # did (truncation cut right after its failure); the prefix is truncated again below
    tail = int(round(TAIL_S / dt))
    cands = [np.concatenate([c, np.repeat(c[-1:], tail, axis=0)]) for c in cands]
    batch = evaluator.evaluate(cands)
    best, best_row = None, None
    for b, c in enumerate(cands):
        r = batch.verdict.row(b)
        if still_fails(r):
            c = _truncate(c, r, dt)
            if best is None or complexity(c) < complexity(best):
                best, best_row = c, r
    return best, best_row, True


def shrink(
    profile: np.ndarray,
    evaluator: BatchEvaluator,
    budget: int = 256,
    still_fails: Callable[[dict], bool] | None = None,
) -> ShrinkResult:
    """Simplest profile, reachable by the moves above, on which ``evaluator``'s model diverges.

    ``still_fails(verdict_row)`` decides whether a candidate counts as failing. By default it
    must diverge with robustness below ``-min(MARGIN, |r0| / 2)``, r0 the original's: shrinking
    walks towards the failure boundary, and a case sitting exactly on it would flip with the
    last bit of rounding (e.g. the corpus's float32 storage). The input must fail; otherwise
    ValueError.
    """
    dt = evaluator.dt
    x = np.asarray(profile, dtype=np.float64).copy()
    start_evals = evaluator.n_evaluations
    first = evaluator.evaluate([x])
    row = first.verdict.row(0)
    still_fails = still_fails or _default_rule(row)
    if not still_fails(row):
        raise ValueError("shrink: the profile to shrink does not fail on this model")
    original = complexity(x)
    x = _truncate(x, row, dt)
    row = evaluator.evaluate([x]).verdict.row(0)
    if not still_fails(row):  # cannot happen for a causal model; keep the original then
        x = np.asarray(profile, dtype=np.float64).copy()
        row = first.verdict.row(0)
    rounds = 0
    while evaluator.n_evaluations - start_evals < budget - 1:  # one kept for the final check
        room = budget - 1 - (evaluator.n_evaluations - start_evals)
        best, best_row, tried = _simplest_failing(x, evaluator, still_fails, room)
        if not tried:
            break
        rounds += 1
        if best is None or complexity(best) >= complexity(x):
            break
        x, row = best, best_row
    # the final profile is judged as it stands (after the last truncation)
    final_row = evaluator.evaluate([x]).verdict.row(0)
    if still_fails(final_row):
        row = final_row
    return ShrinkResult(
        profile=x,
        verdict=row,
        evaluations=evaluator.n_evaluations - start_evals,
        rounds=rounds,
        original=original,
        final=complexity(x),
    )
