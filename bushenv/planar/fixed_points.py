"""Every fixed point of a planar NARX network at held deflection vectors, and its stability.

With q held, every lagged coordinate equals q and the network's recurrence (``narx.py``) is
autonomous in its own scaled outputs y (3,):

    y_t = w_out tanh(c + sum_l S_l y_{t-l}) + b_out,   c = b1 + sum_l Wq_l qs   (qs scaled q)

Its fixed points are the roots of phi(y) = w_out tanh(c + S y) + b_out - y, S = sum_l S_l
(H, 3). The one-axis certificate (``bushenv.certify.fixed_points``) isolates the roots of a
scalar phi by cells; here y is a vector and the cells are boxes, decided by interval arithmetic:

- every tanh lies in [-1, 1], so every root lies in the box I_i = b_out_i +- sum_h
  |w_out[i, h]| (slightly widened), and at least one exists (Brouwer: y -> N(y) maps I into I);
- a box Y = m +- r is *empty* when 0 is outside phi's enclosure for some output i: the
  natural one (tanh is monotone, so each unit's range over Y is exact) or the mean-value one
  phi(m) +- |J(Y)| r, J(Y) the interval Jacobian (tanh' = 1 - tanh^2 bounded over each unit's
  pre-activation range);
- a box holds *exactly one* root when the Krawczyk operator
  K(Y) = m - Jc^-1 phi(m) + |Jc^-1| Jr r  (Jc, Jr centre and radius of J(Y)) lies strictly
  inside Y (Krawczyk 1969; Moore's uniqueness theorem); the root is then found by Newton from m;
- any other box is cut in two along its widest side (off-centre), up to ``MAX_DEPTH`` times.
  Boxes left at the depth limit can only hold (near-)singular roots, a hold on a fold
  surface: they are counted (``unresolved``), never dropped silently.

Stability: linearised about y*, dy_t = sum_l A_l dy_{t-l}, A_l = w_out diag(tanh') S_l (3 x 3);
the fixed point is asymptotically stable when the block companion matrix (15 x 15) has
spectral radius < 1. At a fold a stable and an unstable fixed point meet; over a grid of held
vectors the folds are surfaces: ``fold_crossings`` finds where they cut the grid's edges.
Rounding is not enclosed (floating-point intervals): the tests hold to 1e-9 margins.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_narx import N_PAST_F, N_PAST_Q, PlanarNarx

INITIAL_SPLITS = 5  # per output, 125 boxes per hold to start; odd, and the split below is
SPLIT = 0.4871  # off-centre, so a root at a symmetric point (often y = 0) never sits on a face
MAX_DEPTH = 45  # halvings of a box (15 per side)
MAX_BOXES = 400_000  # live boxes at once; beyond, the rest is counted unresolved
NEWTON_STEPS = 40
FOLD_TOLERANCE = 1e-4  # fold crossings located to this fraction of a grid edge


@dataclass(frozen=True, eq=False)
class HeldNetwork:
    """The arrays of a planar network that its certificates need.

    ``wq`` (6, H, 3): first-layer weights of the scaled coordinate at lags 0..5; ``wy`` (5, H, 3)
    of the own output at lags 1..5; ``k``, ``c`` the backbone (zeros for a pure network).
    """

    q_offset: np.ndarray
    q_scale: np.ndarray
    f_offset: np.ndarray
    f_scale: np.ndarray
    wq: np.ndarray
    wy: np.ndarray
    b1: np.ndarray
    w_out: np.ndarray
    b_out: np.ndarray
    k: np.ndarray
    c: np.ndarray
    dt: float

    @classmethod
    def of(cls, model: PlanarNarx) -> HeldNetwork:
        if not isinstance(model, PlanarNarx):
            raise PlanarModelError(
                f"fixed points are defined for the planar networks (nn, nn-axis, hybrid), "
                f"not {getattr(model, 'name', type(model).__name__)!r}"
            )
        w1 = model.w1
        nq = 3 * (N_PAST_Q + 1)
        k, c = model._backbone_matrices()
        return cls(
            model.q_offset, model.q_scale, model.f_offset, model.f_scale,
            w1[:, :nq].reshape(-1, N_PAST_Q + 1, 3).transpose(1, 0, 2),
            w1[:, nq:].reshape(-1, N_PAST_F, 3).transpose(1, 0, 2),
            model.b1, model.w_out, model.b_out, k, c, model.dt,
        )  # fmt: skip

    @property
    def s(self) -> np.ndarray:
        """(H, 3) the summed own-output weights S."""
        return self.wy.sum(axis=0)

    def held(self, q: np.ndarray) -> np.ndarray:
        """(M, H) the held pre-activation c at the holds ``q`` (M, 3)."""
        qs = (np.asarray(q, dtype=np.float64) - self.q_offset) / self.q_scale
        return self.b1 + qs @ self.wq.sum(axis=0).T

    @property
    def y_box(self) -> tuple[np.ndarray, np.ndarray]:
        """(3,), (3,) centre and half-width of the box every fixed point lies in."""
        return self.b_out.copy(), np.abs(self.w_out).sum(axis=1) * (1 + 1e-9) + 1e-12

    def phi(self, c: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """phi (N, 3) and its Jacobian (N, 3, 3) at pre-activations ``c`` (N, H), points (N, 3)."""
        t = np.tanh(c + y @ self.s.T)
        d = 1.0 - t * t
        jac = np.einsum("ih,nh,hj->nij", self.w_out, d, self.s) - np.eye(3)
        return t @ self.w_out.T + self.b_out - y, jac

    def lag_matrices(self, c: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A (N, 5, 3, 3) own-output lags 1..5 and B (N, 6, 3, 3) scaled-coordinate lags 0..5
        of the linearised recurrence about (c, y)."""
        t = np.tanh(c + y @ self.s.T)
        d = 1.0 - t * t
        a = np.einsum("ih,nh,lhj->nlij", self.w_out, d, self.wy)
        b = np.einsum("ih,nh,lhj->nlij", self.w_out, d, self.wq)
        return a, b

    def force(self, q: np.ndarray, y: np.ndarray) -> np.ndarray:
        """(N, 3) static force at holds ``q``, outputs ``y`` (N, 3): K q + f_offset + f_scale y."""
        return q @ self.k.T + self.f_offset + self.f_scale * y


