"""Every root of the diagonal map of a one-coordinate network in a hold: cells decided by a
bound on phi'' (``fixed_points`` for C = 1).

**Why the search finds every root.** At a hold x the fixed points are the roots of
phi(y) = N(xs, .., y, .., y) - y (``NarxNet.phi``). Every hidden unit is a tanh in [-1, 1], so N
lies in I = [b_out - sum |w_out|, b_out + sum |w_out|] whatever its input; a root
y* = N(.., y*, ..) therefore lies in I, and phi > 0 just below I, phi < 0 just above it, so at
least one root exists. I (slightly widened) is cut into cells; with M bounding |phi''|
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
on a fold to within that width. Unresolved cells are counted per hold and each run of touching
ones gives one root (phi vanishes there to machine precision; a tangent root need not change
sign), so nothing is dropped silently: whether a hold placed exactly on a fold shows its double
root does not depend on how the platform rounds tanh. This is the one-dimensional form of the
box search (``boxes``): in one dimension a curvature bound decides every cell, double roots
included, where boxes leave them unresolved.
"""

from __future__ import annotations

import numpy as np

from bushenv.certify.network import NarxNet, derivative_bounds, diagonal

INITIAL_CELLS = 256  # per hold; the bounds decide the rest
MAX_DEPTH = 40  # halvings of a cell: 2^-40 of a 1/256 cell, far below float64 use
BISECTION_STEPS = 60


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


def roots_by_cells(
    net: NarxNet, c: np.ndarray, n_cells: int = INITIAL_CELLS
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(hold (P,), y (P, 1), unresolved (M,)): every root of a one-coordinate network's phi at
    the held pre-activations ``c`` (M, H1), unsorted."""
    hold, a, b, pa, unresolved = _isolate(net, c, n_cells)
    return hold, _bisect(net, c[hold], a, b, pa)[:, None], unresolved
