"""The compiled arithmetic of ``HalfCarBatch``: chipmunk's step for the half car's bodies and
elements, over many cars at once, with the loop over cars innermost so that it vectorises.

The state ``S`` is (8, 9, N): rows ``PX, PY, ANG, VX, VY, W, COS, SIN`` of the nine bodies
(``BODIES``: the chassis, then per side the lower arm, upper arm, upright and the kinematic
road), one column per car. The elements are chipmunk's ``DampedSpring`` and
``DampedRotarySpring`` in the pymunk car's order (``halfcar_batch_layout``), one sub-step being
chipmunk 7's ``cpSpaceStep`` for them:

1. positions: p += v h, angle += w h (the rotation's cos and sin advanced by the turned angle
   through its Taylor series, below 1e-16 for |w h| < 0.03 rad, i.e. |w| < 100 rad/s, instead
   of libm's cos and sin, which do not vectorise here);
2. each element's pre-step: its spring impulse f h applied at once (the tyre's law: compression
   only, no pull beyond the static load; when a wheel lifts or lands the lateral tyre switches
   in the same sub-step, the tyre's damper from the next, as ``HalfCar._tyre_law``);
3. the lateral load: v += g h on every moving body;
4. ``iterations`` sweeps of the damper impulses (chipmunk's ``applyImpulse``: each damper moves
   its relative velocity towards its target, Gauss-Seidel over the elements).

One difference to the pymunk car: every damper's coefficient per sub-step is implicit Euler at
the current configuration, v_coef = 1 - 1 / (1 + c h k), where the pymunk car sets chipmunk's
coefficient so that it is that at the configuration of its last ``update_damping`` (redone
every 0.02 rad), and the ball joints' at their stiffer direction (``HalfCar.update_damping``).
The tyres' dampers are chipmunk's own, v_coef = 1 - exp(-c h k), as in the pymunk car.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

PX, PY, ANG, VX, VY, W, COS, SIN = range(8)
N_ROWS = 8
SPRING, ROTARY, TYRE, LATERAL = range(4)  # element kinds
# scratch rows per element: the direction, the anchors' arms across it (r x n), 1 / k, v_coef
# and the damper's target velocity
NX, NY, C1, C2, NMASS, VCOEF, TARGET = range(7)
N_SCRATCH = 7
CHUNK = 256  # cars stepped together: one chunk's state and scratch stay in the L1/L2 caches


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _one_minus_exp(x):  # pragma: no cover - compiled
    """1 - exp(-x) for a tyre damper per sub-step (x about 0.12 for the lateral tyre here:
    6e-10 relative; 2e-7 at x = 0.3): a polynomial vectorises where libm's exp does not."""
    return x * (1.0 - x * (0.5 - x * (1.0 / 6 - x * (1.0 / 24 - x * (1.0 / 120 - x / 720)))))


