"""Pieces of the Bouc-Wen step: table look-ups, phi functions, the dense output at a reversal.

Inlined into the lane pass (``boucwen_pass``); the method is in docs/boucwen-integration.md.
``segment_index``, ``hermite_values`` and ``phis_half_and_full`` are branch-free arithmetic
(selects, no calls) so the loops over lanes vectorise; the table reads between them are
gathers, which LLVM does not vectorise on this machine's CPU (AMD), so the pass does them in
short scalar loops of their own. ``locate``, ``locate_zero_crossing`` and ``inverse`` run per
lane in the scalar hand-over loop (a reversal is about one trial step in eight).

Table layout (``tabs``, flat float64): a segment of nodes i = 0..imax at lambda = l0 + i / idl
holds xi_i at ``off + 2 i`` and the slope dxi/dlambda times the node spacing at
``off + 2 i + 1``. Each block has a segment below lambda = 0 (l0 < 0, ending at 0) and one above
(starting at 0); both hold the node lambda = 0. The reflection lambda_r(lambda) (xi(lambda_r) =
-xi(lambda), the lambda a reversal continues from) is stored the same way ``shift`` entries
further on.
"""

from __future__ import annotations

import math

import numba as nb

from bushenv.models.fastpow import exp_

SMALL_Z = 0.5  # |z| below which the phi functions are summed as series (cancellation)
N_SERIES = 14  # series terms: truncation below 1e-17 at |z| = SMALL_Z
INV_FACT = tuple(1.0 / math.factorial(i) for i in range(N_SERIES + 4))
LOCATE_ITERATIONS = 8  # Newton steps from the parabola's root, at most
ZERO_ITERATIONS = 8  # a z = 0 crossing is converged: lambda is then set to 0 exactly
LOCATE_TOL = 1e-7  # in fractions of the step: r at the reversal is off by O(tol^2)


@nb.njit(cache=True, inline="always", error_model="numpy")
def locate_tolerance(rtol):  # pragma: no cover - compiled
    """How closely a reversal is located, in fractions of the step: rtol itself within [1e-7,
    1e-3]. At the default rtol one Newton step mostly suffices (one exponential); a converged
    location changes no error of the accuracy table, and the error keeps shrinking with rtol
    (with one step always, it stopped at ~6e-5 of the peak for rtol <= 7e-6)."""
    return min(1e-3, max(LOCATE_TOL, rtol))


INVERSE_ITERATIONS = 6


@nb.njit(cache=True, inline="always", error_model="numpy")
def segment_index(lam, off_d, l0_d, idl_d, im_d, off_u, idl_u, im_u):  # pragma: no cover
    """Where lambda falls in a block's table: (position of the node pair in ``tabs``, as a
    float; fraction t in [0, 1] between them; 1 / spacing). Arithmetic only (vectorises);
    the ends clamp, NaN goes to the first node."""
    neg = lam < 0.0
    off = off_d if neg else off_u
    l0 = l0_d if neg else 0.0
    idl = idl_d if neg else idl_u
    imax = im_d if neg else im_u
    u = (lam - l0) * idl
    u = 0.0 if not (u > 0.0) else u
    u = imax if u > imax else u
    fi = float(int(u))  # u >= 0: truncation is floor (and vectorises, math.floor does not)
    fi = imax - 1.0 if fi > imax - 1.0 else fi
    return off + 2.0 * fi, u - fi, idl


@nb.njit(cache=True, inline="always", error_model="numpy")
def hermite_values(p0, m0, p1, m1, t, idl):  # pragma: no cover - compiled
    """Cubic Hermite between nodes (p0, m0) and (p1, m1) at t: xi and dxi/dlambda."""
    c2 = 3.0 * (p1 - p0) - 2.0 * m0 - m1
    c3 = 2.0 * (p0 - p1) + m0 + m1
    return p0 + t * (m0 + t * (c2 + t * c3)), (m0 + t * (2.0 * c2 + 3.0 * t * c3)) * idl


@nb.njit(cache=True, inline="always", error_model="numpy")
def hermite(tabs, lam, off_d, l0_d, idl_d, im_d, off_u, idl_u, im_u):  # pragma: no cover
    """xi(lambda) and dxi/dlambda from a block's table (cubic Hermite; clamped at the ends)."""
    k, t, idl = segment_index(lam, off_d, l0_d, idl_d, im_d, off_u, idl_u, im_u)
    i = int(k)
    return hermite_values(tabs[i], tabs[i + 1], tabs[i + 2], tabs[i + 3], t, idl)


@nb.njit(cache=True, inline="always", error_model="numpy")
def _phi3_series(z):  # pragma: no cover - compiled
    """phi_3(z) = sum_j z^j / (j + 3)!, N_SERIES terms by Horner."""
    acc = 0.0
    for j in range(N_SERIES - 1, -1, -1):
        acc = acc * z + INV_FACT[j + 3]
    return acc


