"""Identify a baseline on TRAIN, augment it with candidate effects, judge on TESTs.

``diagnose(train, tests, baseline="linear")`` is the library core behind ``bushenv diagnose``
(``report.py`` only writes files). Records are any objects with ``.time``, ``.displacement``,
``.force`` (``(T,)`` arrays, s, m, N) and ``.dt`` (s), such as ``bushenv.records.Record``.

How an augmented model is fitted
--------------------------------
- ``linear`` baseline: ``F = k x + c v + sum(effect columns * weights)``, all weights (k and c
  included) by bounded linear least squares on TRAIN: the baseline's own parameters are
  re-identified together with the effect, as a bench engineer would refit.
- any other baseline ``b`` (``boucwen``, ``hybrid``, ``nn`` from ``bushenv.identify``):
  ``F = b + dk x + dc v + sum(effect columns * weights)``: the baseline kept as identified, plus
  a spring/damper correction (a baseline identified without the effect has absorbed part of
  it into its stiffness and damping).
- ``delay`` shifts the whole predicted force by ``d`` seconds (``F(t - d)``).

Shape settings (tau grids, delays, heating time constants) are chosen by TRAIN error; every
gap number in the result is measured on the TESTs only (all TEST records concatenated):
``gap = bushenv.metrics.rms_ratio(measured, predicted)`` (seed 000 eq. 8) and
``shrink = 1 - gap_after / gap_before``.

The null augmentation is the spring/damper part alone: for the linear baseline it is the
baseline itself; for the others, ``b + dk x + dc v``, whose gap is ``gap_null``. The rule
judges candidates against the null, so a correction every candidate gets is not credited to
any of them.

Rule for naming an effect (``none`` otherwise)
----------------------------------------------
The best single effect (lowest TEST gap) is named when
1. it shrinks the null's gap by at least ``SHRINK_MIN`` (5 %: a 10 % cut in held-out error
   energy): ``1 - gap_after / gap_null >= 0.05``, and
2. its held-out cut in mean squared error exceeds the most that fitting ``p`` extra weights to
   noise could explain: ``MSE_null - MSE_after > NOISE_MARGIN * p * sigma2 / N_train``, with
   ``sigma2`` the held-out MSE that remains (an upper bound on the noise variance).
When the named single ``A`` leaves more than ``PAIR_TRY_IF_LEFT`` (10 %) of the null's gap,
each of the two best singles is paired with every other effect (fitted jointly, shapes
searched jointly); the best pair replaces ``A`` when it closes at least ``PAIR_GAIN_MIN``
(25 %) of the gap that ``A`` leaves and passes rule 2 with its own ``p``. The member that is
the better single comes first in the pair's name.

``top_two``: the named pair's members; for a named single ``A``, ``A`` and the effect that
closes most of the gap when fitted together with ``A`` (``A``'s pairs are always fitted for
this ranking, even when none may be named); for ``none``, the two best singles.

Rates: candidate columns are continuous-time, and the linear baseline is too, so a TEST at
another sample rate than TRAIN is handled (columns are recomputed at the TEST's dt). Other
baselines are discrete-time models identified at TRAIN's rate; a TEST at another rate is
refused with ``DiagnoseError`` naming both rates.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from itertools import count
from typing import Any

import numpy as np
from scipy import linalg, signal
from scipy.optimize import lsq_linear, minimize_scalar

from bushenv.diagnose import regimes
from bushenv.diagnose.candidates import (
    EFFECTS,
    STENCILS,
    Scales,
    Signals,
    get_candidate,
    shift_columns,
)
from bushenv.metrics import rms_ratio
from bushenv.models.base import DT_TOLERANCE

BASELINES = ("linear", "boucwen", "hybrid", "nn")
SHRINK_MIN = 0.05
NOISE_MARGIN = 2.0
PAIR_GAIN_MIN = 0.25
PAIR_TRY_IF_LEFT = 0.10  # try pairs when the best single leaves more than this fraction of the gap
PAIR_LEADS = 2  # pairs hold at least one of the PAIR_LEADS best singles
MIN_SAMPLES = 64

Progress = Callable[[str], None]
_UIDS = count()


class DiagnoseError(ValueError):
    """The records cannot be diagnosed as given; the message names the record and the reason."""


@dataclass
class Prepared:
    """One record ready for fitting: signals, measured force, baseline force ``b0``."""

    name: str
    time: np.ndarray
    signals: Signals
    force: np.ndarray
    b0: np.ndarray  # simulated non-linear baseline; zeros for the linear baseline
    fit_filter: Any = None  # TRAIN only: low-pass applied to both sides of the regression
    uid: int = field(default_factory=lambda: next(_UIDS))

    @property
    def dt(self) -> float:
        return self.signals.dt


@dataclass
class Augmentation:
    """Effects with chosen shapes and fitted weights (the baseline's own k, c for linear)."""

    effects: tuple[str, ...]
    shapes: tuple
    linear_base: bool
    theta: np.ndarray
    n_extra: int  # weights (and shape settings) added to the baseline

    @property
    def label(self) -> str:
        return "+".join(self.effects) if self.effects else "none"

    @property
    def delay_s(self) -> float:
        return sum(
            get_candidate(e).delay_s(s) for e, s in zip(self.effects, self.shapes, strict=True)
        )


class ColumnCache:
    """Effect columns per (record, effect, shape): the grids reuse them many times."""

    def __init__(self, scales: Scales) -> None:
        self.scales = scales
        self._store: dict[tuple, np.ndarray] = {}

    def get(self, prep: Prepared, effect: str, shape) -> np.ndarray:
        key = (prep.uid, effect, shape)
        if key not in self._store:
            self._store[key] = get_candidate(effect).columns(prep.signals, shape, self.scales)
        return self._store[key]

    def clear(self) -> None:
        self._store.clear()


def _design(
    prep: Prepared, effects: Sequence[str], shapes: Sequence, linear_base: bool, cache: ColumnCache
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Regressors A (T, p), fixed offset (T,), lower bounds (p,) for one record, unshifted.

    A delay d is not applied here: the prediction is ``shift(offset + A w, d)``, and the fit
    advances the measured force instead (``f(t + d) = offset(t) + A(t) w``), which shifts one
    column instead of all of them.
    """
    cols = []
    lower = []
    # a spring and a damper always: the linear baseline's own k, c, or a correction of k, c to
    # a fixed nonlinear baseline (identified without the effect, its k and c absorbed some of it)
    cols.append(np.stack([prep.signals.x, prep.signals.v], axis=1))
    lower.append(np.full(2, -np.inf))
    for e, s in zip(effects, shapes, strict=True):
        cand = get_candidate(e)
        c = cache.get(prep, e, s)
        if c.shape[1]:
            cols.append(c)
            lower.append(cand.lower(s, cache.scales))
    A = np.concatenate(cols, axis=1) if cols else np.zeros((prep.force.size, 0))
    offset = prep.b0
    lo = np.concatenate(lower) if lower else np.zeros(0)
    return A, offset, lo


def _bounded_lstsq(A: np.ndarray, y: np.ndarray, lower: np.ndarray) -> np.ndarray:
    """min |A w - y| subject to w >= lower, on column-scaled A (normal equations, tiny ridge)."""
    p = A.shape[1]
    if p == 0:
        return np.zeros(0)
    scale = np.sqrt(np.mean(A * A, axis=0))
    scale[scale == 0] = 1.0
    As = A / scale
    # normal equations on unit-RMS columns (p <= ~20): the Gram matrix costs one pass over T
    # where a QR costs p; a small ridge steadies near-collinear columns (a 100 s Maxwell branch
    # next to the spring) without biasing the fit
    n = A.shape[0]
    G = As.T @ As + 1e-8 * n * np.eye(p)
    R = linalg.cholesky(G, lower=False)
    Rr = R
    qyr = linalg.solve_triangular(R, As.T @ y, trans="T")
    lo = lower * scale  # lower bounds are 0 or -inf, so scaling keeps them
    if np.all(np.isneginf(lo)):
        w = np.linalg.lstsq(Rr, qyr, rcond=None)[0]
    else:
        w = lsq_linear(Rr, qyr, bounds=(lo, np.full(p, np.inf)), method="bvls").x
    return w / scale


def noise_band_edge(x: np.ndarray, dt: float) -> float | None:
    """Upper edge (Hz) of a displacement's signal band when a noise floor lies above it.

    The floor is the median Welch PSD over the top fifth of the band; the edge is the highest
    frequency 10 dB above it (+20 %). None when there is no clear floor (less than 40 dB below
    the peak) or the edge is within 80 % of Nyquist: then there is nothing to filter away.
    """
    fs = 1.0 / dt
    nper = int(min(x.size, 4096))
    if nper < 64:
        return None
    f, p = signal.welch(x, fs=fs, nperseg=nper)
    floor = float(np.median(p[f >= 0.8 * f[-1]]))
    if not (floor > 0 and floor < 1e-4 * p.max()):
        return None
    edge = 1.2 * float(f[np.nonzero(p >= 10.0 * floor)[0][-1]])
    return edge if edge < 0.8 * f[-1] else None


def _fit_filter(prep: Prepared):
    """Zero-phase low-pass (sos) applied to both sides of the TRAIN regression, or None.

    Noise on a measured displacement, twice differentiated, would bias the inertia weight
    toward zero (errors in variables); filtering the force and every column with the same
    linear filter keeps the regression exact in the signal band and drops the noise above it.
    """
    edge = noise_band_edge(prep.signals.x, prep.dt)
    if edge is None:
        return None
    return signal.butter(4, edge, fs=1.0 / prep.dt, output="sos")


def fit_augmentation(
    effects: Sequence[str],
    shapes: Sequence,
    train: Sequence[Prepared],
    linear_base: bool,
    cache: ColumnCache,
) -> tuple[Augmentation, float]:
    """Weights by bounded least squares on TRAIN; returns the model and its TRAIN MSE."""
    As, ys, lo = [], [], None
    for prep in train:
        A, off, lo = _design(prep, effects, shapes, linear_base, cache)
        delay = sum(get_candidate(e).delay_s(s) for e, s in zip(effects, shapes, strict=True))
        y = shift_columns(prep.force, -delay, prep.dt) - off
        if prep.fit_filter is not None:
            A = signal.sosfiltfilt(prep.fit_filter, A, axis=0) if A.shape[1] else A
            y = signal.sosfiltfilt(prep.fit_filter, y)
        As.append(A)
        ys.append(y)
    A = np.concatenate(As)
    y = np.concatenate(ys)
    theta = _bounded_lstsq(A, y, lo)
    mse = float(np.mean((y - A @ theta) ** 2))
    n_extra = A.shape[1] - 2
    n_extra += sum(1 for e, s in zip(effects, shapes, strict=True) if s is not None)
    aug = Augmentation(tuple(effects), tuple(shapes), linear_base, theta, n_extra)
    return aug, mse


def predict(aug: Augmentation, prep: Prepared, cache: ColumnCache) -> np.ndarray:
    A, off, _ = _design(prep, aug.effects, aug.shapes, aug.linear_base, cache)
    return shift_columns(off + A @ aug.theta, aug.delay_s, prep.dt)


def best_shapes(
    effects: Sequence[str], train: Sequence[Prepared], linear_base: bool, cache: ColumnCache
) -> tuple[Augmentation, float]:
    """Search the product of the effects' shape grids by TRAIN error."""
    grids = [get_candidate(e).shapes(cache.scales) for e in effects]
    best: tuple[Augmentation, float] | None = None
    for combo in _product(grids):
        aug, mse = fit_augmentation(effects, combo, train, linear_base, cache)
        if best is None or mse < best[1]:
            best = (aug, mse)
    assert best is not None
    # a continuous shape (the delay) is refined between its grid neighbours by TRAIN error
    for i, e in enumerate(effects):
        grid = grids[i]
        if not get_candidate(e).continuous_shape or len(grid) < 3:
            continue
        k = grid.index(best[0].shapes[i])
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]

        def train_mse(log_d: float, i: int = i, base: tuple = best[0].shapes) -> float:
            combo = list(base)
            combo[i] = float(np.exp(log_d))
            return fit_augmentation(effects, combo, train, linear_base, cache)[1]

        res = minimize_scalar(
            train_mse, bounds=(np.log(lo), np.log(hi)), method="bounded", options={"xatol": 0.01}
        )
        if res.fun < best[1]:
            combo = list(best[0].shapes)
            combo[i] = float(np.exp(res.x))
            best = fit_augmentation(effects, combo, train, linear_base, cache)
            # the other effects' grid choices were made at a grid delay: choose them again
            for j in range(len(effects)):
                if j == i or len(grids[j]) < 2:
                    continue
                for shape in grids[j]:
                    combo = list(best[0].shapes)
                    combo[j] = shape
                    trial = fit_augmentation(effects, combo, train, linear_base, cache)
                    if trial[1] < best[1]:
                        best = trial
    return best


def _product(grids: list[list]) -> list[tuple]:
    out: list[tuple] = [()]
    for g in grids:
        out = [o + (s,) for o in out for s in g]
    return out


# ----- baselines -------------------------------------------------------------------------
def _fit_nonlinear_baseline(name: str, train_rec: Any, seed: int):
    try:
        from bushenv.identify import fit_model  # the baselines' identification dispatcher
    except ImportError:
        raise DiagnoseError(
            f"baseline {name!r} needs bushenv.identify.fit_model, which is not available in "
            "this checkout; use --baseline linear"
        ) from None
    return fit_model(
        name,
        np.asarray(train_rec.displacement, dtype=np.float64),
        np.asarray(train_rec.force, dtype=np.float64),
        float(train_rec.dt),
        seed,
    )


def _check_record(rec: Any, label: str) -> None:
    for attr in ("time", "displacement", "force", "dt"):
        if not hasattr(rec, attr):
            raise DiagnoseError(f"{label}: not a record (no .{attr})")
    n = np.asarray(rec.displacement).size
    if n < MIN_SAMPLES:
        raise DiagnoseError(f"{label}: {n} samples; the diagnosis needs at least {MIN_SAMPLES}")
    for attr in ("displacement", "force"):
        a = np.asarray(getattr(rec, attr), dtype=np.float64)
        if a.shape != (n,):
            raise DiagnoseError(f"{label}: {attr} has shape {a.shape}, expected ({n},)")
        if not np.all(np.isfinite(a)):
            raise DiagnoseError(f"{label}: {attr} holds NaN or inf")
    if not (np.isfinite(rec.dt) and rec.dt > 0):
        raise DiagnoseError(f"{label}: sample time {rec.dt!r} is not a positive number")
    if np.sqrt(np.mean(np.asarray(rec.force, dtype=np.float64) ** 2)) == 0:
        raise DiagnoseError(f"{label}: force is zero throughout; nothing to diagnose")
    if np.ptp(np.asarray(rec.displacement, dtype=np.float64)) == 0:
        raise DiagnoseError(f"{label}: displacement is constant; nothing identifies a baseline")


def _record_name(rec: Any, default: str) -> str:
    path = getattr(rec, "path", None) or getattr(rec, "source", None)
    if path:
        from pathlib import Path

        return Path(str(path)).stem
    return getattr(rec, "name", None) or default


# ----- the diagnosis ---------------------------------------------------------------------
def diagnose(
    train: Any,
    tests: Sequence[Any],
    baseline: str = "linear",
    progress: Progress | None = None,
    seed: int = 0,
    test_names: Sequence[str] | None = None,
) -> dict[str, Any]:
    """Where the held-out gap lies, which candidate effect closes it, and by how much.

    Returns a JSON-ready dict (see docs/diagnose.md) plus ``"predictions"``: one dict per TEST
    record with ``name`` and (T,) arrays ``time``, ``force_measured``, ``force_baseline``,
    ``force_augmented`` (arrays are not JSON; ``report.py`` writes them as CSV).
    """
    say = progress or (lambda msg: None)
    if baseline not in BASELINES:
        raise DiagnoseError(f"unknown baseline {baseline!r}; known: {list(BASELINES)}")
    if not tests:
        raise DiagnoseError("no TEST record given; the gap is judged on held-out records only")
    _check_record(train, "TRAIN")
    names = list(test_names) if test_names is not None else []
    for i, rec in enumerate(tests):
        if i >= len(names):
            names.append(_record_name(rec, f"test{i + 1}"))
        _check_record(rec, f"TEST {names[i]}")
    if len(set(names)) != len(names):
        raise DiagnoseError(f"TEST records need distinct names (file stems), got {names}")
    train_dt = float(train.dt)
    linear_base = baseline == "linear"
    if not linear_base:
        for n, rec in zip(names, tests, strict=True):
            if abs(float(rec.dt) - train_dt) > DT_TOLERANCE * train_dt * 1e3:
                raise DiagnoseError(
                    f"TEST {n}: sampled at {1 / rec.dt:.6g} Hz but TRAIN at {1 / train_dt:.6g} "
                    f"Hz; baseline {baseline!r} is a discrete-time model identified at the "
                    "TRAIN rate. Resample the record or use --baseline linear (continuous-time)."
                )

    say(f"identifying baseline {baseline!r} on TRAIN ({np.size(train.force)} samples)")
    x_tr = np.asarray(train.displacement, dtype=np.float64)
    scales = Scales(
        sigma_x=float(np.std(x_tr)) or float(np.max(np.abs(x_tr))),
        duration_s=float(x_tr.size * train_dt),
        dt=train_dt,
    )
    cache = ColumnCache(scales)
    model = _fit_nonlinear_baseline(baseline, train, seed) if not linear_base else None

    stencil = "central"

    def prepare(rec: Any, name: str) -> Prepared:
        x = np.asarray(rec.displacement, dtype=np.float64)
        sig = Signals(x, float(rec.dt), stencil)
        b0 = np.zeros_like(x) if model is None else _simulate(model, x)
        return Prepared(
            name, np.asarray(rec.time, dtype=np.float64), sig, np.asarray(rec.force, float), b0
        )

    # the derivative stencil: whichever fits TRAIN better with spring, damper and mass
    tried = {}
    for stencil in STENCILS:
        prep = prepare(train, "train")
        prep.fit_filter = _fit_filter(prep)
        tried[stencil] = (fit_augmentation(("inertia",), (None,), [prep], True, cache)[1], prep)
        cache.clear()
    stencil = min(tried, key=lambda k: tried[k][0])
    tr = [tried[stencil][1]]
    say(f"derivatives by the {stencil} stencil (better TRAIN fit)")
    if tr[0].fit_filter is not None:
        edge = noise_band_edge(tr[0].signals.x, tr[0].dt)
        say(f"TRAIN displacement has a noise floor above {edge:.4g} Hz: fitting below it")
    te = [prepare(rec, n) for rec, n in zip(tests, names, strict=True)]
    f_test = np.concatenate([p.force for p in te])
    n_train = tr[0].force.size

    # the null augmentation: k, c only. For the linear baseline it is the baseline itself; for
    # the others, the baseline plus a spring/damper correction, which every candidate also
    # gets, so the rule judges candidates against it
    base_aug, _ = fit_augmentation((), (), tr, linear_base, cache)
    null_pred = [predict(base_aug, p, cache) for p in te]
    base_pred = null_pred if linear_base else [p.b0 for p in te]
    base_all = np.concatenate(base_pred)
    gap_before = rms_ratio(f_test, base_all)
    null_all = np.concatenate(null_pred)
    gap_null = rms_ratio(f_test, null_all)
    mse_null = float(np.mean((f_test - null_all) ** 2))
    say(f"baseline gap on TESTs: {100 * gap_before:.2f} % (RMS ratio)")

    say("where: splitting the gap by regime, frequency and time")
    where = regimes.where_analysis(
        [p.signals.x for p in te],
        [p.force - b for p, b in zip(te, base_pred, strict=True)],
        [p.dt for p in te],
    )

    def judge(aug: Augmentation, train_mse: float) -> dict[str, Any]:
        pred = np.concatenate([predict(aug, p, cache) for p in te])
        gap_after = rms_ratio(f_test, pred)
        mse_after = float(np.mean((f_test - pred) ** 2))
        margin = NOISE_MARGIN * aug.n_extra * mse_after / n_train
        return {
            "effect": aug.label,
            "gap_before": gap_before,
            "gap_after": gap_after,
            "shrink": 1.0 - gap_after / gap_before if gap_before > 0 else 0.0,
            "shrink_vs_null": 1.0 - gap_after / gap_null if gap_null > 0 else 0.0,
            "n_extra_parameters": aug.n_extra,
            "shape": [
                get_candidate(e).describe(s) for e, s in zip(aug.effects, aug.shapes, strict=True)
            ],
            "gap_train": float(np.sqrt(train_mse / np.mean(tr[0].force ** 2))),
            "beats_noise_margin": bool(mse_null - mse_after > margin),
            "_aug": aug,
        }

    singles = []
    for i, effect in enumerate(EFFECTS):
        say(f"which: candidate {i + 1}/{len(EFFECTS)} {effect}")
        aug, mse = best_shapes((effect,), tr, linear_base, cache)
        singles.append(judge(aug, mse))
    singles.sort(key=lambda r: r["gap_after"])
    for r in singles:
        r["passes"] = bool(r["shrink_vs_null"] >= SHRINK_MIN and r["beats_noise_margin"])

    best = singles[0]
    named = best if best["passes"] else None
    pairs: list[dict[str, Any]] = []
    if named is not None:
        order = [r["effect"] for r in singles]
        # pairs that may be named: one of the PAIR_LEADS best singles with any other effect,
        # tried when the best single leaves a large part of the gap; the best single's pairs
        # are always fitted, to rank the runner-up by what it adds to the first effect
        leads = PAIR_LEADS if best["gap_after"] > PAIR_TRY_IF_LEFT * gap_null else 1
        tried_pairs = set()
        for first in order[:leads]:
            for other in order:
                key = frozenset((first, other))
                if other == first or key in tried_pairs:
                    continue
                tried_pairs.add(key)
                a, b = sorted(key, key=order.index)  # the better single first
                say(f"which: pair {a}+{b}")
                aug, mse = best_shapes((a, b), tr, linear_base, cache)
                pairs.append(judge(aug, mse))
        pairs.sort(key=lambda r: r["gap_after"])
        for r in pairs:
            r["passes"] = bool(
                leads > 1
                and r["gap_after"] <= (1.0 - PAIR_GAIN_MIN) * best["gap_after"]
                and r["beats_noise_margin"]
            )
        winners = [r for r in pairs if r["passes"]]
        if winners:
            named = winners[0]

    if named is None:
        effect = "none"
        aug_final = base_aug
        top_two = [r["effect"] for r in singles[:2]]
    else:
        effect = named["effect"]
        aug_final = named["_aug"]
        if "+" in effect:
            top_two = effect.split("+")
        else:
            # runner-up: the effect that adds most to the named one (its best pair)
            with_best = [r for r in pairs if best["effect"] in r["effect"].split("+")]
            partner = [m for m in with_best[0]["effect"].split("+") if m != best["effect"]]
            top_two = [best["effect"], partner[0]]
    say(f"named effect: {effect}")
    notes = [
        f"TEST {p.name} is the TRAIN record itself: its gap is not held out."
        for p in te
        if p.force.size == n_train
        and np.array_equal(p.force, tr[0].force)
        and np.array_equal(p.signals.x, tr[0].signals.x)
    ]

    predictions = []
    for p, b in zip(te, base_pred, strict=True):
        predictions.append(
            {
                "name": p.name,
                "dt": p.dt,
                "displacement": p.signals.x,
                "time": p.time,
                "force_measured": p.force,
                "force_baseline": b,
                "force_augmented": b if effect == "none" else predict(aug_final, p, cache),
            }
        )
    aug_all = np.concatenate([q["force_augmented"] for q in predictions])
    if effect != "none":
        where_after = regimes.where_analysis(
            [p.signals.x for p in te],
            [p.force - q["force_augmented"] for p, q in zip(te, predictions, strict=True)],
            [p.dt for p in te],
        )
    else:
        where_after = where

    def clean(r: dict[str, Any]) -> dict[str, Any]:
        return {k: v for k, v in r.items() if not k.startswith("_")}

    return {
        "effect": effect,
        "top_two": top_two,
        "baseline": baseline,
        "gap_before": gap_before,
        "gap_null": gap_null,
        "gap_after": rms_ratio(f_test, aug_all),
        "shrink": 1.0 - rms_ratio(f_test, aug_all) / gap_before if gap_before > 0 else 0.0,
        "ranking": [clean(r) for r in singles],
        "pairs": [clean(r) for r in pairs],
        "rule": {
            "shrink_min": SHRINK_MIN,
            "noise_margin": NOISE_MARGIN,
            "pair_gain_min": PAIR_GAIN_MIN,
            "pair_try_if_left": PAIR_TRY_IF_LEFT,
            "text": RULE_TEXT,
        },
        "where": where,
        "where_after": where_after,
        "records": {
            "train": {"samples": int(n_train), "rate_hz": 1.0 / train_dt},
            "tests": [
                {"name": p.name, "samples": int(p.force.size), "rate_hz": 1.0 / p.dt} for p in te
            ],
        },
        "parameters": _parameters(aug_final, scales),
        "notes": notes,
        "derivative_stencil": stencil,
        "train_fit_band_hz": noise_band_edge(tr[0].signals.x, tr[0].dt),
        "predictions": predictions,
    }


RULE_TEXT = (
    f"The best single effect is named when it shrinks the held-out gap (of the baseline with "
    f"its spring and damper refitted) by at least "
    f"{100 * SHRINK_MIN:.0f} % and its cut in held-out mean squared error exceeds "
    f"{NOISE_MARGIN:g} x (extra parameters) x (remaining MSE) / (TRAIN samples), the most that "
    f"fitting noise could explain; otherwise 'none'. A pair replaces it when the best single "
    f"leaves more than {100 * PAIR_TRY_IF_LEFT:.0f} % of the gap and the pair closes at least "
    f"{100 * PAIR_GAIN_MIN:.0f} % of what the single leaves (and passes the noise margin); "
    f"pairs hold one of the {PAIR_LEADS} best singles and any other effect, fitted jointly."
)


def _simulate(model: Any, x: np.ndarray) -> np.ndarray:
    out = np.asarray(model.simulate(x), dtype=np.float64)
    if not np.all(np.isfinite(out)):
        raise DiagnoseError(f"baseline {model.name!r} diverged (NaN/inf) in free run")
    return out


def _parameters(aug: Augmentation, scales: Scales) -> dict[str, Any]:
    """The augmented model's weights in plain numbers, labelled by column."""
    labels: list[str] = []
    if aug.linear_base:
        labels += ["k_n_per_m", "c_ns_per_m"]
    else:
        labels += ["delta_k_n_per_m", "delta_c_ns_per_m"]
    for e, s in zip(aug.effects, aug.shapes, strict=True):
        cand = get_candidate(e)
        n = cand.columns_count(s, scales)
        labels += [f"{e}[{j}]" for j in range(n)]
    out: dict[str, Any] = {lab: float(w) for lab, w in zip(labels, aug.theta, strict=True)}
    if aug.delay_s:
        out["delay_s"] = aug.delay_s
    return out