def spectral_radius(a: np.ndarray) -> np.ndarray:
    """(N,) spectral radius of the block companion matrices of dy_t = sum_l a[:, l-1] dy_{t-l}
    (``a`` (N, L, 3, 3))."""
    n, lags = a.shape[:2]
    comp = np.zeros((n, 3 * lags, 3 * lags))
    comp[:, :3, :] = a.transpose(0, 2, 1, 3).reshape(n, 3, 3 * lags)
    comp[:, 3:, :-3] = np.eye(3 * (lags - 1))
    return np.abs(np.linalg.eigvals(comp)).max(axis=-1) if n else np.zeros(0)


@dataclass(frozen=True, eq=False)
class PlanarFixedPoints:
    """Fixed points at M holds, flattened to P points sorted by hold.

    ``q`` (M, 3) holds (m, m, rad); ``hold`` (P,) index into ``q``; ``y`` (P, 3) scaled outputs;
    ``force`` (P, 3) static force (N, N, N m); ``spectral_radius`` (P,); ``unresolved`` (M,)
    boxes left at the depth limit (0 unless a hold sits on a fold surface).
    """

    q: np.ndarray
    hold: np.ndarray
    y: np.ndarray
    force: np.ndarray
    spectral_radius: np.ndarray
    unresolved: np.ndarray

    @property
    def stable(self) -> np.ndarray:
        return self.spectral_radius < 1.0

    @property
    def count(self) -> np.ndarray:
        """(M,) fixed points per hold."""
        return np.bincount(self.hold, minlength=len(self.q))

    @property
    def stable_count(self) -> np.ndarray:
        """(M,) stable fixed points per hold."""
        return np.bincount(self.hold[self.stable], minlength=len(self.q))


def _enclosures(net: HeldNetwork, c: np.ndarray, m: np.ndarray, r: np.ndarray):
    """phi(m), natural and mean-value enclosure radii, Jacobian centre and radius over boxes."""
    s, sa = net.s, np.abs(net.s)
    pc = c + m @ s.T
    pr = r @ sa.T
    lo, hi = np.tanh(pc - pr), np.tanh(pc + pr)
    tm, tr = 0.5 * (lo + hi), 0.5 * (hi - lo)
    wa = np.abs(net.w_out)
    nat_c = tm @ net.w_out.T + net.b_out - m
    nat_r = tr @ wa.T + r
    # tanh' = 1 - tanh^2 over [pc - pr, pc + pr]: largest where |.| is least
    near = np.where((pc - pr) * (pc + pr) <= 0, 0.0, np.minimum(np.abs(pc - pr), np.abs(pc + pr)))
    d_hi = 1.0 - np.tanh(near) ** 2
    d_lo = 1.0 - np.maximum(lo * lo, hi * hi)
    dm, dr = 0.5 * (d_hi + d_lo), 0.5 * (d_hi - d_lo)
    jc = np.einsum("ih,nh,hj->nij", net.w_out, dm, s) - np.eye(3)
    jr = np.einsum("ih,nh,hj->nij", wa, dr, sa)
    fm, _ = net.phi(c, m)
    return fm, nat_c, nat_r, jc, jr