@nb.njit(cache=True, inline="always", error_model="numpy")
def _closed(z, e):  # pragma: no cover - compiled
    """phi_1..3 of z from e = e^z: phi_1 = (e - 1) / z, phi_(k+1) = (phi_k - 1/k!) / z (this
    recursion cancels for small |z|)."""
    iz = 1.0 / z
    q1 = (e - 1.0) * iz
    q2 = (q1 - 1.0) * iz
    return q1, q2, (q2 - 0.5) * iz


@nb.njit(cache=True, inline="always", error_model="numpy")
def _series(z):  # pragma: no cover - compiled
    """phi_1..3 of small z: phi_3 summed, phi_2 = 1/2 + z phi_3, phi_1 = 1 + z phi_2 (stable)."""
    p3 = _phi3_series(z)
    p2 = 0.5 + z * p3
    return 1.0 + z * p2, p2, p3


@nb.njit(cache=True, inline="always", error_model="numpy")
def _phis_from(z, e):  # pragma: no cover - compiled
    """phi_1..3 of z given e = e^z, either form as |z| asks; both are computed and one is
    selected, so that a loop over lanes vectorises."""
    big = abs(z) >= SMALL_Z
    q1, q2, q3 = _closed(z if big else 1.0, e)
    s1, s2, s3 = _series(0.0 if big else z)
    return (q1 if big else s1), (q2 if big else s2), (q3 if big else s3)


@nb.njit(cache=True, inline="always", error_model="numpy")
def phis_half_and_full(z, form):  # pragma: no cover - compiled
    """phi_1..3 at z / 2 and at z, and e^(z/2), e^z, from one exponential. ``form``: 1 if
    every lane of the loop has |z/2| >= SMALL_Z (closed forms only), 2 if every lane has |z| <
    SMALL_Z (series only), 0 otherwise (both, selected per lane). The values do not depend on
    ``form`` (the same expressions are selected), only the work does."""
    eh = exp_(0.5 * z)
    ef = eh * eh
    if form == 1:
        a1, a2, a3 = _closed(0.5 * z, eh)
        b1, b2, b3 = _closed(z, ef)
    elif form == 2:
        a1, a2, a3 = _series(0.5 * z)
        b1, b2, b3 = _series(z)
    else:
        a1, a2, a3 = _phis_from(0.5 * z, eh)
        b1, b2, b3 = _phis_from(z, ef)
    return a1, a2, a3, b1, b2, b3, eh, ef


@nb.njit(cache=True, error_model="numpy")
def dense(theta, ya, lr, hh, n0, d1, d2):  # pragma: no cover - compiled
    """The step's solution at theta in [0, 1] of it (variation of constants with N quadratic
    through its values at 0, 1/2, 1; ``d1``, ``d2`` its divided differences): y, y' and y''."""
    z = -lr * hh * theta
    e = math.exp(z)
    if abs(z) >= SMALL_Z:  # scalar code: branch instead of computing both forms
        iz = 1.0 / z
        p1 = (e - 1.0) * iz
        p2 = (p1 - 1.0) * iz
        p3 = (p2 - 0.5) * iz
    else:
        p3 = _phi3_series(z)
        p2 = 0.5 + z * p3
        p1 = 1.0 + z * p2
    th2 = theta * theta
    y = e * ya + hh * (
        n0 * theta * p1 + d1 * th2 * p2 + d2 * (2.0 * th2 * theta * p3 - 0.5 * th2 * p2)
    )
    nv = n0 + d1 * theta + d2 * theta * (theta - 0.5)
    dn = (d1 + d2 * (2.0 * theta - 0.5)) / hh
    dy = -lr * y + nv
    return y, dy, -lr * dy + dn


