"""Identifying the vector Bouc-Wen bushing (``bushenv.models.boucwen.planar``) from 3-axis
records: the ``boucwen`` kind's identification over three coordinates (``fit_boucwen``), and
the ``hybrid-bw`` kind's backbone (``mimo.fit_hybrid_bw``). The one-axis Bouc-Wen (seed 002's
16 parameters) is identified by a global search instead (``global_search.py``).

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
worse: studies/2026-11-planar-fit-unseen). ``relaxation_selection="extrapolation"`` then drops the
shortest branches when that predicts the training records' largest deflections better
(``_select``; an option: measured to help on one bushing and hurt on another). The summary warns
of branches the records cannot tell from the static stiffness (``relaxation.inseparable``).
``relaxation_form="qlv"``: the branches relax the elastic force F_e,i = K_i q + G_i (q_i q^2)
(``relaxation.py``), so the force is bilinear in (K, G) and the weights r_m,i; per row, from
the constant form's fit (r = R_ii / K_ii), ``QLV_ROUNDS`` rounds of alternating least squares:
(K, C, G, h) given r, then (C, r >= 0, h >= 0) given K and G. Each step is the model's exact
least squares in its unknowns, so the residual never grows; a fixed count keeps it
deterministic.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from bushenv.identify.boucwen_options import VectorBoucWenOptions
from bushenv.identify.data import IdentificationError, TrainingSet
from bushenv.models.base import velocity_of
from bushenv.models.boucwen import relaxation
from bushenv.models.boucwen.planar import PlanarBoucWen
from bushenv.models.planar_base import COORDS, PlanarModelError
from bushenv.progress import Progress, ProgressSpec

SEARCH_ETA = (1.0, 6.0)
SEARCH_BETA = (0.5, 3.0)
SEARCH_D_SHARE = (0.01, 2.0)  # yield deflection searched, share of each axis's peak
START_D_SHARE = (0.05, 0.1, 0.2, 0.4)  # start yield deflections, share of each axis's peak
EXTRAPOLATION_SHARE = 0.1  # the largest deflections held out to choose the relaxation branches
SELECTION_TIE = 0.01  # scores closer than this (relative) are a tie: the fuller grid kept
MIN_SAMPLES = 20  # per record
QLV_ROUNDS = 3  # alternations of the quasi-linear form's least squares, per shape


class _OutOfTime(Exception):
    pass


class _Problem:
    """The training records' regressors, and the least squares of the force rows given a
    hysteretic shape and the relaxation branches kept (indices into ``taus``)."""

    def __init__(self, qs: list[np.ndarray], fs: list[np.ndarray], dt: float,
                 taus: np.ndarray, yield_surface: str, form: str = "constant") -> None:  # fmt: skip
        self.qs, self.dt, self.taus, self.surface, self.form = qs, dt, taus, yield_surface, form
        self.q = np.vstack(qs)
        self.f = np.vstack(fs)
        v = np.vstack([velocity_of(q, dt) for q in qs])
        self.p = np.vstack([relaxation.branch_deflections(q, dt, taus) for q in qs])  # (N, 3 M)
        self.peak = np.maximum(np.abs(self.q).max(axis=0), 1e-12)
        self.lin = np.hstack([self.q, v])
        self.cubic = [self.q[:, i : i + 1] * self.q**2 for i in range(3)]  # q_i q_j^2
        self.col = np.maximum(np.abs(self.lin).max(axis=0), 1e-300)
        self.cub_col = [np.maximum(np.abs(c).max(axis=0), 1e-300) for c in self.cubic]
        self.p_col = np.maximum(np.abs(self.p).max(axis=0), 1e-300)
        # the quasi-linear form's base columns of row i: q, v, q_i q^2, the branches' filtered
        # increments of q and of q_i q^2 (``_Columns``), and their QR on every row
        self.base: list[np.ndarray] = []
        self.base_scale: list[np.ndarray] = []
        self.base_qr: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        if form == "qlv":
            for i in range(3):
                parts = [relaxation.branch_deflections(q[:, i : i + 1] * q**2, dt, taus)
                         for q in qs]  # fmt: skip
                base = np.hstack([self.lin, self.cubic[i], self.p, np.vstack(parts)])
                scale = np.maximum(np.abs(base).max(axis=0), 1e-300)
                q0, r0 = np.linalg.qr(base / scale)
                self.base.append(base)
                self.base_scale.append(scale)
                self.base_qr.append((q0, r0, q0.T @ self.f[:, i]))

    def hysteretic(self, p: np.ndarray) -> np.ndarray:
        d, beta, eta = np.exp(p[:3]), float(p[3]), float(p[4])
        unit = PlanarBoucWen(np.zeros((3, 3)), np.zeros((3, 3)), np.ones(3), d,
                             (beta, 1.0 - beta, eta), yield_surface=self.surface,
                             dt=self.dt)  # fmt: skip
        return np.vstack([unit.hysteretic_state(q) for q in self.qs])

    def solve(
        self, z: np.ndarray, keep: np.ndarray, fit: Any = slice(None), judged: Any = None
    ) -> tuple[float, np.ndarray]:
        """Coefficients fitted on rows ``fit`` (row i: K_i (3), C_i (3), G_i (3), R_i (3 K),
        h_i for the K branches kept) and the sum over the axes of the RMS ratio on rows
        ``judged`` (default: the fitted ones)."""
        judged = fit if judged is None else judged
        if self.form == "qlv" and len(keep):
            return self.solve_qlv(z, keep, fit, judged)
        return self.solve_constant(z, keep, fit, judged)

    def solve_constant(
        self, z: np.ndarray, keep: np.ndarray, fit: Any = slice(None), judged: Any = None
    ) -> tuple[float, np.ndarray]:
        """``solve`` for the constant form (the branch columns hold R_m[i, i], N/m ...)."""
        judged = fit if judged is None else judged
        n_p = 3 * len(keep)
        coef = np.zeros((3, 10 + n_p))
        score = 0.0
        for i in range(3):
            a = np.hstack([self.lin / self.col, self.cubic[i] / self.cub_col[i], z[:, i : i + 1]])
            y = self.f[:, i]
            if n_p:  # the branches on coordinate i, R_m[i, i] >= 0, and h_i >= 0
                cols = 3 * keep + i
                held = np.hstack([self.p[:, cols] / self.p_col[cols], a[:, 9:]])
                c, r = _bounded_lstsq(a[fit, :9], held[fit], y[fit])
                error = a[judged, :9] @ c + held[judged] @ r - y[judged]
                rows = np.zeros(n_p)
                rows[i::3] = r[:-1] / self.p_col[cols]
                coef[i] = np.concatenate([c[:6] / self.col, c[6:9] / self.cub_col[i], rows,
                                          r[-1:]])  # fmt: skip
            else:
                c, *_ = np.linalg.lstsq(a[fit], y[fit], rcond=None)
                if c[9] < 0:  # a hysteresis giving energy: refit without it
                    c = np.append(np.linalg.lstsq(a[fit, :9], y[fit], rcond=None)[0], 0.0)
                error = a[judged] @ c - y[judged]
                coef[i] = np.concatenate([c[:6] / self.col, c[6:9] / self.cub_col[i], c[9:]])
            score += float(np.linalg.norm(error) / max(np.linalg.norm(y[judged]), 1e-300))
        return score, coef

    def solve_qlv(
        self, z: np.ndarray, keep: np.ndarray, fit: Any, judged: Any
    ) -> tuple[float, np.ndarray]:
        """``solve`` for the quasi-linear form: the constant form's fit, then ``QLV_ROUNDS``
        alternations; the branch columns of row i hold the weights r_m,i (dimensionless).
        Every design is a combination of row i's base columns (``base``), so each least
        squares runs on their triangular factor (as many rows as columns), not on the
        records."""
        n_m, n_k = len(self.taus), len(keep)
        coef = np.zeros((3, 10 + 3 * n_k))
        score = 0.0
        for i in range(3):
            a, y_hat = self.reduced(i, z[:, i], fit)
            col = _Columns(n_m, keep, a.shape[1])
            # the constant form: R_m[i, i] on the branch deflections of coordinate i
            x, rh = _solve_reduced(a, col.unit(col.q + col.v + col.c),
                                   col.unit([col.pq(m, i) for m in range(n_k)] + [col.z]),
                                   y_hat)  # fmt: skip
            k_i, g_i = x[:3], x[6:9]
            r = np.maximum(rh[:-1] / k_i[i], 0.0) if k_i[i] > 0 else np.zeros(n_k)
            for _ in range(QLV_ROUNDS):
                # (K, C, G, h) given r: the elastic columns carry their relaxation along
                free = np.column_stack(
                    [col.elastic(j, r, "q") for j in range(3)]
                    + [col.unit([c])[:, 0] for c in col.v]
                    + [col.elastic(j, r, "c") for j in range(3)]
                )
                x, hr = _solve_reduced(a, free, col.unit([col.z]), y_hat)
                k_i, g_i, h = x[:3], x[6:9], hr[0]
                # (C, r, h) given K and G: each branch's elastic-force column, r >= 0
                held = np.column_stack([col.branch(m, k_i, g_i) for m in range(n_k)]
                                       + [col.unit([col.z])[:, 0]])  # fmt: skip
                fixed = col.coefficients(k_i, np.zeros(3), g_i, np.zeros(n_k), 0.0)
                c_v, rh = _solve_reduced(a, col.unit(col.v), held, y_hat - a @ fixed)
                r, h = rh[:-1], rh[-1]
            beta = col.coefficients(k_i, c_v, g_i, r, h)
            rows = self.base[i][judged]
            error = rows @ beta[:-1] + z[judged, i] * h - self.f[judged, i]
            branches = np.zeros(3 * n_k)
            branches[i::3] = r
            coef[i] = np.concatenate([k_i, c_v, g_i, branches, [h]])
            score += float(np.linalg.norm(error) / max(np.linalg.norm(self.f[judged, i]), 1e-300))
        return score, coef

    def reduced(self, i: int, z: np.ndarray, fit: Any) -> tuple[np.ndarray, np.ndarray]:
        """(A, y_hat): row i's base columns and z on rows ``fit`` as Q A (Q orthonormal, A
        square), and y_hat = Q' f_i, so |B beta - f_i| = |A beta - y_hat| + a constant."""
        y = self.f[:, i]
        scale = self.base_scale[i]
        if isinstance(fit, slice) and fit == slice(None):
            q0, r0, qy = self.base_qr[i]
            zs = z / max(np.abs(z).max(), 1e-300)
            w = q0.T @ zs
            rest = zs - q0 @ w
            rho = np.linalg.norm(rest)
            e = rest / rho if rho > 0 else rest
            r = np.block([[r0, w[:, None]], [np.zeros((1, r0.shape[1])), np.array([[rho]])]])
            a = r * np.append(scale, max(np.abs(z).max(), 1e-300))[None, :]
            return a, np.append(qy, e @ y)
        full = np.column_stack([self.base[i][fit], z[fit]])
        s = np.maximum(np.abs(full).max(axis=0), 1e-300)
        q, r = np.linalg.qr(full / s)
        return r * s[None, :], q.T @ y[fit]

    def beyond(self) -> np.ndarray | None:
        """Rows whose deflection vector (each coordinate over its peak) is among the largest
        ``EXTRAPOLATION_SHARE``; None when the rest are too few to fit every column."""
        size = np.linalg.norm(self.q / self.peak, axis=1)
        rows = size > np.quantile(size, 1.0 - EXTRAPOLATION_SHARE)
        columns = 10 + len(self.taus)
        return rows if rows.any() and (~rows).sum() >= 20 * columns else None


