"""Every fixed point of a NARX network in a hold, its stability, and the folds between holds.

**Why the search below finds every fixed point.** At a hold x the fixed points are the roots
of phi(y) = N(xs, .., y, .., y) - y (``network.diagonal``). Every hidden unit is a tanh in
[-1, 1], so N lies in I = [b_out - sum |w_out|, b_out + sum |w_out|] whatever its input; a
root y* = N(.., y*, ..) therefore lies in I, and phi > 0 just below I, phi < 0 just above it,
so at least one root exists. I (slightly widened) is cut into cells; with M bounding |phi''|
(``network.derivative_bounds``) a cell [a, b] of width w, sigma = sign(phi(a)), is

- *empty* when phi(a), phi(b) share the sign sigma and sigma phi(a) + sigma phi'(a) w/2 - M w^2/8
  and sigma phi(b) - sigma phi'(b) w/2 - M w^2/8 are both > 0: by Taylor's theorem sigma phi is
  bounded below on each half by a concave quadratic whose minimum over the half is at its
  ends, and those ends are the numbers just checked, so phi has no root in the cell;
- *monotone* when phi'(a), phi'(b) share a sign and |phi'(a)| + |phi'(b)| > M w: phi' is
  M-Lipschitz, so it cannot reach 0 inside, phi is strictly monotone and has exactly one root
  in [a, b) if phi(a) = 0 or phi(a) phi(b) < 0, none otherwise.

Any other cell is halved, up to ``MAX_DEPTH`` times. Every root lies in a cell that is never
declared empty, so each root ends in a monotone cell (found, then refined by bisection to
machine precision) or in a cell left unresolved at the depth limit, which is narrower than
``2**-MAX_DEPTH`` of the initial cell and can only hold a (near-)double root: a hold sitting
on a fold to within that width. Unresolved cells are counted per hold (``unresolved``) and
each run of touching ones gives one root (phi vanishes there to machine precision; a tangent
root need not change sign), so nothing is dropped silently: whether a hold placed exactly on a
fold shows its double root no longer depends on how the platform rounds tanh.

**Stability.** Linearised about y*, the held recurrence is dy_t = sum_j a_j dy_{t-j}
(``network.lag_gradients``); the fixed point is asymptotically stable when the spectral
radius of its companion matrix is below 1. Since phi'(y*) = sum a_j - 1, a root where phi'
vanishes (a double root) has the eigenvalue 1: that is where, as x moves, a stable and an
unstable fixed point meet and vanish (a fold, :func:`folds`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.certify.network import NarxNet, derivative_bounds, diagonal, lag_gradients

INITIAL_CELLS = 256  # per hold; the bounds decide the rest
MAX_DEPTH = 40  # halvings of a cell: 2^-40 of a 1/256 cell, far below float64 use
BISECTION_STEPS = 60
FOLD_TOLERANCE_M = 1e-9  # folds are located to a nanometre of displacement


@dataclass(frozen=True, eq=False)
class FixedPoints:
    """The fixed points at M holds, flattened to P points sorted by (hold, y).

    ``x_m`` (M,) holds, m; ``hold`` (P,) index into ``x_m``; ``y`` (P,) scaled network
    output; ``force_n`` (P,) static force (k x + f_offset + f_scale y), N; ``spectral_radius``
    (P,); ``lag_gradient`` (P, n_past_f) the a_j; ``unresolved`` (M,) cells left at the depth
    limit (0 unless a hold sits on a fold to within machine precision).
    """

    x_m: np.ndarray
    hold: np.ndarray
    y: np.ndarray
    force_n: np.ndarray
    spectral_radius: np.ndarray
    lag_gradient: np.ndarray
    unresolved: np.ndarray

    @property
    def stable(self) -> np.ndarray:
        return self.spectral_radius < 1.0

    @property
    def point_x_m(self) -> np.ndarray:
        """(P,) the hold of each fixed point, m."""
        return self.x_m[self.hold]

    @property
    def count(self) -> np.ndarray:
        """(M,) number of fixed points per hold."""
        return np.bincount(self.hold, minlength=self.x_m.size)

    def of_hold(self, i: int) -> np.ndarray:
        """Indices (into the flat arrays) of hold ``i``'s fixed points, by increasing y."""
        return np.flatnonzero(self.hold == i)