def _newton(net: HeldNetwork, c: np.ndarray, y: np.ndarray) -> np.ndarray:
    for _ in range(NEWTON_STEPS):
        f, j = net.phi(c, y)
        step = np.linalg.solve(j, f[..., None])[..., 0]
        y = y - step
        if np.all(np.abs(step) <= 1e-15 * np.maximum(1.0, np.abs(y))):
            break
    return y


def _isolate(net: HeldNetwork, c_holds: np.ndarray):
    """Root of each Krawczyk-unique box (hold, y), and unresolved boxes per hold."""
    ctr, half = net.y_box
    M = c_holds.shape[0]
    n0 = INITIAL_SPLITS
    g = (np.arange(n0) + 0.5) / n0 * 2 - 1  # cell centres in [-1, 1]
    cells = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    hold = np.repeat(np.arange(M), len(cells))
    m = ctr + np.tile(cells, (M, 1)) * half
    r = np.broadcast_to(half / n0, m.shape).copy()
    found_h, found_y = [], []
    unresolved = np.zeros(M, dtype=np.int64)
    for depth in range(MAX_DEPTH + 1):
        c = c_holds[hold]
        fm, nat_c, nat_r, jc, jr = _enclosures(net, c, m, r)
        mv_r = np.einsum("nij,nj->ni", np.abs(jc) + jr, r)
        empty = np.any(np.abs(nat_c) > nat_r, axis=1) | np.any(np.abs(fm) > mv_r, axis=1)
        det = np.linalg.det(jc)
        ok = ~empty & (np.abs(det) > 1e-300)
        unique = np.zeros(len(m), dtype=bool)
        if ok.any():
            inv = np.linalg.inv(jc[ok])
            kc = m[ok] - np.einsum("nij,nj->ni", inv, fm[ok])
            slack = np.abs(np.eye(3) - inv @ jc[ok]) + np.abs(inv) @ jr[ok]  # I - Y J(Y)
            kr = np.einsum("nij,nj->ni", slack, r[ok])
            inside = np.all(np.abs(kc - m[ok]) + kr < r[ok] * (1 - 1e-9), axis=1)
            apart = np.any(np.abs(kc - m[ok]) - kr > r[ok], axis=1)  # K(Y) misses Y: no root
            unique[np.flatnonzero(ok)[inside]] = True
            empty[np.flatnonzero(ok)[apart]] = True
        if unique.any():
            found_h.append(hold[unique])
            found_y.append(_newton(net, c[unique], m[unique]))
        rest = ~empty & ~unique
        hold, m, r = hold[rest], m[rest], r[rest]
        if hold.size == 0:
            break
        if depth == MAX_DEPTH or 2 * hold.size > MAX_BOXES:
            np.add.at(unresolved, hold, 1)
            break
        # cut the widest side at SPLIT of its width: left part SPLIT, right part 1 - SPLIT
        rows, axis = np.arange(len(r)), np.argmax(r, axis=1)
        lo, w = m[rows, axis] - r[rows, axis], 2.0 * r[rows, axis]
        m_l, m_r, r_l, r_r = m.copy(), m.copy(), r.copy(), r.copy()
        m_l[rows, axis], r_l[rows, axis] = lo + 0.5 * SPLIT * w, 0.5 * SPLIT * w
        m_r[rows, axis] = lo + SPLIT * w + 0.5 * (1 - SPLIT) * w
        r_r[rows, axis] = 0.5 * (1 - SPLIT) * w
        hold = np.concatenate([hold, hold])
        m, r = np.concatenate([m_l, m_r]), np.concatenate([r_l, r_r])
    h = np.concatenate(found_h) if found_h else np.zeros(0, dtype=np.int64)
    y = np.concatenate(found_y) if found_y else np.zeros((0, 3))
    return h, y, unresolved