def say_of(progress: ProgressSpec) -> Callable[[str], None] | None:
    """Progress lines as the searches here write them: to a callable given, on stderr (True),
    or none (False)."""
    if callable(progress):
        return progress
    return Progress(label="").say if progress else None


def fit_boucwen(
    data: TrainingSet,
    options: VectorBoucWenOptions,
    seed: int = 0,
    progress: ProgressSpec = True,
) -> PlanarBoucWen:
    """The ``boucwen`` identification of ``data``'s (T, 3) records (``fit_vector_boucwen``;
    deterministic, ``seed`` unused); its summary is ``model.training["info"]``."""
    for s in data.segments:
        if len(s) < MIN_SAMPLES:
            raise IdentificationError(
                f"{s.label}: {len(s)} samples; the boucwen identification needs at least "
                f"{MIN_SAMPLES} per record: give longer records"
            )
    model, info = fit_vector_boucwen(data.histories(), data.dt, options, say=say_of(progress))
    model.training = {"info": info}
    return model


def fit_vector_boucwen(
    histories: Sequence[tuple[np.ndarray, np.ndarray]],
    dt: float,
    options: VectorBoucWenOptions | None = None,
    say: Callable[[str], None] | None = None,
) -> tuple[PlanarBoucWen, dict[str, Any]]:
    """Identify from records ``[(q (T, 3), f (T, 3)), ...]`` (each run from rest).

    Returns the model and a summary: evaluations, score (sum of the three RMS ratios on the
    training records), whether the clock stopped the search, the relaxation branches kept.
    """
    opt = options or VectorBoucWenOptions()
    qs = [np.asarray(q, dtype=np.float64) for q, _ in histories]
    fs = [np.asarray(f, dtype=np.float64) for _, f in histories]
    for q, f in zip(qs, fs, strict=True):
        if q.ndim != 2 or q.shape[1] != 3 or f.shape != q.shape or q.shape[0] < MIN_SAMPLES:
            raise PlanarModelError(
                f"fit_vector_boucwen: records must be (T, 3) q and f with T >= {MIN_SAMPLES}, got "
                f"{q.shape} and {f.shape}"
            )
    taus = opt.taus()
    prob = _Problem(qs, fs, dt, taus, opt.yield_surface, opt.relaxation_form)
    lo = np.concatenate([np.log(prob.peak * SEARCH_D_SHARE[0]), [SEARCH_BETA[0], SEARCH_ETA[0]]])
    hi = np.concatenate([np.log(prob.peak * SEARCH_D_SHARE[1]), [SEARCH_BETA[1], SEARCH_ETA[1]]])
    t_start = time.perf_counter()
    count = [0]

    def search(keep: np.ndarray, starts: list[np.ndarray]) -> tuple[dict[str, Any], bool]:
        best: dict[str, Any] = {"score": np.inf}
        t0, first = time.perf_counter(), count[0]  # each search its own clock

        budget = opt.evaluations + len(starts)

        def score_of(p: np.ndarray) -> float:
            spent = time.perf_counter() - t0
            if count[0] > first and opt.time_limit_s and spent > opt.time_limit_s:
                raise _OutOfTime
            p = np.clip(p, lo, hi)
            s, coef = prob.solve(prob.hysteretic(p), keep)
            count[0] += 1
            if s < best["score"]:
                best.update(score=s, p=p.copy(), coef=coef)
            done = count[0] - first
            if say and done % 50 == 0:
                left = spent / done * max(budget - done, 0)
                score = best["score"]
                say(f"boucwen: {count[0]} evaluations, score {score:.4f}, ~{left:.0f} s left")
            return s

        try:
            for p in starts:
                score_of(p)
            from scipy.optimize import minimize

            minimize(
                score_of,
                best["p"],
                method="Powell",
                bounds=list(zip(lo, hi, strict=True)),
                options={"maxfev": opt.evaluations, "xtol": 1e-4, "ftol": 1e-7},
            )
        except _OutOfTime:
            return best, True
        return best, False

    every = np.argsort(taus)
    starts = [np.concatenate([np.log(prob.peak * share), [0.5, eta]])
              for share in START_D_SHARE for eta in (1.0, 2.0)]  # fmt: skip
    best, stopped = search(every, starts)
    keep, note = every, "every branch (no selection)"
    if len(taus) and opt.relaxation_selection == "extrapolation":
        keep, note = _select(prob, best["p"], every)
        if len(keep) < len(taus):
            if say:
                say(f"boucwen: relaxation: {note}; the shape searched again with them")
            best, again = search(keep, [best["p"], *starts])
            stopped = stopped or again
    p, coef = best["p"], best["coef"]
    kept = taus[keep]
    gain = coef[:, 9:-1].reshape(3, len(kept), 3).transpose(1, 0, 2)  # R_m[i, j]: 3 m + j
    model = PlanarBoucWen(coef[:, :3], coef[:, 3:6], coef[:, -1], np.exp(p[:3]),
                          (p[3], 1.0 - p[3], p[4]), coef[:, 6:9], opt.yield_surface,
                          dt=dt, relax_tau=kept, relax_gain=gain,
                          relaxation_form=opt.relaxation_form)  # fmt: skip
    info = {
        "evaluations": count[0],
        "score_sum_rms_ratio": best["score"],
        "time_limited": stopped,
        "wall_time_s": time.perf_counter() - t_start,
    }
    if len(taus):
        info["relaxation"] = note
    if len(kept):
        cols = (3 * keep[:, None] + np.arange(3)).ravel()
        lost = relaxation.inseparable(prob.q, prob.lin[:, 3:], prob.p[:, cols], kept)
        if any(lost):
            info["relaxation warning"] = _not_identified(lost)
    return model, info


