"""Identifying the vector Bouc-Wen bushing (``boucwen.py``) from 3-axis records.

The force is linear in K, C and h once the hysteretic shape (d, beta, eta) is fixed, so the
search runs over those five numbers only (variable projection): for each trial shape, z is
run along every record from rest and K, C, h follow by least squares, one force row at a time
(row i: f_i ~ K_i q + C_i v + G_i (q_i q^2) + h_i z_i; G per row, so not constrained to derive
from one strain energy). The score is the sum over the axes of the free-run RMS
ratio (seed 000 eq. 8): the model has no force feedback, so the least-squares residual is its
free-run error. Search: a grid of 8 start shapes (the first always runs), then bounded Powell
(scipy). Deterministic: budgets are evaluations; ``time_limit_s`` only seconds them (a stop by
the clock is reported).
A row whose best h is negative (a hysteresis that would give energy) is refitted with h = 0.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv.identify.options import option
from bushenv.models.base import velocity_of
from bushenv.planar.base import PlanarModelError
from bushenv.planar.boucwen import PlanarBoucWen

SEARCH_ETA = (1.0, 6.0)
SEARCH_BETA = (0.5, 3.0)
SEARCH_D_SHARE = (0.01, 2.0)  # yield deflection searched, share of each axis's peak
START_D_SHARE = (0.05, 0.1, 0.2, 0.4)  # start yield deflections, share of each axis's peak


@dataclass(frozen=True)
class PlanarBoucWenOptions:
    """Options of the vector Bouc-Wen identification; each is a flag of ``bushenv fit``."""

    evaluations: int = option(200, "shape evaluations of the bounded Powell search (after 8)")
    yield_surface: str = option(
        "vector",
        "vector: one yield surface on the deflection vector; axis: each coordinate its own",
        choices=("vector", "axis"),
    )
    time_limit_s: float = option(
        120.0,
        "wall-time limit of the search, s (0: none); evaluations decide below it, so a seed "
        "reproduces the parameters; a stop by the clock is reported on the card",
    )

    def check(self) -> None:
        if self.evaluations < 1 or self.time_limit_s < 0:
            raise PlanarModelError(
                f"evaluations must be >= 1 and time_limit_s >= 0, got {self.evaluations}, "
                f"{self.time_limit_s}"
            )


class _OutOfTime(Exception):
    pass


def fit_planar_boucwen(
    histories: Sequence[tuple[np.ndarray, np.ndarray]],
    dt: float,
    options: PlanarBoucWenOptions | None = None,
    say: Callable[[str], None] | None = None,
) -> tuple[PlanarBoucWen, dict[str, Any]]:
    """Identify from records ``[(q (T, 3), f (T, 3)), ...]`` (each run from rest).

    Returns the model and a summary: evaluations, score (sum of the three RMS ratios on the
    training records), whether the clock stopped the search.
    """
    opt = options or PlanarBoucWenOptions()
    qs = [np.asarray(q, dtype=np.float64) for q, _ in histories]
    fs = [np.asarray(f, dtype=np.float64) for _, f in histories]
    for q, f in zip(qs, fs, strict=True):
        if q.ndim != 2 or q.shape[1] != 3 or f.shape != q.shape or q.shape[0] < 20:
            raise PlanarModelError(
                f"fit_planar_boucwen: records must be (T, 3) q and f with T >= 20, got "
                f"{q.shape} and {f.shape}"
            )
    q_all = np.vstack(qs)
    v_all = np.vstack([velocity_of(q, dt) for q in qs])
    f_all = np.vstack(fs)
    peak = np.maximum(np.abs(q_all).max(axis=0), 1e-12)
    f_norm = np.maximum(np.sqrt(np.sum(f_all**2, axis=0)), 1e-300)
    lin = np.hstack([q_all, v_all])
    cubic = [q_all[:, i : i + 1] * q_all**2 for i in range(3)]  # row i: q_i q_j^2, j = 0..2
    col = np.maximum(np.abs(lin).max(axis=0), 1e-300)
    cub_col = [np.maximum(np.abs(c).max(axis=0), 1e-300) for c in cubic]
    lo = np.concatenate([np.log(peak * SEARCH_D_SHARE[0]), [SEARCH_BETA[0], SEARCH_ETA[0]]])
    hi = np.concatenate([np.log(peak * SEARCH_D_SHARE[1]), [SEARCH_BETA[1], SEARCH_ETA[1]]])
    t0 = time.perf_counter()
    best: dict[str, Any] = {"score": np.inf}
    count = [0]

    def solve(p: np.ndarray) -> tuple[float, np.ndarray]:
        d, beta, eta = np.exp(p[:3]), float(p[3]), float(p[4])
        unit = PlanarBoucWen(np.zeros((3, 3)), np.zeros((3, 3)), np.ones(3), d,
                             (beta, 1.0 - beta, eta), yield_surface=opt.yield_surface,
                             dt=dt)  # fmt: skip
        z = np.vstack([unit.hysteretic_state(q) for q in qs])
        coef = np.zeros((3, 10))  # row i: K_i (3), C_i (3), G_i (3), h_i
        score = 0.0
        for i in range(3):
            a = np.hstack([lin / col, cubic[i] / cub_col[i], z[:, i : i + 1]])
            c, *_ = np.linalg.lstsq(a, f_all[:, i], rcond=None)
            if c[9] < 0:  # a hysteresis giving energy: refit without it
                c = np.append(np.linalg.lstsq(a[:, :9], f_all[:, i], rcond=None)[0], 0.0)
            coef[i] = np.concatenate([c[:6] / col, c[6:9] / cub_col[i], c[9:]])
            score += float(np.linalg.norm(a @ c - f_all[:, i]) / f_norm[i])
        return score, coef

    def score_of(p: np.ndarray) -> float:
        if count[0] and opt.time_limit_s and time.perf_counter() - t0 > opt.time_limit_s:
            raise _OutOfTime
        p = np.clip(p, lo, hi)
        s, coef = solve(p)
        count[0] += 1
        if s < best["score"]:
            best.update(score=s, p=p.copy(), coef=coef)
        if say and count[0] % 50 == 0:
            spent = time.perf_counter() - t0
            left = spent / count[0] * max(opt.evaluations + 8 - count[0], 0)
            say(f"boucwen: {count[0]} evaluations, score {best['score']:.4f}, ~{left:.0f} s left")
        return s

    stopped = False
    try:
        for share in START_D_SHARE:
            for eta in (1.0, 2.0):
                score_of(np.concatenate([np.log(peak * share), [0.5, eta]]))
        from scipy.optimize import minimize

        minimize(
            score_of,
            best["p"],
            method="Powell",
            bounds=list(zip(lo, hi, strict=True)),
            options={"maxfev": opt.evaluations, "xtol": 1e-4, "ftol": 1e-7},
        )
    except _OutOfTime:
        stopped = True
    p, coef = best["p"], best["coef"]
    model = PlanarBoucWen(coef[:, :3], coef[:, 3:6], coef[:, 9], np.exp(p[:3]),
                          (p[3], 1.0 - p[3], p[4]), coef[:, 6:9], opt.yield_surface,
                          dt=dt)  # fmt: skip
    info = {
        "evaluations": count[0],
        "score_sum_rms_ratio": best["score"],
        "time_limited": stopped,
        "wall_time_s": time.perf_counter() - t0,
    }
    return model, info
