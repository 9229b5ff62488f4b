"""Identifying the vector Bouc-Wen bushing (``boucwen.py``) from 3-axis records.

The force is linear in K, C and h once the hysteretic shape (d, beta, eta) is fixed, so the
search runs over those five numbers only (variable projection): for each trial shape, z is
run along every record from rest and K, C, h follow by least squares, one force row at a time
(row i: f_i ~ K_i q + C_i v + G_i (q_i q^2) + h_i z_i [+ R_i p]; G per row, so not constrained
to derive from one strain energy; p the relaxation branches' deflections of ``relaxation.py`` at
the time constants ``relaxation_times``, fixed, so R is linear too). The score is the sum over
the axes of the free-run RMS ratio (seed 000 eq. 8): the model has no force feedback, so the
least-squares residual is its free-run error. Search: a grid of 8 start shapes (the first
always runs), then bounded Powell (scipy). Deterministic: budgets are evaluations;
``time_limit_s`` only seconds them (a stop by the clock is reported).
A row whose best h is negative (a hysteresis that would give energy) is refitted with h = 0.
With a relaxation, its branches act on each coordinate alone (R_m diagonal) with R_m[i, i] >= 0
and h_i >= 0, by non-negative least squares: every branch stores and dissipates energy only,
so the element stays passive (a free 3x3 R_m, fitted and then made semidefinite, was measured
worse: docs/planar_fit_unseen.md).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv.identify.options import option
from bushenv.models.base import velocity_of
from bushenv.planar import relaxation
from bushenv.planar.base import PlanarModelError
from bushenv.planar.boucwen import PlanarBoucWen

SEARCH_ETA = (1.0, 6.0)
SEARCH_BETA = (0.5, 3.0)
SEARCH_D_SHARE = (0.01, 2.0)  # yield deflection searched, share of each axis's peak
START_D_SHARE = (0.05, 0.1, 0.2, 0.4)  # start yield deflections, share of each axis's peak
# two per decade over the band a vehicle bushing is driven in (corners 0.16 Hz to 50 Hz): fixed,
# not fitted, so the force stays linear in every gain
RELAXATION_TIMES = "0.003,0.01,0.03,0.1,0.3,1"


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

    relaxation_times: str = option(
        RELAXATION_TIMES,
        "time constants of the relaxation branches (Prony series, one per coordinate each, "
        "gains >= 0), s, comma-separated; '' for none",
    )

    def taus(self) -> np.ndarray:
        """(M,) the relaxation time constants, s."""
        text = self.relaxation_times.strip()
        try:
            taus = np.array([float(x) for x in text.split(",")]) if text else np.zeros(0)
        except ValueError:
            raise PlanarModelError(
                f"relaxation_times: {self.relaxation_times!r} is not a comma-separated list of "
                "seconds (e.g. 0.01,0.1,1)"
            ) from None
        if np.any(~np.isfinite(taus)) or np.any(taus <= 0) or len(set(taus)) != len(taus):
            raise PlanarModelError(
                f"relaxation_times: {self.relaxation_times!r}: each must be a distinct time "
                "constant > 0 s"
            )
        return taus

    def check(self) -> None:
        self.taus()
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
    taus = opt.taus()
    p_all = np.vstack([relaxation.branch_deflections(q, dt, taus) for q in qs])  # (N, 3 M)
    peak = np.maximum(np.abs(q_all).max(axis=0), 1e-12)
    f_norm = np.maximum(np.sqrt(np.sum(f_all**2, axis=0)), 1e-300)
    lin = np.hstack([q_all, v_all])
    cubic = [q_all[:, i : i + 1] * q_all**2 for i in range(3)]  # row i: q_i q_j^2, j = 0..2
    col = np.maximum(np.abs(lin).max(axis=0), 1e-300)
    cub_col = [np.maximum(np.abs(c).max(axis=0), 1e-300) for c in cubic]
    p_col = np.maximum(np.abs(p_all).max(axis=0), 1e-300)
    n_p = p_all.shape[1]
    lo = np.concatenate([np.log(peak * SEARCH_D_SHARE[0]), [SEARCH_BETA[0], SEARCH_ETA[0]]])
    hi = np.concatenate([np.log(peak * SEARCH_D_SHARE[1]), [SEARCH_BETA[1], SEARCH_ETA[1]]])
    t0 = time.perf_counter()
    best: dict[str, Any] = {"score": np.inf}
    count = [0]

    def hysteretic(p: np.ndarray) -> np.ndarray:
        d, beta, eta = np.exp(p[:3]), float(p[3]), float(p[4])
        unit = PlanarBoucWen(np.zeros((3, 3)), np.zeros((3, 3)), np.ones(3), d,
                             (beta, 1.0 - beta, eta), yield_surface=opt.yield_surface,
                             dt=dt)  # fmt: skip
        return np.vstack([unit.hysteretic_state(q) for q in qs])

    def solve(p: np.ndarray) -> tuple[float, np.ndarray]:
        """Score and coefficients, row i: K_i (3), C_i (3), G_i (3), R_i (3 M), h_i."""
        z = hysteretic(p)
        coef = np.zeros((3, 10 + n_p))
        score = 0.0
        for i in range(3):
            a = np.hstack([lin / col, cubic[i] / cub_col[i], z[:, i : i + 1]])
            if n_p:  # the branches on coordinate i, R_m[i, i] >= 0, and h_i >= 0
                own = p_all[:, i::3] / p_col[i::3]
                c, r = _bounded_lstsq(a[:, :9], np.hstack([own, a[:, 9:]]), f_all[:, i])
                fitted = a[:, :9] @ c + np.hstack([own, a[:, 9:]]) @ r
                rows = np.zeros(n_p)
                rows[i::3] = r[:-1] / p_col[i::3]
                coef[i] = np.concatenate([c[:6] / col, c[6:9] / cub_col[i], rows, r[-1:]])
            else:
                c, *_ = np.linalg.lstsq(a, f_all[:, i], rcond=None)
                if c[9] < 0:  # a hysteresis giving energy: refit without it
                    c = np.append(np.linalg.lstsq(a[:, :9], f_all[:, i], rcond=None)[0], 0.0)
                fitted = a @ c
                coef[i] = np.concatenate([c[:6] / col, c[6:9] / cub_col[i], c[9:]])
            score += float(np.linalg.norm(fitted - f_all[:, i]) / f_norm[i])
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
    gain = coef[:, 9:-1].reshape(3, len(taus), 3).transpose(1, 0, 2)  # R_m[i, j]: 3 m + j
    model = PlanarBoucWen(coef[:, :3], coef[:, 3:6], coef[:, -1], np.exp(p[:3]),
                          (p[3], 1.0 - p[3], p[4]), coef[:, 6:9], opt.yield_surface,
                          dt=dt, relax_tau=taus, relax_gain=gain)  # fmt: skip
    info = {
        "evaluations": count[0],
        "score_sum_rms_ratio": best["score"],
        "time_limited": stopped,
        "wall_time_s": time.perf_counter() - t0,
    }
    return model, info


def _bounded_lstsq(free: np.ndarray, held: np.ndarray, y: np.ndarray):
    """min |free x + held r - y| with r >= 0: ``free`` projected out (QR), the non-negative
    least squares on what is left (scipy ``nnls``), then x given r. Returns (x, r)."""
    from scipy.optimize import nnls

    q, _ = np.linalg.qr(free)
    r, _ = nnls(held - q @ (q.T @ held), y - q @ (q.T @ y))
    x, *_ = np.linalg.lstsq(free, y - held @ r, rcond=None)
    return x, r
