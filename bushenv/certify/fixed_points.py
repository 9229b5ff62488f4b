"""Every fixed point of a NARX network at held deflection vectors, its stability, and the folds
between holds, for a network over any number of coordinates C.

At a hold q the fixed points are the roots of phi(y) = N(qs, .., y, .., y) - y (``network``).
They are found exhaustively: by cells for C = 1 (``cells``: a bound on phi'' decides every cell,
double roots at a fold included), by boxes for C > 1 (``boxes``: interval enclosures and
Krawczyk's uniqueness test; boxes left at the depth limit are counted, ``unresolved``).

**Stability.** Linearised about y*, the held recurrence is dy_t = sum_l A_l dy_{t-l}
(``NarxNet.lag_matrices``, C x C each); the fixed point is asymptotically stable when the
spectral radius of its block companion matrix is below 1 (C = 1: the scalar companion matrix
of the a_j). Since phi's Jacobian is sum_l A_l - I, a singular root has the eigenvalue 1: that
is where, as q moves, a stable and an unstable fixed point meet and vanish (a fold). Over a grid
of holds the folds are points (C = 1) or surfaces: :func:`folds` finds where they cut the grid's
edges and locates each by bisection (to a nanometre of translation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.certify.boxes import roots_by_boxes
from bushenv.certify.cells import INITIAL_CELLS, roots_by_cells
from bushenv.certify.network import CertifyError, NarxNet, narx_net

FOLD_TOLERANCE_M = 1e-9  # one-coordinate folds are located to a nanometre of displacement
FOLD_TOLERANCE = 1e-4  # fold crossings on a grid's edges: to this fraction of the edge
DUPLICATE = 1e-9  # two roots of one hold closer than this (scaled output) are one


@dataclass(frozen=True, eq=False)
class FixedPoints:
    """The fixed points at M holds, flattened to P points sorted by hold (then y).

    ``q`` (M, C) holds (m, or rad for a rotation); ``hold`` (P,) index into ``q``; ``y`` (P, C)
    scaled network outputs; ``force`` (P, C) static force (K q + f_offset + f_scale y: N, or
    N m); ``spectral_radius`` (P,); ``lag_gradient`` (P, n_past_f, C, C) the lag matrices A_l;
    ``unresolved`` (M,) cells or boxes left at the depth limit (0 unless a hold sits on a fold).
    A one-coordinate network's holds read as scalars too: ``x_m``, ``point_x_m``, ``force_n``.
    """

    q: np.ndarray
    hold: np.ndarray
    y: np.ndarray
    force: np.ndarray
    spectral_radius: np.ndarray
    lag_gradient: np.ndarray
    unresolved: np.ndarray

    @property
    def stable(self) -> np.ndarray:
        return self.spectral_radius < 1.0

    @property
    def count(self) -> np.ndarray:
        """(M,) number of fixed points per hold."""
        return np.bincount(self.hold, minlength=len(self.q))

    @property
    def stable_count(self) -> np.ndarray:
        """(M,) stable fixed points per hold."""
        return np.bincount(self.hold[self.stable], minlength=len(self.q))

    def of_hold(self, i: int) -> np.ndarray:
        """Indices (into the flat arrays) of hold ``i``'s fixed points, in order."""
        return np.flatnonzero(self.hold == i)

    @property
    def x_m(self) -> np.ndarray:
        """(M,) the holds of a one-coordinate network, m."""
        return self.q[:, 0]

    @property
    def point_x_m(self) -> np.ndarray:
        """(P,) the hold of each fixed point of a one-coordinate network, m."""
        return self.q[self.hold, 0]

    @property
    def force_n(self) -> np.ndarray:
        """(P,) the static force of a one-coordinate network's fixed points, N."""
        return self.force[:, 0]


def spectral_radius(a: np.ndarray) -> np.ndarray:
    """(P,) spectral radius of the block companion matrices of dy_t = sum_l a[:, l-1] dy_{t-l};
    ``a`` (P, L, C, C), or (P, L) for one coordinate."""
    a = np.asarray(a, dtype=np.float64)
    if a.ndim <= 2:
        a = np.atleast_2d(a)[:, :, None, None]
    n, lags, dim = a.shape[0], a.shape[1], a.shape[2]
    comp = np.zeros((n, dim * lags, dim * lags))
    comp[:, :dim, :] = a.transpose(0, 2, 1, 3).reshape(n, dim, dim * lags)
    comp[:, dim:, :-dim] = np.eye(dim * (lags - 1))
    return np.abs(np.linalg.eigvals(comp)).max(axis=-1) if n else np.zeros(0)