def _not_identified(lost: list[list[float]]) -> str:
    """The card's warning for branches the records cannot tell from the static stiffness."""
    shown = "; ".join(
        f"{c} {', '.join(f'{t:g}' for t in taus)} s"
        for c, taus in zip(COORDS, lost, strict=True)
        if taus
    )
    slowest = max(t for taus in lost for t in taus)
    return (
        f"the records hold too little motion slower than these branches to tell them from the "
        f"static stiffness ({shown}; variance inflation >= {relaxation.SEPARABLE_INFLATION:g}): "
        f"the force under a held deflection is not identified (a branch of tau s needs motion "
        f"below 1/(2 pi tau), {1 / (2 * np.pi * slowest):.2g} Hz for {slowest:g} s); add a "
        "record with holds or slow motion (the preload sweeps of bushenv measure --axes 3) or "
        "leave them out (--relaxation-times)"
    )


def _select(prob: _Problem, p: np.ndarray, every: np.ndarray) -> tuple[np.ndarray, str]:
    """The relaxation branches kept: of the grids that drop the shortest branches one by one
    (down to none), the one whose fit on the smaller deflections best predicts the largest
    (``_Problem.beyond``) at the shape ``p``; the fullest grid within ``SELECTION_TIE`` of the
    best score. Short branches can
    imitate an amplitude-dependent friction loop at the training amplitude and not beyond it
    (studies/2026-11-planar-fit-unseen); this asks the training records, not held-out ones."""
    beyond = prob.beyond()
    if beyond is None:
        return every, "every branch (too few samples to test extrapolation)"
    z = prob.hysteretic(p)
    scores = [prob.solve(z, every[k:], ~beyond, beyond)[0] for k in range(len(every) + 1)]
    k = int(np.flatnonzero(np.array(scores) <= min(scores) * (1.0 + SELECTION_TIE))[0])
    shown = ", ".join(f"{s:.3f}" for s in scores)
    kept = ", ".join(f"{t:g}" for t in np.sort(prob.taus[every[k:]]))
    kept = f"{kept} s" if kept else "no branch"
    return every[k:], (
        f"kept {kept} (sum of RMS ratios on the largest {EXTRAPOLATION_SHARE:.0%} of "
        f"deflections, fitted on the rest, dropping the shortest branches one by one: {shown})"
    )


