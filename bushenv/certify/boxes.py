"""Every root of the diagonal map of a network over C coordinates in a hold: boxes decided by
interval arithmetic (``fixed_points`` for C > 1).

With q held the fixed points are the roots of phi(y) = w_out tanh(c + S y) + b_out - y,
S = sum_l S_l (H, C) (``NarxNet.phi``). The one-coordinate search (``cells``) isolates the
roots of a scalar phi by cells; here y is a vector and the cells are boxes:

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

Rounding is not enclosed (floating-point intervals): the tests hold to 1e-9 margins. The
enclosures are those of one hidden layer (the networks over several coordinates have one).
"""

from __future__ import annotations

import numpy as np

from bushenv.certify.network import CertifyError, NarxNet

INITIAL_SPLITS = 5  # per output, 5^C boxes per hold to start; odd, and the split below is
SPLIT = 0.4871  # off-centre, so a root at a symmetric point (often y = 0) never sits on a face
MAX_DEPTH = 45  # halvings of a box (15 per side for C = 3)
MAX_BOXES = 400_000  # live boxes at once; beyond, the rest is counted unresolved
NEWTON_STEPS = 40


def _enclosures(net: NarxNet, c: np.ndarray, m: np.ndarray, r: np.ndarray):
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
    jc = np.einsum("ih,nh,hj->nij", net.w_out, dm, s) - np.eye(net.n_coords)
    jr = np.einsum("ih,nh,hj->nij", wa, dr, sa)
    fm, _ = net.phi(c, m)
    return fm, nat_c, nat_r, jc, jr


def _newton(net: NarxNet, c: np.ndarray, y: np.ndarray) -> np.ndarray:
    for _ in range(NEWTON_STEPS):
        f, j = net.phi(c, y)
        step = np.linalg.solve(j, f[..., None])[..., 0]
        y = y - step
        if np.all(np.abs(step) <= 1e-15 * np.maximum(1.0, np.abs(y))):
            break
    return y


def _start(net: NarxNet, holds: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hold index, centres and half-widths of the first INITIAL_SPLITS^C boxes of every hold."""
    ctr, half = net.y_box
    n0, dim = INITIAL_SPLITS, net.n_coords
    g = (np.arange(n0) + 0.5) / n0 * 2 - 1  # cell centres in [-1, 1]
    cells = np.stack(np.meshgrid(*[g] * dim, indexing="ij"), -1).reshape(-1, dim)
    hold = np.repeat(np.arange(holds), len(cells))
    m = ctr + np.tile(cells, (holds, 1)) * half
    return hold, m, np.broadcast_to(half / n0, m.shape).copy()


def _split(hold, m, r):
    """Each box cut along its widest side at SPLIT of its width: left SPLIT, right 1 - SPLIT."""
    rows, axis = np.arange(len(r)), np.argmax(r, axis=1)
    lo, w = m[rows, axis] - r[rows, axis], 2.0 * r[rows, axis]
    m_l, m_r, r_l, r_r = m.copy(), m.copy(), r.copy(), r.copy()
    m_l[rows, axis], r_l[rows, axis] = lo + 0.5 * SPLIT * w, 0.5 * SPLIT * w
    m_r[rows, axis] = lo + SPLIT * w + 0.5 * (1 - SPLIT) * w
    r_r[rows, axis] = 0.5 * (1 - SPLIT) * w
    return np.concatenate([hold, hold]), np.concatenate([m_l, m_r]), np.concatenate([r_l, r_r])


def roots_by_boxes(net: NarxNet, c_holds: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(hold (P,), y (P, C), unresolved (M,)): the root of each Krawczyk-unique box at the held
    pre-activations ``c_holds`` (M, H1), unsorted (a root on a face two boxes share: twice)."""
    if net.two_layers:
        raise CertifyError(
            f"{net.model_name}: the box search over several coordinates encloses one hidden "
            "layer; this network has two"
        )
    dim = net.n_coords
    holds = c_holds.shape[0]
    hold, m, r = _start(net, holds)
    found_h, found_y = [], []
    unresolved = np.zeros(holds, dtype=np.int64)
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
            slack = np.abs(np.eye(dim) - inv @ jc[ok]) + np.abs(inv) @ jr[ok]  # I - Y J(Y)
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
        hold, m, r = _split(hold, m, r)
    h = np.concatenate(found_h) if found_h else np.zeros(0, dtype=np.int64)
    y = np.concatenate(found_y) if found_y else np.zeros((0, dim))
    return h, y, unresolved