def _holds(net: NarxNet, q) -> np.ndarray:
    """(M, C) holds from ``q``: (M, C), or (M,) for one coordinate."""
    q = np.asarray(q, dtype=np.float64)
    q = q.reshape(-1, 1) if net.n_coords == 1 and q.ndim <= 1 else np.atleast_2d(q)
    if q.ndim != 2 or q.shape[1] != net.n_coords or not np.all(np.isfinite(q)):
        raise CertifyError(
            f"holds must be finite (M, {net.n_coords}) ({', '.join(net.units)}), got {q.shape}"
        )
    return q


def fixed_points(net_or_model, q, n_cells: int = INITIAL_CELLS) -> FixedPoints:
    """Every fixed point of a network (a ``NarxNet`` or a NARX model) held at each row of ``q``
    (M, C); one coordinate: ``q`` may be (M,). ``n_cells``: the one-coordinate search's first
    cells per hold."""
    net = net_or_model if isinstance(net_or_model, NarxNet) else narx_net(net_or_model)
    q = _holds(net, q)
    c = net.held(q)
    if net.n_coords == 1:
        hold, y, unresolved = roots_by_cells(net, c, n_cells)
    else:
        hold, y, unresolved = roots_by_boxes(net, c)
    order = np.lexsort((*y.T[::-1], hold))
    hold, y = hold[order], y[order]
    if net.n_coords > 1:  # a root on the face two unique boxes share is found twice: keep one
        dup = np.zeros(len(y), dtype=bool)
        dup[1:] = (hold[1:] == hold[:-1]) & np.all(np.abs(y[1:] - y[:-1]) < DUPLICATE, axis=1)
        hold, y = hold[~dup], y[~dup]
    a, _ = net.lag_matrices(c[hold], y)
    return FixedPoints(
        q=q,
        hold=hold,
        y=y,
        force=net.force(q[hold], y),
        spectral_radius=spectral_radius(a),
        lag_gradient=a,
        unresolved=unresolved,
    )


def grid(*axes) -> np.ndarray:
    """(N_1 ... N_C, C) the held vectors of a grid over the given per-coordinate values, the
    first coordinate slowest."""
    mesh = np.meshgrid(*[np.atleast_1d(np.asarray(a, dtype=np.float64)) for a in axes],
                       indexing="ij")  # fmt: skip
    return np.stack([m.ravel() for m in mesh], axis=1)


@dataclass(frozen=True)
class Fold:
    """Where the number of fixed points changes between two holds: a fold (surface, C > 1)
    cuts the edge from ``q_from`` to ``q_to`` at ``q``, from ``count_from`` to ``count_to``
    fixed points; ``force`` where the pair meets, ``radii`` the spectral radii of the pair on
    the side it exists (one is >= 1 at a fold)."""

    q: tuple[float, ...]
    q_from: tuple[float, ...]
    q_to: tuple[float, ...]
    count_from: int
    count_to: int
    force: tuple[float, ...] = ()
    radii: tuple[float, float] = (float("nan"), float("nan"))

    @property
    def exists_above(self) -> bool:
        """Whether the pair exists past the crossing (towards ``q_to``)."""
        return self.count_to > self.count_from

    @property
    def gained(self) -> int:
        """Fixed points gained crossing from ``q_from`` to ``q_to`` (-2 or +2 normally)."""
        return self.count_to - self.count_from

    @property
    def x_m(self) -> float:
        """Where a one-coordinate fold lies, m."""
        return self.q[0]

    @property
    def force_n(self) -> float:
        """Where a one-coordinate fold's pair meets, N."""
        return self.force[0] if self.force else float("nan")


def _pair_at(fp: FixedPoints, i: int) -> tuple[int, int]:
    """The two fixed points of hold ``i`` closest in y (the pair about to merge)."""
    idx = fp.of_hold(i)
    y = fp.y[idx]
    gap = np.linalg.norm(y[:, None, :] - y[None, :, :], axis=-1) + np.diag(np.full(len(y), np.inf))
    j, k = np.unravel_index(np.argmin(gap), gap.shape)
    return int(idx[min(j, k)]), int(idx[max(j, k)])