@nb.njit(cache=True, error_model="numpy")
def locate(ya, lr, hh, n0, d1, d2, s, g0, g1, g2, first, ua, du_dt, tol):  # pragma: no cover
    """Where in the step (fraction theta) the relative velocity d = u - y' changes sign, and y
    there. s d was g0, g1, g2 at theta = 0, 1/2, 1, turning negative in the ``first`` half or
    the second; ``ua``, ``du_dt``: u at the step's start and its slope in time; ``tol``: in
    fractions of the step (``locate_tolerance``).

    Start: the root of the parabola through the three values; then Newton on s d(theta) of
    the dense output, kept inside the bracket by bisection.
    """
    lo, hi = (0.0, 0.5) if first else (0.5, 1.0)
    # parabola g(theta) = g0 + b theta + c theta^2 through the three values
    c = 2.0 * (g2 - 2.0 * g1 + g0)
    b = g2 - g0 - c
    th = 0.5 * (lo + hi)
    if c != 0.0:
        disc = b * b - 4.0 * c * g0
        if disc >= 0.0:
            q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
            for r in (q / c, g0 / q if q != 0.0 else -1.0):
                if lo < r < hi:
                    th = r
    elif b != 0.0 and lo < -g0 / b < hi:
        th = -g0 / b
    y = ya
    for _ in range(LOCATE_ITERATIONS):
        y, dy, d2y = dense(th, ya, lr, hh, n0, d1, d2)
        g = s * (ua + du_dt * hh * th - dy)
        if g > 0.0:
            lo = th
        else:
            hi = th
        dg = s * hh * (du_dt - d2y)
        tn = th - g / dg if dg != 0.0 else 0.5 * (lo + hi)
        if not (lo < tn < hi):
            tn = 0.5 * (lo + hi)
        if abs(tn - th) <= tol or hi - lo <= tol:
            return tn, y + dy * hh * (tn - th)
        th = tn
    y, _, _ = dense(th, ya, lr, hh, n0, d1, d2)  # the stiff transient: y' changes fast
    return th, y


@nb.njit(cache=True, error_model="numpy")
def locate_zero_crossing(ya, lr, hh, n0, d1, d2, s, aw, la, l_end, ua, du_dt):  # pragma: no cover
    """Where in the step (fraction theta) lambda, rising from ``la`` < 0 to ``l_end`` > 0,
    passes 0 (z passes 0, where |z|^n has its cusp), and y there: Newton on lambda(theta) =
    la + s aw (integral of u - (y - ya)) of the dense output, kept inside [0, 1]."""
    lo, hi = 0.0, 1.0
    th = -la / (l_end - la)
    y = ya
    for _ in range(ZERO_ITERATIONS):
        y, dy, _ = dense(th, ya, lr, hh, n0, d1, d2)
        tt = th * hh
        lam = la + s * aw * (tt * (ua + 0.5 * du_dt * tt) - (y - ya))
        if lam < 0.0:
            lo = th
        else:
            hi = th
        dl = s * aw * hh * (ua + du_dt * tt - dy)
        tn = th - lam / dl if dl != 0.0 else 0.5 * (lo + hi)
        if not (lo < tn < hi):
            tn = 0.5 * (lo + hi)
        if abs(tn - th) <= LOCATE_TOL or hi - lo <= LOCATE_TOL:
            return tn, y + dy * hh * (tn - th)
        th = tn
    y, _, _ = dense(th, ya, lr, hh, n0, d1, d2)  # the stiff transient: y' changes fast
    return th, y


@nb.njit(cache=True, error_model="numpy")
def inverse(tabs, target, off_d, l0_d, idl_d, im_d, off_u, idl_u, im_u):  # pragma: no cover
    """lambda with xi(lambda) = target on a block's table (the ends clamp)."""
    neg = target < 0.0
    off = off_d if neg else off_u
    l0 = l0_d if neg else 0.0
    idl = idl_d if neg else idl_u
    imax = int(im_d if neg else im_u)
    if target <= tabs[int(off)]:
        return l0
    if target >= tabs[int(off) + 2 * imax]:
        return l0 + imax / idl
    lo = 0
    hi = imax
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if tabs[int(off) + 2 * mid] <= target:
            lo = mid
        else:
            hi = mid
    k = int(off) + 2 * lo
    t, _, _ = hermite_solve(
        tabs[k], tabs[k + 1], tabs[k + 2], tabs[k + 3], target, INVERSE_ITERATIONS, 0.0
    )
    return l0 + (lo + t) / idl


@nb.njit(cache=True, inline="always", error_model="numpy")
def hermite_solve(p0, m0, p1, m1, target, iterations, tol):  # pragma: no cover - compiled
    """t in [0, 1] where the cubic Hermite p0 + t (m0 + t (c2 + t c3)) (ends p0, p1, slopes
    m0, m1 times the spacing) equals ``target``: Newton safeguarded by bisection, at most
    ``iterations`` steps, stopping once a step moves t by less than ``tol``. Returns (t, c2, c3)."""
    c2 = 3.0 * (p1 - p0) - 2.0 * m0 - m1
    c3 = 2.0 * (p0 - p1) + m0 + m1
    t = (target - p0) / (p1 - p0) if p1 > p0 else 0.0
    a = 0.0
    b = 1.0
    for _ in range(iterations):
        f = p0 + t * (m0 + t * (c2 + t * c3)) - target
        if f > 0.0:
            b = t
        else:
            a = t
        df = m0 + t * (2.0 * c2 + 3.0 * t * c3)
        tn = t - f / df if df > 0.0 else 0.5 * (a + b)
        tn = tn if a <= tn <= b else 0.5 * (a + b)
        if abs(tn - t) < tol:
            t = tn
            break
        t = tn
    return t, c2, c3
