"""Fit a candidate (a combination of effects) on some records and judge it on others.

Weights by bounded linear least squares from the summed Gram products of ``design.py``;
shape settings (heating laws and time constants, delays) by the fitting error
over the product of the members' grids, a delay refined by a bounded 1-D search. ``Fold``s
say which records fit and which are judged: one fold (TRAIN fits, TESTs judged), or one per
record in the cross mode (all others fit, that one is judged).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import linalg
from scipy.optimize import lsq_linear, minimize_scalar

from bushenv.diagnose.design import DAMPER, SPRING, Block, ColumnStore, Prepared
from bushenv.diagnose.effects.base import Combination, Nuisance
from bushenv.diagnose.effects.timeshift import shift_columns

START_NEEDED = 0.05  # the share of a lone record's squared error its warm start must cut


@dataclass(frozen=True)
class Fold:
    """Records whose weights are fitted, and records judged with them."""

    fit: tuple[Prepared, ...]
    judged: tuple[Prepared, ...]


@dataclass
class Fit:
    """A combination with chosen shapes and its fitted weights."""

    combo: Combination
    shapes: tuple
    blocks: tuple[Block, ...]
    theta: np.ndarray
    mse: float  # on the records fitted
    n: int  # samples fitted
    force_ms: float  # mean square of the force fitted (for a relative fitting error)
    nuisance: tuple[Block, ...] = ()  # per-record blocks (a warm start), fitted per record
    nuisance_w: dict = field(default_factory=dict)  # start key (record or session) -> weights
    start_seen_s: dict = field(default_factory=dict)  # start key -> its earliest record fitted

    @property
    def delay_s(self) -> float:
        return sum(m.delay_s(s) for m, s in zip(self.combo.members, self.shapes, strict=True))

    @property
    def n_extra(self) -> int:
        """Weights beyond a spring and a damper, plus one per shape setting chosen."""
        shaped = sum(1 for s in self.shapes if s is not None)
        return int(self.theta.size) - 2 + shaped


def bounded_lstsq(g: np.ndarray, b: np.ndarray, lower: np.ndarray, n: int) -> np.ndarray:
    """min |A w - y| subject to w >= lower, from G = A^T A and b = A^T y.

    Columns are scaled to unit RMS; a ridge of 1e-8 of the scaled diagonal steadies
    near-collinear columns (a long Maxwell branch beside the spring) without biasing the fit.
    """
    p = g.shape[0]
    if p == 0:
        return np.zeros(0)
    scale = np.sqrt(np.maximum(np.diag(g), 0.0) / max(n, 1))
    scale[scale == 0] = 1.0
    gs = g / np.outer(scale, scale) + 1e-8 * n * np.eye(p)
    r = linalg.cholesky(gs, lower=False)
    qy = linalg.solve_triangular(r, b / scale, trans="T")
    lo = lower * scale
    if np.all(np.isneginf(lo)):
        w = linalg.solve_triangular(r, qy)
    else:
        w = lsq_linear(r, qy, bounds=(lo, np.full(p, np.inf)), method="bvls").x
    return w / scale


def blocks_of(store: ColumnStore, combo: Combination, shapes: tuple, linear_base: bool):
    spring = DAMPER if (linear_base and combo.replaces_spring) else SPRING
    blocks = [spring]
    for m, s in zip(combo.members, shapes, strict=True):
        if m.columns_count(s, store.scales) > 0:
            blocks.append((m.name, s))
    return tuple(blocks)


def nuisance_of(store: ColumnStore, combo: Combination, shapes: tuple) -> tuple[Block, ...]:
    """The per-record blocks of ``combo`` at ``shapes`` (a warm start), if any."""
    out = []
    for m, s in zip(combo.members, shapes, strict=True):
        if m.columns_count(Nuisance(s), store.scales) > 0:
            out.append((m.name, Nuisance(s)))
    return tuple(out)


def fit(
    store: ColumnStore,
    combo: Combination,
    shapes: tuple,
    records: tuple[Prepared, ...],
    linear_base: bool,
) -> Fit:
    """Weights of ``combo`` at ``shapes`` by bounded least squares on ``records``; per-record
    blocks (``nuisance_of``) get weights of their own on each record, fitted jointly.

    A lone record keeps its per-record block only where it needs it: the block cuts the
    record's squared error by more than ``START_NEEDED``, else the record is fitted without
    (it starts cold). Under a steady power the heat is affine in a start's cooling
    ``exp(-t / tau)``, so the spring, the heating and a start are one family on one record
    (the smallest singular value 1e-4 of the largest on a steady sine): fitted whole, the
    start traded with them (a spring 43 times the specimen's) and the heating law chosen by
    the trade extrapolated to the other record. Two records or more tell their starts apart."""
    nuis = nuisance_of(store, combo, shapes)
    with_start = _fit(store, combo, shapes, records, linear_base, nuis)
    if len(records) > 1 or not nuis:
        return with_start
    cold = _fit(store, combo, shapes, records, linear_base, ())
    return with_start if with_start.mse < (1.0 - START_NEEDED) * cold.mse else cold


def _fit(
    store: ColumnStore,
    combo: Combination,
    shapes: tuple,
    records: tuple[Prepared, ...],
    linear_base: bool,
    nuis: tuple[Block, ...],
) -> Fit:
    blocks = blocks_of(store, combo, shapes, linear_base)
    delay = sum(m.delay_s(s) for m, s in zip(combo.members, shapes, strict=True))
    p_ = sum(store.columns_count(b) for b in blocks)
    q = sum(store.columns_count(b) for b in nuis)
    starts = list(dict.fromkeys(p.start_key for p in records))  # a session's records share one
    size = p_ + q * len(starts)
    g, b, yy = np.zeros((size, size)), np.zeros(size), 0.0
    for p in records:
        gp = store.gram(p, blocks + nuis)
        bp, yp = store.rhs(p, blocks + nuis, delay)
        o = p_ + starts.index(p.start_key) * q
        g[:p_, :p_] += gp[:p_, :p_]
        b[:p_] += bp[:p_]
        yy += yp
        if q:
            g[:p_, o : o + q] += gp[:p_, p_:]
            g[o : o + q, :p_] += gp[p_:, :p_]
            g[o : o + q, o : o + q] += gp[p_:, p_:]
            b[o : o + q] += bp[p_:]
    n = sum(p.n for p in records)
    lower = np.concatenate([store.lower(blocks), np.zeros(size - p_)])
    w = bounded_lstsq(g, b, lower, n)
    mse = max(float(yy - 2 * w @ b + w @ g @ w) / n, 0.0)
    force_ms = float(sum(np.sum(p.force**2) for p in records)) / n
    own = {k: w[p_ + i * q : p_ + (i + 1) * q] for i, k in enumerate(starts)} if q else {}
    seen = {k: min(p.signals.session_time_s for p in records if p.start_key == k) for k in own}
    return Fit(combo, tuple(shapes), blocks, w[:p_], mse, n, force_ms, nuis, own, seen)


def predict(store: ColumnStore, f: Fit, prep: Prepared) -> np.ndarray:
    """The fitted model's force on one record (N), (T,). A per-record block gets the weights
    the record was fitted with, or its session's where a record of the session run before it
    was fitted (the start has only cooled since). Else one scale of its own along
    ``start_direction``, read from its cooling and its level (``judged_start``), from 0 to
    the warmest fitted record's, or to its session's fitted start (the state it starts in --
    a heat -- is the record's: one bounded number, not a spring and damper of its own; a
    session's start fitted on records run after it, where it has cooled, is read through
    a cooling that may have left little of it)."""
    a = store.design(prep, f.blocks)
    out = prep.b0 + a @ f.theta
    if f.nuisance:
        wn = store.design(prep, f.nuisance)
        own = f.nuisance_w.get(prep.start_key)
        if own is not None and prep.signals.session_time_s >= f.start_seen_s[prep.start_key]:
            out = out + wn @ own
        else:
            direction = start_direction(store, f)
            d = shift_columns(wn @ direction, f.delay_s, prep.dt)
            dd = float(d @ d)
            if dd > 0:
                shifted = shift_columns(out, f.delay_s, prep.dt)
                own_spring = shift_columns(store.design(prep, (SPRING,)), f.delay_s, prep.dt)
                scale = judged_start(prep.force - shifted, d, own_spring)
                top = warmest_start(f, direction, own)
                return shifted + min(max(scale, 0.0), top) * d
    return shift_columns(out, f.delay_s, prep.dt)


def judged_start(residual: np.ndarray, d: np.ndarray, spring: np.ndarray) -> float:
    """A judged record's start along ``d``: the smaller of what its cooling shows
    (``cooling_scale``) and what its level shows (the least-squares scale of ``d`` on the
    residual). Neither reading may claim more than the other: a level without its cooling is
    a stiffness of the record's own (any effect whose secant changes from record to record),
    and a cooling read through a leak long beside the record is noisy where its level is not."""
    level = float(residual @ d) / float(d @ d)
    return min(cooling_scale(residual, d, spring), level)


def cooling_scale(residual: np.ndarray, d: np.ndarray, spring: np.ndarray) -> float:
    """The scale of a judged record's start ``d`` read from its cooling alone: ``d`` less what
    the record's own spring and damper (``spring``, (T, 2)) give of it. A start whose leak is
    long beside the record hardly cools: its level is a stiffness of the record's own, which
    any effect whose secant changes from record to record gives as well (a friction, a
    backbone at a larger amplitude); only its fall through the record is thermal's."""
    part = d - spring @ np.linalg.lstsq(spring, d, rcond=None)[0]
    pp = float(part @ part)
    return float(residual @ part) / pp if pp > 1e-12 * float(d @ d) else 0.0


def warmest_start(f: Fit, direction: np.ndarray, own: np.ndarray | None = None) -> float:
    """The largest fitted record's start along ``direction`` (a scale), or the record's
    session's start (``own``) where it was fitted: a judged record starts no warmer."""
    dd = float(direction @ direction)
    if dd <= 0:
        return 0.0
    starts = [own] if own is not None else list(f.nuisance_w.values())
    return max(max(float(w @ direction) / dd for w in starts), 0.0)


def start_direction(store: ColumnStore, f: Fit) -> np.ndarray:
    """The per-record block's weights up to a scale, for a record judged: the effect's own
    weights where its columns match the per-record ones one to one (a record that starts warm
    loses stiffness and damping in the ratio heating takes them), else the fitted records'
    mean start."""
    mean = np.mean(list(f.nuisance_w.values()), axis=0)
    if len(f.nuisance) != 1:
        return mean
    name, i = f.nuisance[0][0], 0
    for block in f.blocks:
        n = store.columns_count(block)
        if block[0] == name and n == mean.size:
            return f.theta[i : i + n]
        i += n
    return mean


def _product(grids: list[list]) -> list[tuple]:
    out: list[tuple] = [()]
    for g in grids:
        out = [o + (s,) for o in out for s in g]
    return out


def best_shapes(
    store: ColumnStore, combo: Combination, records: tuple[Prepared, ...], linear_base: bool
) -> Fit:
    """The shapes with the lowest fitting error over the product of the members' grids, a
    continuous shape refined from the best of each of its families (a thermal leak under each
    heating law: the coarse grid can rank the laws wrong)."""
    grids = [m.shapes(store.scales) for m in combo.members]

    def delay_of(shapes: tuple) -> float:
        return sum(m.delay_s(s) for m, s in zip(combo.members, shapes, strict=True))

    # by delay, so that the shifted force targets of one delay are used together
    fits = [
        fit(store, combo, c, records, linear_base) for c in sorted(_product(grids), key=delay_of)
    ]
    best = min(fits, key=lambda f: f.mse)
    for i, member in enumerate(combo.members):
        if not (member.continuous_shape and len(grids[i]) >= 3):
            continue
        families: dict = {}
        for f in fits:
            families.setdefault(member.shape_family(f.shapes[i]), []).append(f)
        mine = member.shape_family(best.shapes[i])
        starts = [
            best if fam == mine else min(fs, key=lambda f: f.mse) for fam, fs in families.items()
        ]
        refined = [_refine(store, combo, grids, i, f, records, linear_base) for f in starts]
        best = min([best, *refined], key=lambda f: f.mse)
    return best


def _refine(store, combo, grids, i: int, best: Fit, records, linear_base: bool) -> Fit:
    """Refine shape ``i``'s continuous part between its finite grid neighbours, then choose
    the others again."""
    member = combo.members[i]
    here = best.shapes[i]
    values = sorted(
        member.shape_value(s)
        for s in grids[i]
        if member.shape_family(s) == member.shape_family(here)
    )
    v = member.shape_value(here)
    if len(values) < 2 or not np.isfinite(v):
        return best
    k = values.index(v)
    lo, hi = values[max(k - 1, 0)], values[min(k + 1, len(values) - 1)]
    if not np.isfinite(hi):  # beyond the last finite value: the cumulative heat, no start
        hi = v

    def shaped(log_s: float) -> tuple:
        combo_s = list(best.shapes)
        combo_s[i] = member.with_shape_value(here, float(np.exp(log_s)))
        return tuple(combo_s)

    def mse(log_s: float) -> float:
        return fit(store, combo, shaped(log_s), records, linear_base).mse

    res = minimize_scalar(
        mse, bounds=(np.log(lo), np.log(hi)), method="bounded", options={"xatol": 0.01}
    )
    if res.fun >= best.mse:
        return best
    best = fit(store, combo, shaped(res.x), records, linear_base)
    for j in range(len(grids)):
        if j == i or len(grids[j]) < 2:
            continue
        for s in grids[j]:
            trial_shapes = list(best.shapes)
            trial_shapes[j] = s
            trial = fit(store, combo, tuple(trial_shapes), records, linear_base)
            if trial.mse < best.mse:
                best = trial
    return best


@dataclass
class Judged:
    """A combination fitted fold by fold and judged on the held-out records."""

    combo: Combination
    fits: list[Fit]
    predictions: dict[int, np.ndarray]  # record uid -> held-out prediction
    sse: float
    n: int

    @property
    def mse(self) -> float:
        return self.sse / self.n

    @property
    def gap_train(self) -> float:
        """RMS ratio of the fitting error (fitting records), averaged over folds."""
        return float(np.mean([np.sqrt(f.mse / f.force_ms) for f in self.fits]))

    @property
    def n_extra(self) -> int:
        return self.fits[0].n_extra


def judge(store: ColumnStore, combo: Combination, folds: list[Fold], linear_base: bool) -> Judged:
    """Fit ``combo`` on each fold's fitting records, predict its judged records."""
    preds: dict[int, np.ndarray] = {}
    fits = []
    sse, n = 0.0, 0
    for fold in folds:
        f = best_shapes(store, combo, fold.fit, linear_base)
        fits.append(f)
        for p in fold.judged:
            pred = predict(store, f, p)
            preds[p.uid] = pred
            sse += float(np.sum((p.force - pred) ** 2))
            n += p.n
    return Judged(combo, fits, preds, sse, n)


def describe_shapes(f: Fit) -> list[str]:
    return [m.describe(s) for m, s in zip(f.combo.members, f.shapes, strict=True)]


def parameters(store: ColumnStore, f: Fit, linear_base: bool) -> dict[str, Any]:
    """The fitted model in physical terms: spring, damper and each effect, SI units."""
    out: dict[str, Any] = {}
    i = 0
    for block in f.blocks:
        n = store.columns_count(block)
        w = f.theta[i : i + n]
        i += n
        if block == SPRING:
            pre = "" if linear_base else "delta_"
            out[f"{pre}k_n_per_m"], out[f"{pre}c_ns_per_m"] = float(w[0]), float(w[1])
        elif block == DAMPER:
            out["c_ns_per_m"] = float(w[0])
        else:
            member = next(m for m in f.combo.members if m.name == block[0])
            out[block[0]] = member.parameters(block[1], store.scales, w)
    for m, s in zip(f.combo.members, f.shapes, strict=True):
        if m.name not in out:
            out[m.name] = m.parameters(s, store.scales, np.zeros(0))
        if any(b[0] == m.name for b in f.nuisance):
            ws = list(f.nuisance_w.values())
            out[m.name].update(m.nuisance_parameters(s, store.scales, ws))
    return out