def spectral_radius(a: np.ndarray) -> np.ndarray:
    """(P,) spectral radius of the companion matrices of dy_t = sum_j a[:, j-1] dy_{t-j}."""
    a = np.atleast_2d(a)
    P, n = a.shape
    comp = np.zeros((P, n, n))
    comp[:, 0, :] = a
    comp[:, np.arange(1, n), np.arange(n - 1)] = 1.0
    return np.abs(np.linalg.eigvals(comp)).max(axis=-1) if P else np.zeros(0)


def _cells(net: NarxNet, c: np.ndarray, n_cells: int):
    lo, hi = net.y_range
    pad = 1e-9 * (hi - lo) + 1e-12
    edges = np.linspace(lo - pad, hi + pad, n_cells + 1)
    phi, dphi = diagonal(net, c[:, None, :], edges[None, :])
    m = c.shape[0]
    hold = np.repeat(np.arange(m), n_cells)
    a = np.tile(edges[:-1], m)
    b = np.tile(edges[1:], m)
    return (
        hold,
        a,
        b,
        phi[:, :-1].ravel(),
        phi[:, 1:].ravel(),
        dphi[:, :-1].ravel(),
        dphi[:, 1:].ravel(),
    )


def _isolate(net: NarxNet, c: np.ndarray, n_cells: int):
    """Cells [a, b) holding exactly one root, and the unresolved ones (see the module doc)."""
    _, curv = derivative_bounds(net)
    hold, a, b, pa, pb, da, db = _cells(net, c, n_cells)
    found, unresolved = [], []
    for depth in range(MAX_DEPTH + 1):
        w = b - a
        sig = np.sign(pa)
        q = curv * w * w / 8.0
        empty = (
            (pa * pb > 0) & (sig * (pa + da * w / 2) - q > 0) & (sig * (pb - db * w / 2) - q > 0)
        )
        mono = (da * db > 0) & (np.abs(da) + np.abs(db) > curv * w)
        has_root = (pa == 0) | (pa * pb < 0)
        pick = ~empty & mono & has_root
        found.append((hold[pick], a[pick], b[pick], pa[pick]))
        rest = ~empty & ~mono
        hold, a, b, pa, pb, da, db = (v[rest] for v in (hold, a, b, pa, pb, da, db))
        if hold.size == 0:
            break
        if depth == MAX_DEPTH:
            unresolved.append(hold)
            # phi vanishes on such a cell to machine precision: a (near-)double root, kept
            # whether or not phi changes sign across it (a tangent root at a fold does not,
            # or does by rounding alone), one per run of adjacent cells; pa = 0 marks it exact
            keep = _one_per_run(hold, a, b, np.abs(pa) + np.abs(pb))
            sign_change = (pa == 0) | (pa * pb < 0)
            found.append((hold[keep], a[keep], b[keep], np.where(sign_change, pa, 0.0)[keep]))
            break
        mid = 0.5 * (a + b)
        pm, dm = diagonal(net, c[hold], mid)
        hold = np.concatenate([hold, hold])
        a, b = np.concatenate([a, mid]), np.concatenate([mid, b])
        pa, pb = np.concatenate([pa, pm]), np.concatenate([pm, pb])
        da, db = np.concatenate([da, dm]), np.concatenate([dm, db])
    cat = [np.concatenate(parts) for parts in zip(*found, strict=True)]
    bad = np.concatenate(unresolved) if unresolved else np.zeros(0, dtype=np.int64)
    return (*cat, np.bincount(bad, minlength=c.shape[0]))


def _one_per_run(hold: np.ndarray, a: np.ndarray, b: np.ndarray, size: np.ndarray) -> np.ndarray:
    """Indices of one cell (the smallest ``size``) per run of touching cells of one hold."""
    order = np.lexsort((a, hold))
    keep, best = [], None
    for k, i in enumerate(order):
        j = order[k - 1] if k else None
        touching = j is not None and hold[i] == hold[j] and a[i] <= b[j]
        if not touching:
            if best is not None:
                keep.append(best)
            best = i
        elif size[i] < size[best]:
            best = i
    if best is not None:
        keep.append(best)
    return np.array(keep, dtype=np.int64)


