"""The coupled elastic law of the planar reference: a strain energy, its force and its tangent.

Coordinates q = (u_a axial m, u_r radial m, theta rotation rad). The elastic force is the
gradient of one strain energy, so the tangent stiffness is symmetric (Maxwell-Betti) and the
element stores, never creates, energy::

    W = 1/2 k_a u_a^2 (1 + gamma_a m(u_r))            radial deflection stiffens axial shear
      + 1/2 k_r u_r^2 + k_r e(u_r) phi(theta)          F_r falls, then rises, under rotation
      + 1/2 k_t theta^2
      + sum_i k_i q_i^4 / (4 L_i^2)                    hardening (cubic force), per coordinate

    phi(theta) = d (s^4 - 2 s^2),  s = theta / theta_m   (phi = -d at theta_m, 0 at sqrt(2) theta_m)
    e(u) = u_c^2 ln cosh(u / u_c)                        (u^2/2 for |u| << u_c, ~u_c |u| beyond)
    m(u) = 2 e(u) / u_c^2                                (~(u/u_c)^2, then ~2 |u| / u_c)

At a held radial deflection the radial force F_r = k_r u_r + k_r e'(u_r) phi(theta) first falls
(by d k_r e'(u_r) at theta_m) and then rises, the shape Kadlowec, Wineman & Hulbert (Acta
Mechanica 163, 2003) measured under superposed torsion. The saturation e(u) keeps the coupling
from growing as u_r^2, so the energy stays convex over the whole stroke (tested on a grid).

Reciprocity decides the rest: dM/du_r = dF_r/dtheta for any elastic element, so the secant
rotational stiffness M/theta rises with radial preload exactly where F_r rises with rotation
(|theta| > theta_m) and falls where F_r falls (|theta| < theta_m). A conservative bushing
cannot have both "F_r falls under small rotation" and "preload stiffens small rotations".
"""

from __future__ import annotations

import numba as nb
import numpy as np

# indices into the elastic parameter vector
E_KA, E_KR, E_KT, E_GA, E_D, E_TM, E_UC, E_LA, E_LR, E_LT = range(10)
N_EPAR = 10


@nb.njit(cache=True, inline="always")
def _e_terms(u: float, uc: float) -> tuple[float, float, float]:
    """e(u), e'(u), e''(u) for e = uc^2 ln cosh(u / uc), overflow-free."""
    z = u / uc
    az = abs(z)
    lncosh = az + np.log1p(np.exp(-2.0 * az)) - np.log(2.0)
    th = np.tanh(z)
    return uc * uc * lncosh, uc * th, 1.0 - th * th


@nb.njit(cache=True)
def elastic_force(ua: float, ur: float, th: float, p: np.ndarray, out: np.ndarray) -> None:
    """Write (F_a N, F_r N, M N m) = grad W at (ua, ur, th) into ``out`` (3,)."""
    ka, kr, kt, ga, d, tm, uc = p[E_KA], p[E_KR], p[E_KT], p[E_GA], p[E_D], p[E_TM], p[E_UC]
    e, e1, _ = _e_terms(ur, uc)
    s = th / tm
    phi = d * (s**4 - 2.0 * s * s)
    phi1 = d * (4.0 * s**3 - 4.0 * s) / tm
    m = 2.0 * e / (uc * uc)
    m1 = 2.0 * e1 / (uc * uc)
    fa = ka * ua * (1.0 + ga * m)
    fr = 0.5 * ka * ga * ua * ua * m1 + kr * ur + kr * e1 * phi
    mo = kr * e * phi1 + kt * th
    if p[E_LA] > 0.0:
        fa += ka * ua**3 / p[E_LA] ** 2
    if p[E_LR] > 0.0:
        fr += kr * ur**3 / p[E_LR] ** 2
    if p[E_LT] > 0.0:
        mo += kt * th**3 / p[E_LT] ** 2
    out[0] = fa
    out[1] = fr
    out[2] = mo


def tangent_stiffness(q: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The 3x3 tangent stiffness dF/dq at ``q`` (3,): N/m, N/rad (= N m/m), N m/rad."""
    ua, ur, th = (float(c) for c in q)
    ka, kr, kt, ga, d, tm, uc = (float(p[i]) for i in range(7))
    e, e1, e2 = _e_terms(ur, uc)
    s = th / tm
    phi = d * (s**4 - 2.0 * s * s)
    phi1 = d * (4.0 * s**3 - 4.0 * s) / tm
    phi2 = d * (12.0 * s * s - 4.0) / tm**2
    m, m1, m2 = (2.0 * t / (uc * uc) for t in (e, e1, e2))
    k = np.empty((3, 3))
    k[0, 0] = ka * (1.0 + ga * m)
    k[0, 1] = k[1, 0] = ka * ga * ua * m1
    k[0, 2] = k[2, 0] = 0.0
    k[1, 1] = 0.5 * ka * ga * ua * ua * m2 + kr + kr * e2 * phi
    k[1, 2] = k[2, 1] = kr * e1 * phi1
    k[2, 2] = kr * e * phi2 + kt
    for i, (kk, li, qi) in enumerate(((ka, p[E_LA], ua), (kr, p[E_LR], ur), (kt, p[E_LT], th))):
        if li > 0:
            k[i, i] += 3.0 * kk * qi * qi / li**2
    return k