def _locate(net: NarxNet, a, b, n_a, tol: np.ndarray, refine: bool) -> list[Fold]:
    """Bisect each edge a -> b (rows) until its bracket is narrower than ``tol`` (per edge,
    as a fraction of it); the pair at the end where it exists gives force and radii."""
    s_lo, s_hi = np.zeros(len(a)), np.ones(len(a))
    if not refine:
        s_lo = s_hi = np.full(len(a), 0.5)
    while np.any(s_hi - s_lo > tol):
        s = 0.5 * (s_lo + s_hi)
        same = fixed_points(net, a + s[:, None] * (b - a)).count == n_a
        s_lo, s_hi = np.where(same, s, s_lo), np.where(same, s_hi, s)
    lo, hi = a + s_lo[:, None] * (b - a), a + s_hi[:, None] * (b - a)
    ends = fixed_points(net, np.concatenate([lo, hi]))
    k, out = len(a), []
    for j in range(k):
        c_lo, c_hi = int(ends.count[j]), int(ends.count[k + j])
        side = k + j if c_hi > c_lo else j
        p, r = _pair_at(ends, side) if ends.count[side] >= 2 else (None, None)
        nan2 = (float("nan"), float("nan"))
        out.append(
            Fold(
                q=tuple(float(v) for v in 0.5 * (lo[j] + hi[j])),
                q_from=tuple(float(v) for v in a[j]),
                q_to=tuple(float(v) for v in b[j]),
                count_from=c_lo,
                count_to=c_hi,
                force=()
                if p is None
                else tuple(float(v) for v in 0.5 * (ends.force[p] + ends.force[r])),
                radii=nan2
                if p is None
                else (float(ends.spectral_radius[p]), float(ends.spectral_radius[r])),
            )
        )
    return out


def folds(
    net_or_model,
    fp: FixedPoints | None = None,
    axes: list | None = None,
    refine: bool = True,
    tol_m: float = FOLD_TOLERANCE_M,
) -> list[Fold]:
    """Folds crossing the edges of the grid ``grid(*axes)`` (``fp``: its fixed points, if
    already computed; ``axes`` None: ``fp``'s holds of one coordinate, sorted), each located by
    bisection along its edge to ``tol_m`` of translation (a nanometre) or ``FOLD_TOLERANCE`` of
    the edge, whichever is finer (``refine=False``: placed at the edge's middle; over several
    coordinates the bisection costs ~14 or more certificates of every crossing edge). Two folds
    on one edge show as one change (or none when they cancel): the grid must be finer than
    their spacing."""
    net = net_or_model if isinstance(net_or_model, NarxNet) else narx_net(net_or_model)
    if axes is None:
        if fp is None:
            raise CertifyError("folds: give the grid's axes or its fixed points")
        axes = [fp.q[:, 0]]
    axes = [np.atleast_1d(np.asarray(v, dtype=np.float64)) for v in axes]
    q = grid(*axes)
    fp = fp if fp is not None else fixed_points(net, q)
    n = fp.count.reshape([len(v) for v in axes])
    idx = np.arange(q.shape[0]).reshape(n.shape)
    lo_i, hi_i = [], []
    for ax in range(len(axes)):
        sl0, sl1 = [slice(None)] * len(axes), [slice(None)] * len(axes)
        sl0[ax], sl1[ax] = slice(0, -1), slice(1, None)
        change = n[tuple(sl0)] != n[tuple(sl1)]
        lo_i.append(idx[tuple(sl0)][change])
        hi_i.append(idx[tuple(sl1)][change])
    lo_i, hi_i = np.concatenate(lo_i), np.concatenate(hi_i)
    if lo_i.size == 0:
        return []
    a, b = q[lo_i], q[hi_i]
    metres = np.array([u == "m" for u in net.units])
    length_m = np.max(np.abs(b - a) * metres, axis=1)
    with np.errstate(divide="ignore"):
        tol = np.minimum(FOLD_TOLERANCE, np.where(length_m > 0, tol_m / length_m, np.inf))
    return _locate(net, a, b, fp.count[lo_i], tol, refine)