@nb.njit(cache=True, nogil=True, error_model="numpy")
def substeps_kernel(
    S, rest, stiff, damp, contact, gx, h_car, n_sub, iterations,
    kind, ia, ib, side, anchors, m_inv, i_inv, k_tyre, lift, c_tyre, k_lat, c_lat, b_lo, b_hi,
):  # fmt: skip  # pragma: no cover - compiled
    """Advance the cars ``b_lo`` to ``b_hi - 1`` (columns of ``S``; the others untouched, so
    two threads may step two ranges) by ``n_sub`` sub-steps of ``h_car`` (N,) s (0 holds a car
    still).

    Per car: ``rest``, ``stiff``, ``damp`` (E, N) each element's rest length (rest angle for a
    rotary spring), stiffness and damping coefficient c (physical, N s/m or N m s/rad);
    ``contact`` (2, N) 1.0 where a wheel touches its road (updated); ``gx`` (N,) the lateral
    load on every body, m/s^2. Per element: ``kind``, bodies ``ia``, ``ib``, the road side
    (tyres), local anchors (E, 4); per body ``m_inv``, ``i_inv`` (0 for the roads). The tyres'
    law: ``k_tyre``, ``lift`` (the most negative tyre force, -static load), ``c_tyre``; the
    lateral tyres' ``k_lat``, ``c_lat`` while the wheel touches.

    Cars go in chunks of ``CHUNK`` copied to local arrays of a fixed width (the last chunk
    padded with a car held still), so that the compiler sees every row apart and vectorises
    the loops over cars."""
    n_el = kind.shape[0]
    n_body = m_inv.shape[0]
    n = b_hi
    # ONE local array for the chunk (state, scratch, parameters, contacts, load, step), so that
    # the compiler relates every access by a row offset and vectorises (arrays apart it would
    # have to check at run time, pair by pair, and gives up)
    o_sc = N_ROWS * n_body  # element e's scratch row r: o_sc + e * N_SCRATCH + r
    o_par = o_sc + N_SCRATCH * n_el  # rest, stiffness, damping of element e: o_par + 3 e + ...
    o_ct = o_par + 3 * n_el  # contact left, right; then landed left, right; the load; the step
    o_g, o_h = o_ct + 4, o_ct + 5
    w = min(CHUNK, (n - b_lo + 7) // 8 * 8)  # a chunk's width: small batches pad to 8 cars
    L = np.zeros((o_h + 1, w))
    for b0 in range(b_lo, n, w):
        for i in range(w):
            b = b0 + i if b0 + i < n else b0
            L[o_h, i] = h_car[b] if b0 + i < n else 0.0
            L[o_g, i] = gx[b]
            L[o_ct, i], L[o_ct + 1, i] = contact[0, b], contact[1, b]
            for r in range(N_ROWS):
                for k in range(n_body):
                    L[r * n_body + k, i] = S[r, k, b]
            for e in range(n_el):
                L[o_par + 3 * e, i], L[o_par + 3 * e + 1, i] = rest[e, b], stiff[e, b]
                L[o_par + 3 * e + 2, i] = damp[e, b]
        for _ in range(n_sub):
            _positions(L, o_h, n_body)
            for e in range(n_el):
                _pre_step(L, o_sc, o_par, o_ct, o_h, e, kind[e], ia[e], ib[e], side[e], anchors,
                          m_inv, i_inv, n_body, k_tyre, lift, c_tyre, k_lat, c_lat)  # fmt: skip
            for k in range(n_body):  # the lateral load on every moving body
                if m_inv[k] != 0.0:
                    vx = VX * n_body + k
                    for i in range(L.shape[1]):
                        L[vx, i] += L[o_g, i] * L[o_h, i]
            for _it in range(iterations):
                for e in range(n_el):
                    _damp(L, o_sc + e * N_SCRATCH, kind[e], ia[e], ib[e], m_inv, i_inv, n_body)
        for i in range(min(w, n - b0)):
            b = b0 + i
            contact[0, b], contact[1, b] = L[o_ct, i], L[o_ct + 1, i]
            for r in range(N_ROWS):
                for k in range(n_body):
                    S[r, k, b] = L[r * n_body + k, i]
            for e in range(n_el):
                rest[e, b] = L[o_par + 3 * e, i]


@nb.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _positions(L, o_h, n_body):  # pragma: no cover - compiled
    for k in range(n_body):
        px, py, ang = PX * n_body + k, PY * n_body + k, ANG * n_body + k
        vx, vy, w = VX * n_body + k, VY * n_body + k, W * n_body + k
        co, si = COS * n_body + k, SIN * n_body + k
        for i in range(L.shape[1]):
            h = L[o_h, i]
            L[px, i] += h * L[vx, i]
            L[py, i] += h * L[vy, i]
            x = h * L[w, i]
            L[ang, i] += x
            x2 = x * x
            cw = 1.0 - x2 * (0.5 - x2 * (1.0 / 24 - x2 / 720))
            sw = x * (1.0 - x2 * (1.0 / 6 - x2 * (1.0 / 120 - x2 / 5040)))
            c, s = L[co, i], L[si, i]
            L[co, i] = c * cw - s * sw
            L[si, i] = s * cw + c * sw


@nb.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _pre_step(
    L, o_sc, o_par, o_ct, o_h, e, kd, a, bb, sd, anchors, m_inv, i_inv, n_body,
    k_tyre, lift, c_tyre, k_lat, c_lat,
):  # fmt: skip  # pragma: no cover - compiled
    """Element ``e``'s chipmunk pre-step for the chunk: its geometry and damper coefficient
    into the scratch, its spring impulse applied."""
    ma, mb, ja, jb = m_inv[a], m_inv[bb], i_inv[a], i_inv[bb]
    s0 = o_sc + e * N_SCRATCH
    wa, wb = W * n_body + a, W * n_body + bb
    rs, st, dm = o_par + 3 * e, o_par + 3 * e + 1, o_par + 3 * e + 2
    ct, ld = o_ct + sd, o_ct + 2 + sd  # this side's contact and landed rows
    if kd == ROTARY:
        moment = ja + jb
        angle_a, angle_b = ANG * n_body + a, ANG * n_body + bb
        for i in range(L.shape[1]):
            h = L[o_h, i]
            L[s0 + NMASS, i] = 1.0 / moment
            L[s0 + VCOEF, i] = 1.0 - 1.0 / (1.0 + L[dm, i] * h * moment)
            L[s0 + TARGET, i] = 0.0
            j = ((L[angle_a, i] - L[angle_b, i]) - L[rs, i]) * L[st, i] * h
            L[wa, i] -= j * ja
            L[wb, i] += j * jb
        return
    ax, ay, bx, by = anchors[e, 0], anchors[e, 1], anchors[e, 2], anchors[e, 3]
    pxa, pya, pxb, pyb = PX * n_body + a, PY * n_body + a, PX * n_body + bb, PY * n_body + bb
    ca, sa, cb, sb = COS * n_body + a, SIN * n_body + a, COS * n_body + bb, SIN * n_body + bb
    # the geometry first (k in NMASS, the length in VCOEF, dx in TARGET for now), then each
    # kind's law in a loop of its own: a loop without branches vectorises
    for i in range(L.shape[1]):
        r1x = L[ca, i] * ax - L[sa, i] * ay
        r1y = L[sa, i] * ax + L[ca, i] * ay
        r2x = L[cb, i] * bx - L[sb, i] * by
        r2y = L[sb, i] * bx + L[cb, i] * by
        dx = (L[pxb, i] + r2x) - (L[pxa, i] + r1x)
        dy = (L[pyb, i] + r2y) - (L[pya, i] + r1y)
        dist = math.sqrt(dx * dx + dy * dy)
        inv = 0.0 if dist == 0.0 else 1.0 / dist  # chipmunk: n = 0 at dist 0
        nx, ny = dx * inv, dy * inv
        c1 = r1x * ny - r1y * nx
        c2 = r2x * ny - r2y * nx
        L[s0 + NX, i], L[s0 + NY, i], L[s0 + C1, i], L[s0 + C2, i] = nx, ny, c1, c2
        L[s0 + NMASS, i] = ma + mb + c1 * c1 * ja + c2 * c2 * jb
        L[s0 + VCOEF, i] = dist
        L[s0 + TARGET, i] = dx
    if kd == SPRING:  # the force goes to TARGET until the impulse is applied
        for i in range(L.shape[1]):
            h, k = L[o_h, i], L[s0 + NMASS, i]
            L[s0 + TARGET, i] = (L[rs, i] - L[s0 + VCOEF, i]) * L[st, i]
            L[s0 + VCOEF, i] = 1.0 - 1.0 / (1.0 + L[dm, i] * h * k)
    elif kd == TYRE:
        for i in range(L.shape[1]):
            h, k = L[o_h, i], L[s0 + NMASS, i]
            was = L[ct, i]
            f = k_tyre * (L[rs, i] - L[s0 + VCOEF, i])
            now = 1.0 if f > lift else 0.0
            L[ld, i] = 1.0 if now > was else 0.0
            L[ct, i] = now
            L[s0 + TARGET, i] = f if now > 0.0 else lift
            L[s0 + VCOEF, i] = _one_minus_exp(c_tyre * was * h * k)  # the damper before a switch
    else:  # LATERAL, after its tyre: on landing its rest length is the gap now
        for i in range(L.shape[1]):
            h, k = L[o_h, i], L[s0 + NMASS, i]
            on = L[ct, i]
            L[rs, i] = abs(L[s0 + TARGET, i]) if L[ld, i] > 0.0 else L[rs, i]
            L[s0 + TARGET, i] = (L[rs, i] - L[s0 + VCOEF, i]) * k_lat * on
            L[s0 + VCOEF, i] = _one_minus_exp(c_lat * on * h * k)
    # the spring impulse f h; 1 / k and the damper's target for the sweeps
    vxa, vya, vxb, vyb = VX * n_body + a, VY * n_body + a, VX * n_body + bb, VY * n_body + bb
    for i in range(L.shape[1]):
        j = L[s0 + TARGET, i] * L[o_h, i]
        nx, ny, c1, c2 = L[s0 + NX, i], L[s0 + NY, i], L[s0 + C1, i], L[s0 + C2, i]
        L[s0 + NMASS, i] = 1.0 / L[s0 + NMASS, i]
        L[s0 + TARGET, i] = 0.0
        L[vxa, i] -= j * nx * ma
        L[vya, i] -= j * ny * ma
        L[wa, i] -= j * c1 * ja
        L[vxb, i] += j * nx * mb
        L[vyb, i] += j * ny * mb
        L[wb, i] += j * c2 * jb


@nb.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _damp(L, s0, kd, a, bb, m_inv, i_inv, n_body):  # pragma: no cover - compiled
    """One Gauss-Seidel sweep of an element's damper over the chunk (chipmunk's
    ``applyImpulse``; its scratch rows from ``s0``)."""
    ma, mb, ja, jb = m_inv[a], m_inv[bb], i_inv[a], i_inv[bb]
    wa, wb = W * n_body + a, W * n_body + bb
    if kd == ROTARY:
        for i in range(L.shape[1]):
            wr = L[wa, i] - L[wb, i]
            wd = (L[s0 + TARGET, i] - wr) * L[s0 + VCOEF, i]
            L[s0 + TARGET, i] = wr + wd
            j = wd * L[s0 + NMASS, i]
            L[wa, i] += j * ja
            L[wb, i] -= j * jb
        return
    vxa, vya, vxb, vyb = VX * n_body + a, VY * n_body + a, VX * n_body + bb, VY * n_body + bb
    for i in range(L.shape[1]):
        nx, ny, c1, c2 = L[s0 + NX, i], L[s0 + NY, i], L[s0 + C1, i], L[s0 + C2, i]
        # (v_b + w_b x r2 - v_a - w_a x r1) . n, with w x r . n = w (r x n)
        vrn = (L[vxb, i] - L[vxa, i]) * nx + (L[vyb, i] - L[vya, i]) * ny
        vrn += L[wb, i] * c2 - L[wa, i] * c1
        vd = (L[s0 + TARGET, i] - vrn) * L[s0 + VCOEF, i]
        L[s0 + TARGET, i] = vrn + vd
        j = vd * L[s0 + NMASS, i]
        L[vxa, i] -= j * nx * ma
        L[vya, i] -= j * ny * ma
        L[wa, i] -= j * c1 * ja
        L[vxb, i] += j * nx * mb
        L[vyb, i] += j * ny * mb
        L[wb, i] += j * c2 * jb


@nb.njit(cache=True, nogil=True, error_model="numpy")
def bushing_motion_kernel(S, arm, sign, anchor_b, anchor_a, q, v):  # pragma: no cover
    """(q, v) (N, P, 3) of the P pivots of every car: the arm's inner end relative to the
    chassis (body 0), in the chassis frame (axial: outboard positive; radial: up; the arm's
    rotation, wheel-up positive; the right side mirrored), as ``HalfCar.bushing_motion``."""
    for p in range(arm.shape[0]):
        k, s = arm[p], sign[p]
        ax, ay = anchor_b[p, 0], anchor_b[p, 1]
        a0x, a0y = anchor_a[p, 0], anchor_a[p, 1]
        for b in range(S.shape[2]):
            cos, sin = S[COS, 0, b], S[SIN, 0, b]
            cx, cy, w = S[PX, 0, b], S[PY, 0, b], S[W, 0, b]
            ca, sa, wa = S[COS, k, b], S[SIN, k, b], S[W, k, b]
            rx, ry = ca * ax - sa * ay, sa * ax + ca * ay
            px, py = S[PX, k, b] + rx, S[PY, k, b] + ry
            vx = S[VX, k, b] - wa * ry - (S[VX, 0, b] - w * (py - cy))
            vy = S[VY, k, b] + wa * rx - (S[VY, 0, b] + w * (px - cx))
            dx = px - (cx + cos * a0x - sin * a0y)
            dy = py - (cy + sin * a0x + cos * a0y)
            q[b, p, 0] = s * (cos * dx + sin * dy)
            q[b, p, 1] = -sin * dx + cos * dy
            q[b, p, 2] = s * (S[ANG, k, b] - S[ANG, 0, b])
            v[b, p, 0] = s * (cos * vx + sin * vy)
            v[b, p, 1] = -sin * vx + cos * vy
            v[b, p, 2] = s * (wa - w)


def zero_state(n: int) -> np.ndarray:
    """(8, 9, n) state rows, all zero but the rotations' cosines."""
    S = np.zeros((N_ROWS, 9, n))
    S[COS] = 1.0
    return S