class _Columns:
    """Row i's base columns (``_Problem.base`` then z) by index, and the quasi-linear form's
    designs and coefficients on them: q (3), v (3), c = q_i q^2 (3), P_m[q] (3 M), P_m[c]
    (3 M), z; ``keep`` the branches used, in the order of their gains."""

    def __init__(self, n_m: int, keep: np.ndarray, width: int) -> None:
        self.n_m, self.keep, self.width = n_m, keep, width
        self.q, self.v, self.c = [0, 1, 2], [3, 4, 5], [6, 7, 8]
        self.z = width - 1

    def pq(self, m: int, j: int) -> int:
        return 9 + 3 * int(self.keep[m]) + j

    def pc(self, m: int, j: int) -> int:
        return 9 + 3 * self.n_m + 3 * int(self.keep[m]) + j

    def unit(self, cols: list[int]) -> np.ndarray:
        t = np.zeros((self.width, len(cols)))
        t[cols, np.arange(len(cols))] = 1.0
        return t

    def elastic(self, j: int, r: np.ndarray, kind: str) -> np.ndarray:
        """Base column q_j (or c_j) with its relaxation r_m P_m[.] added."""
        t = np.zeros(self.width)
        t[self.q[j] if kind == "q" else self.c[j]] = 1.0
        for m, rm in enumerate(r):
            t[self.pq(m, j) if kind == "q" else self.pc(m, j)] += rm
        return t

    def branch(self, m: int, k: np.ndarray, g: np.ndarray) -> np.ndarray:
        """Branch m's elastic-force column: sum_j K_j P_m[q_j] + G_j P_m[c_j]."""
        t = np.zeros(self.width)
        for j in range(3):
            t[self.pq(m, j)] = k[j]
            t[self.pc(m, j)] = g[j]
        return t

    def coefficients(self, k, c, g, r, h) -> np.ndarray:
        """The base coefficients of the model (K, C, G, gains r, h)."""
        beta = np.zeros(self.width)
        beta[self.q], beta[self.v], beta[self.c], beta[self.z] = k, c, g, h
        for m, rm in enumerate(r):
            beta += rm * self.branch(m, k, g)
        return beta


def _solve_reduced(a: np.ndarray, free: np.ndarray, held: np.ndarray, y_hat: np.ndarray):
    """``_bounded_lstsq`` on the designs ``a @ free`` and ``a @ held`` (columns scaled to unit
    norm for the solvers, the coefficients scaled back)."""
    f, h = a @ free, a @ held
    fs = np.maximum(np.linalg.norm(f, axis=0), 1e-300)
    hs = np.maximum(np.linalg.norm(h, axis=0), 1e-300)
    x, r = _bounded_lstsq(f / fs, h / hs, y_hat)
    return x / fs, r / hs


def _bounded_lstsq(free: np.ndarray, held: np.ndarray, y: np.ndarray):
    """min |free x + held r - y| with r >= 0: ``free`` projected out (QR), the non-negative
    least squares on what is left (scipy ``nnls``), then x given r. Returns (x, r)."""
    from scipy.optimize import nnls

    q, _ = np.linalg.qr(free)
    r, _ = nnls(held - q @ (q.T @ held), y - q @ (q.T @ y))
    x, *_ = np.linalg.lstsq(free, y - held @ r, rcond=None)
    return x, r
