"""The arithmetic of ``HalfCarBatch``: chipmunk's step for the half car's bodies and elements,
over many cars at once (the sub-steps compiled per element table by ``halfcar_batch_lanes``,
with the loop over cars innermost so that it vectorises), and the bushings' motion.

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
The tyres' dampers are chipmunk's own, v_coef = 1 - exp(-c h k), as in the pymunk car (exp by
its polynomial to x^6, which vectorises where libm's does not: 6e-10 relative at x = 0.12, the
lateral tyre's here; 2e-7 at x = 0.3).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

PX, PY, ANG, VX, VY, W, COS, SIN = range(8)
N_ROWS = 8
SPRING, ROTARY, TYRE, LATERAL = range(4)  # element kinds


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


@nb.njit(cache=True, nogil=True, error_model="numpy")
def hold_kernel(
    forces, q, v, split, base, sign, rows, limits, rest, ok
):  # pragma: no cover - compiled
    """Each column's pivot forces ``forces`` (N, P, 3) at (q, v): ``ok`` (N,) where every
    one is within ``limits`` (3,) (False where NaN), and there the remainder
    H = F - (k_in q + c_in v) (``split`` (N, P, 2, 3)) held in the sub-steps' springs: rows
    ``rows`` (P * 3,) of ``rest`` get ``base + sign H / k_in`` (``base`` (3,), ``sign``
    (P, 3)); a column not ok keeps its rest lengths."""
    n_p = forces.shape[1]
    for b in range(forces.shape[0]):
        good = True
        for i in range(n_p):
            for c in range(3):
                if not abs(forces[b, i, c]) <= limits[c]:
                    good = False
        ok[b] = good
        if good:
            for i in range(n_p):
                for c in range(3):
                    k_in = split[b, i, 0, c]
                    held = forces[b, i, c] - (k_in * q[b, i, c] + split[b, i, 1, c] * v[b, i, c])
                    rest[rows[3 * i + c], b] = base[c] + sign[i, c] * held / k_in


@nb.njit(cache=True, nogil=True, error_model="numpy")
def bounds_kernel(
    body, roll, travel, q, max_body, max_roll, max_travel, max_deflection, bad
):  # pragma: no cover - compiled
    """``bad`` (N,): a column with a body coordinate ``body`` (K, N) or the roll not finite or
    beyond ``max_body`` / ``max_roll``, a wheel's ``travel`` (S, N) beyond ``max_travel``, a
    pivot's deflection ``q`` (N, P, 3) not finite or (its two translations) beyond
    ``max_deflection``."""
    for b in range(bad.shape[0]):
        out = not (math.isfinite(roll[b]) and abs(roll[b]) <= max_roll)
        for k in range(body.shape[0]):
            x = body[k, b]
            out |= not (math.isfinite(x) and abs(x) <= max_body)
        for s in range(travel.shape[0]):
            out |= abs(travel[s, b]) > max_travel
        for i in range(q.shape[1]):
            for c in range(3):
                x = q[b, i, c]
                out |= not math.isfinite(x)
                if c < 2:
                    out |= abs(x) > max_deflection
        bad[b] = out
