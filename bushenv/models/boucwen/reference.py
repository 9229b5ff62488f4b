"""The plain reference for the Bouc-Wen kernel: fixed-step RK4 on seed 002 eqs. 1-4 as printed.

Obviously right and slow (libm pow, both blocks together, a fixed number of equal sub-steps per
sample); ``boucwen_accuracy`` measures the production kernel against it, never a hot path.
"""

from __future__ import annotations

import math

import numba as nb

JIT = dict(cache=True, fastmath=False, nogil=True, error_model="numpy")


@nb.njit(**JIT)
def _printed_rhs(p, b, xx, u, y, w, z1, z2):  # pragma: no cover - compiled
    c0 = p[0, b]
    k0 = p[1, b]
    c1 = p[2, b]
    k1 = p[3, b]
    c2 = p[4, b]
    k2 = p[5, b]
    dy = (c1 * u + k1 * (xx - y) - k0 * y + p[14, b] * z1) / c1  # eq. 3
    dw = (c2 * u + k2 * (xx - w) + p[15, b] * z2) / (c0 + c2)  # eq. 4
    d1 = u - dy
    d2 = u - dw
    s1 = math.copysign(1.0, d1) * math.copysign(1.0, z1) if d1 != 0.0 and z1 != 0.0 else 0.0
    s2 = math.copysign(1.0, d2) * math.copysign(1.0, z2) if d2 != 0.0 and z2 != 0.0 else 0.0
    dz1 = d1 * (p[6, b] - (p[10, b] + p[8, b] * s1) * abs(z1) ** p[12, b])  # eq. 1
    dz2 = d2 * (p[7, b] - (p[11, b] + p[9, b] * s2) * abs(z2) ** p[13, b])  # eq. 2
    return dy, dw, dz1, dz2


@nb.njit(**JIT)
def boucwen_fixed_step(x, v, p, dt, n_sub, out):  # pragma: no cover - compiled
    """Reference free run from rest: RK4 with ``n_sub`` equal sub-steps per sample.

    x, v, out (T, B), p (16, B). Converged for large ``n_sub`` (checked in the tests by doubling
    it); used to measure the production kernel's error, never in a hot path.
    """
    T, B = x.shape
    h = dt / n_sub
    for b in range(B):
        y = 0.0
        w = 0.0
        z1 = 0.0
        z2 = 0.0
        x0 = 0.0
        u0 = 0.0
        for t in range(T):
            x1 = x[t, b]
            u1 = v[t, b]
            for i in range(n_sub):
                sa = i / n_sub
                sm = (i + 0.5) / n_sub
                se = (i + 1.0) / n_sub
                xa = x0 + sa * (x1 - x0)
                ua = u0 + sa * (u1 - u0)
                xm = x0 + sm * (x1 - x0)
                um = u0 + sm * (u1 - u0)
                xe = x0 + se * (x1 - x0)
                ue = u0 + se * (u1 - u0)
                a1, a2, a3, a4 = _printed_rhs(p, b, xa, ua, y, w, z1, z2)
                hh = 0.5 * h
                b1, b2, b3, b4 = _printed_rhs(
                    p, b, xm, um, y + hh * a1, w + hh * a2, z1 + hh * a3, z2 + hh * a4
                )
                c1, c2, c3, c4 = _printed_rhs(
                    p, b, xm, um, y + hh * b1, w + hh * b2, z1 + hh * b3, z2 + hh * b4
                )
                d1, d2, d3, d4 = _printed_rhs(
                    p, b, xe, ue, y + h * c1, w + h * c2, z1 + h * c3, z2 + h * c4
                )
                y += h / 6.0 * (a1 + 2.0 * b1 + 2.0 * c1 + d1)
                w += h / 6.0 * (a2 + 2.0 * b2 + 2.0 * c2 + d2)
                z1 += h / 6.0 * (a3 + 2.0 * b3 + 2.0 * c3 + d3)
                z2 += h / 6.0 * (a4 + 2.0 * b4 + 2.0 * c4 + d4)
            dw = (p[4, b] * u1 + p[5, b] * (x1 - w) + p[15, b] * z2) / (p[0, b] + p[4, b])
            out[t, b] = p[1, b] * y + p[0, b] * dw  # eq. 5
            x0 = x1
            u0 = u1