def _bisect(net: NarxNet, c: np.ndarray, a: np.ndarray, b: np.ndarray, pa: np.ndarray):
    """Roots of phi in [a, b) given a sign change (or phi(a) = 0), vectorised."""
    exact = pa == 0
    sa = np.sign(pa)
    a, b = a.copy(), b.copy()
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (a + b)
        pm, _ = diagonal(net, c, mid)
        left = np.sign(pm) == sa
        a = np.where(left, mid, a)
        b = np.where(left, b, mid)
        if np.all(b - a <= 4 * np.finfo(float).eps * np.maximum(1.0, np.abs(a))):
            break
    return np.where(exact, a, 0.5 * (a + b))


def fixed_points(net: NarxNet, x_m: np.ndarray, n_cells: int = INITIAL_CELLS) -> FixedPoints:
    """Every fixed point of ``net`` held at each displacement of ``x_m`` (M,), m."""
    x_m = np.atleast_1d(np.asarray(x_m, dtype=np.float64))
    c = net.held_preactivation(x_m)
    hold, a, b, pa, unresolved = _isolate(net, c, n_cells)
    y = _bisect(net, c[hold], a, b, pa)
    order = np.lexsort((y, hold))
    hold, y = hold[order], y[order]
    grad, _ = lag_gradients(net, c[hold], y)
    return FixedPoints(
        x_m=x_m,
        hold=hold,
        y=y,
        force_n=net.force_n(x_m[hold], y),
        spectral_radius=spectral_radius(grad),
        lag_gradient=grad,
        unresolved=unresolved,
    )


@dataclass(frozen=True)
class Fold:
    """A fold between two holds: a pair of fixed points exists on one side of ``x_m`` only.

    ``exists_above``: the pair exists for x > x_m (else for x < x_m). ``force_n``: where the
    pair meets. ``radii``: spectral radii of the pair just on its side (one is >= 1 at a
    fold). ``gained``: fixed points gained crossing it upwards in x (-2 or +2 normally).
    """

    x_m: float
    force_n: float
    exists_above: bool
    radii: tuple[float, float]
    gained: int


def _pair_at(fp: FixedPoints, i: int) -> tuple[int, int]:
    """The two adjacent fixed points of hold ``i`` closest in y (the pair about to merge)."""
    idx = fp.of_hold(i)
    k = int(np.argmin(np.diff(fp.y[idx])))
    return int(idx[k]), int(idx[k + 1])


def folds(net: NarxNet, fp: FixedPoints, tol_m: float = FOLD_TOLERANCE_M) -> list[Fold]:
    """Folds between consecutive holds of ``fp`` (x sorted ascending), refined by bisection.

    Where the number of fixed points changes between x_i and x_{i+1}, the interval is halved
    (all such intervals at once) until it is narrower than ``tol_m``. Two folds within one
    interval of the hold grid are seen as one change (or none when they cancel): the grid
    must be finer than the folds' spacing.
    """
    n = fp.count
    change = np.flatnonzero(n[1:] != n[:-1])
    if change.size == 0:
        return []
    lo, hi = fp.x_m[change].copy(), fp.x_m[change + 1].copy()
    n_lo = n[change].copy()
    while np.max(hi - lo) > tol_m:
        mid = 0.5 * (lo + hi)
        same = fixed_points(net, mid).count == n_lo
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    result = []
    ends = fixed_points(net, np.concatenate([lo, hi]))
    k = lo.size
    for j in range(k):
        c_lo, c_hi = ends.count[j], ends.count[k + j]
        side = k + j if c_hi > c_lo else j
        p, q = _pair_at(ends, side) if ends.count[side] >= 2 else (0, 0)
        result.append(
            Fold(
                x_m=float(0.5 * (lo[j] + hi[j])),
                force_n=float(0.5 * (ends.force_n[p] + ends.force_n[q])),
                exists_above=bool(c_hi > c_lo),
                radii=(float(ends.spectral_radius[p]), float(ends.spectral_radius[q])),
                gained=int(c_hi - c_lo),
            )
        )
    return result