def fixed_points(model: PlanarNarx, q: np.ndarray) -> PlanarFixedPoints:
    """Every fixed point of ``model`` (a planar network) held at each row of ``q`` (M, 3)."""
    net = HeldNetwork.of(model)
    q = np.atleast_2d(np.asarray(q, dtype=np.float64))
    if q.ndim != 2 or q.shape[1] != 3 or not np.all(np.isfinite(q)):
        raise PlanarModelError(
            f"holds must be finite (M, 3) (axial m, radial m, rad), got {q.shape}"
        )
    c = net.held(q)
    hold, y, unresolved = _isolate(net, c)
    # a root on the face two unique boxes share is found twice: keep one
    order = np.lexsort((*y.T[::-1], hold))
    hold, y = hold[order], y[order]
    dup = np.zeros(len(y), dtype=bool)
    dup[1:] = (hold[1:] == hold[:-1]) & np.all(np.abs(y[1:] - y[:-1]) < 1e-9, axis=1)
    hold, y = hold[~dup], y[~dup]
    a, _ = net.lag_matrices(c[hold], y)
    return PlanarFixedPoints(
        q=q,
        hold=hold,
        y=y,
        force=net.force(q[hold], y),
        spectral_radius=spectral_radius(a),
        unresolved=unresolved,
    )


def grid(axial_m, radial_m, rotation_rad) -> np.ndarray:
    """(Na Nr Nt, 3) the held vectors of a grid, axial slowest, rotation fastest."""
    a, r, t = np.meshgrid(axial_m, radial_m, rotation_rad, indexing="ij")
    return np.stack([a.ravel(), r.ravel(), t.ravel()], axis=1)


@dataclass(frozen=True)
class FoldCrossing:
    """Where the number of fixed points changes along a grid edge: the fold surface cuts the
    edge between holds ``q_from`` and ``q_to`` at ``q`` (m, m, rad), from ``count_from`` to
    ``count_to`` fixed points."""

    q: tuple[float, float, float]
    q_from: tuple[float, float, float]
    q_to: tuple[float, float, float]
    count_from: int
    count_to: int


def fold_crossings(
    model: PlanarNarx,
    axial_m,
    radial_m,
    rotation_rad,
    fp: PlanarFixedPoints | None = None,
    refine: bool = True,
) -> list[FoldCrossing]:
    """Fold-surface crossings on the edges of the grid ``grid(axial_m, radial_m, rotation_rad)``
    (``fp``: its fixed points, if already computed), each refined by bisection along its edge
    to ``FOLD_TOLERANCE`` of it (``refine=False``: placed at the edge's middle; the bisection
    costs ~14 certificates of every crossing edge). Two crossings on one edge show as one
    change (or none): the grid must be finer."""
    axes = [
        np.atleast_1d(np.asarray(v, dtype=np.float64)) for v in (axial_m, radial_m, rotation_rad)
    ]
    q = grid(*axes)
    fp = fp if fp is not None else fixed_points(model, q)
    n = fp.count.reshape([len(v) for v in axes])
    idx = np.arange(q.shape[0]).reshape(n.shape)
    lo_i, hi_i = [], []
    for ax in range(3):
        sl0 = [slice(None)] * 3
        sl1 = [slice(None)] * 3
        sl0[ax], sl1[ax] = slice(0, -1), slice(1, None)
        change = n[tuple(sl0)] != n[tuple(sl1)]
        lo_i.append(idx[tuple(sl0)][change])
        hi_i.append(idx[tuple(sl1)][change])
    lo_i, hi_i = np.concatenate(lo_i), np.concatenate(hi_i)
    if lo_i.size == 0:
        return []
    a, b = q[lo_i].copy(), q[hi_i].copy()
    n_a = fp.count[lo_i]
    s_lo, s_hi = np.zeros(len(a)), np.ones(len(a))
    if not refine:
        s_lo = s_hi = np.full(len(a), 0.5)
    while np.max(s_hi - s_lo) > FOLD_TOLERANCE:
        s = 0.5 * (s_lo + s_hi)
        same = fixed_points(model, a + s[:, None] * (b - a)).count == n_a
        s_lo, s_hi = np.where(same, s, s_lo), np.where(same, s_hi, s)
    at = a + (0.5 * (s_lo + s_hi))[:, None] * (b - a)
    return [
        FoldCrossing(tuple(at[k]), tuple(a[k]), tuple(b[k]), int(n_a[k]), int(fp.count[hi_i[k]]))
        for k in range(len(a))
    ]
