"""One trial step of the Bouc-Wen lanes: the tile scratch layout and the vectorised phases.

The method is in ``boucwen_kernels`` (its docstring) and docs/boucwen-integration.md; this is
its inner loop. Each phase is a loop over the lanes of a tile that LLVM vectorises (no calls,
no conditional loads: every value is loaded, then selected); between the phases, the table
reads run as short scalar loops (``_read``), being gathers LLVM does not vectorise on this
machine's CPU (AMD). A lane reads and writes only its own entries of the scratch, with no
fused multiply-add, so its bits do not depend on the tile it sits in.
"""

from __future__ import annotations

import math

import numba as nb

from bushenv.models.boucwen.step import (
    SMALL_Z,
    hermite_values,
    phis_half_and_full,
    segment_index,
)
from bushenv.models.boucwen.tables import BC_ROWS

# error_model="numpy": no zero-division guard branches, so the loops over lanes vectorise.
JIT = dict(cache=True, fastmath=False, nogil=True, error_model="numpy")

MIN_STEP_FRACTION = 1e-14  # of dt
LAST_FRACTION = 0.6  # a step reaching this far into the rest of the sample takes all of it
LAST_REJECT = 0.55  # a rejected step is retried with at most this much of the rest
DIP = 1e-3  # a reversal and its return within one step, this shallow, are ignored
TOUCH_STEP = 1.0 / 64.0  # of dt: the step taken through a touch of d = 0 (see _finish)
BW_TILE = 16  # lanes per tile: two 8-double AVX-512 vectors

# The tile scratch L is flat: row r of lane j is L[r * BW_TILE + j]. Offsets known at compile
# time let LLVM tell the rows apart and vectorise over lanes. The first len(BC_ROWS) rows are
# the block's constants (``boucwen_tables.BC_ROWS``), copied from ``bc``.
_ROWS = BC_ROWS + tuple(
    (
        # lane state, the sample's input, flags
        "Y LB S H TAU NST X0 DX U0 DU X1 U1 ACT CODE FAIL EVT OUTV FLIPT "
        # what locating a reversal needs
        "YA HH LR N0 D1 D2 G0 G1 G2 FAC F2 UA L2 "
        # the step between the pass's phases
        "HS LAST XA XM XB UM UB DUM DUB F0 E1 E2 WA0 WA1 WA2 WB0 WB1 WB2 R1 R2 Y1 Y2 F1 "
        # table reads: position, fraction, 1 / spacing and the four values, three slots
        "K0 T0 I0 P00 P01 P02 P03 K1 T1 I1 P10 P11 P12 P13 K2 T2 I2 P20 P21 P22 P23"
    ).split()
)
_N_ROWS = len(_ROWS)
_N_BC = len(BC_ROWS)
(
    _LAM, _KX, _CU, _AAW, _AAA, _AW, _TOL, _WGT, _WJ, _FOUT,
    _OFFD, _L0D, _IDLD, _IMD, _OFFU, _IDLU, _IMU, _LTOP, _FTOP, _OK, _ZW, _SHIFT, _CUSP, _RTOL,
    _Y, _LB, _S, _H, _TAU, _NST, _X0, _DX, _U0, _DU, _X1, _U1,
    _ACT, _CODE, _FAIL, _EVT, _OUTV, _FLIPT,
    _YA, _HH, _LR, _N0, _D1, _D2, _G0, _G1, _G2, _FAC, _F2, _UA, _L2,
    _HS, _LAST, _XA, _XM, _XB, _UM, _UB, _DUM, _DUB, _F0, _E1, _E2,
    _WA0, _WA1, _WA2, _WB0, _WB1, _WB2, _R1, _R2, _Y1, _Y2, _F1,
    _K0, _T0, _I0, _P00, _P01, _P02, _P03,
    _K1, _T1, _I1, _P10, _P11, _P12, _P13,
    _K2, _T2, _I2, _P20, _P21, _P22, _P23,
) = (r * BW_TILE for r in range(_N_ROWS))  # fmt: skip


@nb.njit(cache=True, inline="always", error_model="numpy")
def _where(L, j, lam):  # pragma: no cover - compiled
    """Where lambda falls in lane j's table (``segment_index``)."""
    return segment_index(
        lam, L[_OFFD + j], L[_L0D + j], L[_IDLD + j], L[_IMD + j],
        L[_OFFU + j], L[_IDLU + j], L[_IMU + j],
    )  # fmt: skip


@nb.njit(cache=True, inline="always", error_model="numpy")
def _read(L, tabs, n, rk, rp):  # pragma: no cover - compiled
    """The table reads for lanes 0 <= j < n (a gather, scalar): positions in row ``rk``,
    values to rows rp .. rp + 3."""
    for j in range(n):
        k = int(L[rk + j])
        L[rp + j] = tabs[k]
        L[rp + BW_TILE + j] = tabs[k + 1]
        L[rp + 2 * BW_TILE + j] = tabs[k + 2]
        L[rp + 3 * BW_TILE + j] = tabs[k + 3]


@nb.njit(cache=True, inline="always", error_model="numpy")
def _f(L, j, p0, m0, p1, m1, t, idl, s, yy, xx, uu):  # pragma: no cover - compiled
    """f = y' on branch s from a table read (nodes p0, m0, p1, m1 at fraction t), and df/dy."""
    xi, dxi = hermite_values(p0, m0, p1, m1, t, idl)
    f = L[_CU + j] * uu + L[_KX + j] * xx - L[_LAM + j] * yy + s * L[_AAW + j] * xi
    return f, -L[_LAM + j] - L[_AAA + j] * dxi


@nb.njit(**JIT)
def _setup(L, n, dt, inv_dt):  # pragma: no cover - compiled
    """Phase 1: the step's size and inputs; where lambda at its start falls."""
    for j in range(n):
        h = L[_H + j]
        tau = L[_TAU + j]
        rem = dt - tau
        last = h >= LAST_FRACTION * rem
        hh = rem if last else h
        fa = tau * inv_dt
        fm = (tau + 0.5 * hh) * inv_dt
        fb = 1.0 if last else (tau + hh) * inv_dt
        x0 = L[_X0 + j]
        dx = L[_DX + j]
        u0 = L[_U0 + j]
        du = L[_DU + j]
        ua = u0 + du * fa
        um = u0 + du * fm
        ub = u0 + du * fb
        L[_HS + j] = hh
        L[_LAST + j] = 1.0 if last else 0.0
        L[_XA + j] = x0 + dx * fa
        L[_XM + j] = x0 + dx * fm
        L[_XB + j] = x0 + dx * fb
        L[_UA + j] = ua
        L[_UM + j] = um
        L[_UB + j] = ub
        L[_DUM + j] = 0.25 * hh * (ua + um)  # integral of u over the first half of the step
        L[_DUB + j] = 0.5 * hh * (ua + ub)
        k, t, idl = _where(L, j, L[_LB + j])
        L[_K0 + j] = k
        L[_T0 + j] = t
        L[_I0 + j] = idl


@nb.njit(**JIT)
def _start(L, n):  # pragma: no cover - compiled
    """Phase 2a: f and L = -df/dy at the step's start. Returns which forms of the phi
    functions the lanes need (``boucwen_step.phis_half_and_full``)."""
    n_small = 0
    n_big = 0
    for j in range(n):
        s = -1.0 if L[_S + j] < 0.0 else 1.0
        f0, j0 = _f(
            L, j, L[_P00 + j], L[_P01 + j], L[_P02 + j], L[_P03 + j], L[_T0 + j], L[_I0 + j],
            s, L[_Y + j], L[_XA + j], L[_UA + j],
        )  # fmt: skip
        zz = j0 * L[_HS + j]
        L[_F0 + j] = f0
        L[_LR + j] = -j0
        n_small += 1 if abs(zz) < SMALL_Z else 0
        n_big += 1 if abs(0.5 * zz) >= SMALL_Z else 0
    return 1 if n_big == n else (2 if n_small == n else 0)


@nb.njit(cache=True, inline="always", error_model="numpy")
def _guess_lane(L, j, form):  # pragma: no cover - compiled
    """Phase 2b for lane j: the exponential weights, the linearised solution as the first
    guess at theta = 1/2 and 1, and where its lambda falls."""
    y = L[_Y + j]
    la = L[_LB + j]
    s = -1.0 if L[_S + j] < 0.0 else 1.0
    hh = L[_HS + j]
    xa = L[_XA + j]
    ua = L[_UA + j]
    f0 = L[_F0 + j]
    lr = L[_LR + j]
    zz = -lr * hh
    q1, q2, q3, r1, r2, r3, e1, e2 = phis_half_and_full(zz, form)
    # weights of N at theta = 0, 1/2, 1 in y(1/2) (a) and y(1) (b): the integrals of
    # e^(-L h (c - theta)) times the quadratic Lagrange basis, via phi_k
    m0 = 0.5 * q1
    m1 = 0.25 * q2
    m2 = 0.25 * q3
    a0 = m0 - 3.0 * m1 + 2.0 * m2
    a1 = 4.0 * m1 - 4.0 * m2
    a2 = 2.0 * m2 - m1
    m2 = 2.0 * r3
    b0 = r1 - 3.0 * r2 + 2.0 * m2
    b1 = 4.0 * r2 - 4.0 * m2
    b2 = 2.0 * m2 - r2
    n0 = f0 + lr * y
    # the linearised problem (z' at its slope at the start) as the first guess
    aag = lr - L[_LAM + j]
    cu = L[_CU + j]
    kx = L[_KX + j]
    dum = L[_DUM + j]
    dub = L[_DUB + j]
    n1 = n0 + cu * (L[_UM + j] - ua) + kx * (L[_XM + j] - xa) + aag * dum
    n2 = n0 + cu * (L[_UB + j] - ua) + kx * (L[_XB + j] - xa) + aag * dub
    y1 = e1 * y + hh * (a0 * n0 + a1 * n1 + a2 * n2)
    y2 = e2 * y + hh * (b0 * n0 + b1 * n1 + b2 * n2)
    L[_N0 + j] = n0
    L[_E1 + j] = e1
    L[_E2 + j] = e2
    L[_WA0 + j] = a0
    L[_WA1 + j] = a1
    L[_WA2 + j] = a2
    L[_WB0 + j] = b0
    L[_WB1 + j] = b1
    L[_WB2 + j] = b2
    L[_R1 + j] = r1
    L[_R2 + j] = r2
    L[_Y1 + j] = y1
    L[_Y2 + j] = y2
    aw = s * L[_AW + j]
    k, t, idl = _where(L, j, la + aw * (dum - (y1 - y)))
    L[_K1 + j] = k
    L[_T1 + j] = t
    L[_I1 + j] = idl
    k, t, idl = _where(L, j, la + aw * (dub - (y2 - y)))
    L[_K2 + j] = k
    L[_T2 + j] = t
    L[_I2 + j] = idl


@nb.njit(**JIT)
def _guess(L, n, form):  # pragma: no cover - compiled
    """Phase 2b over the lanes, one loop per form so that each vectorises without the work
    of the other."""
    if form == 1:
        for j in range(n):
            _guess_lane(L, j, 1)
    elif form == 2:
        for j in range(n):
            _guess_lane(L, j, 2)
    else:
        for j in range(n):
            _guess_lane(L, j, 0)


@nb.njit(**JIT)
def _newton(L, n):  # pragma: no cover - compiled
    """Phase 3: one Newton step on the collocation equations; where the new lambda at the
    step's end falls. f at the new midpoint value is taken from its linearisation at the old
    one (second order in the Newton correction; a table read there changed nothing
    measurable); at the end it is read exactly, as the reversal test and eq. 5 need it."""
    for j in range(n):
        y = L[_Y + j]
        la = L[_LB + j]
        s = -1.0 if L[_S + j] < 0.0 else 1.0
        hh = L[_HS + j]
        lr = L[_LR + j]
        n0 = L[_N0 + j]
        y1 = L[_Y1 + j]
        y2 = L[_Y2 + j]
        f1, j1 = _f(
            L,
            j,
            L[_P10 + j],
            L[_P11 + j],
            L[_P12 + j],
            L[_P13 + j],
            L[_T1 + j],
            L[_I1 + j],
            s,
            y1,
            L[_XM + j],
            L[_UM + j],
        )
        f2, j2 = _f(
            L,
            j,
            L[_P20 + j],
            L[_P21 + j],
            L[_P22 + j],
            L[_P23 + j],
            L[_T2 + j],
            L[_I2 + j],
            s,
            y2,
            L[_XB + j],
            L[_UB + j],
        )
        n1 = f1 + lr * y1
        n2 = f2 + lr * y2
        a1 = L[_WA1 + j]
        a2 = L[_WA2 + j]
        b1 = L[_WB1 + j]
        b2 = L[_WB2 + j]
        g1 = hh * (j1 + lr)
        g2 = hh * (j2 + lr)
        res1 = y1 - L[_E1 + j] * y - hh * (L[_WA0 + j] * n0 + a1 * n1 + a2 * n2)
        res2 = y2 - L[_E2 + j] * y - hh * (L[_WB0 + j] * n0 + b1 * n1 + b2 * n2)
        k11 = 1.0 - a1 * g1
        k12 = -a2 * g2
        k21 = -b1 * g1
        k22 = 1.0 - b2 * g2
        idet = 1.0 / (k11 * k22 - k12 * k21)
        d1 = (k22 * res1 - k12 * res2) * idet
        d2 = (k11 * res2 - k21 * res1) * idet
        y2 = y2 - d2
        L[_Y1 + j] = y1 - d1
        L[_Y2 + j] = y2
        L[_F1 + j] = f1 - j1 * d1
        k, t, idl = _where(L, j, la + s * L[_AW + j] * (L[_DUB + j] - (y2 - y)))
        L[_K2 + j] = k
        L[_T2 + j] = t
        L[_I2 + j] = idl


@nb.njit(**JIT)
def _finish(L, n, dt, maxs):  # pragma: no cover - compiled
    """Phase 4: error estimate, reversal test, accept or reject (see ``_pass``)."""
    for j in range(n):
        act = L[_ACT + j] != 0.0
        y = L[_Y + j]
        la = L[_LB + j]
        s = -1.0 if L[_S + j] < 0.0 else 1.0
        h = L[_H + j]
        tau = L[_TAU + j]
        hh = L[_HS + j]
        last = L[_LAST + j] != 0.0
        lr = L[_LR + j]
        n0 = L[_N0 + j]
        y1 = L[_Y1 + j]
        y2 = L[_Y2 + j]
        xb = L[_XB + j]
        ua = L[_UA + j]
        um = L[_UM + j]
        ub = L[_UB + j]
        f1 = L[_F1 + j]
        f2, j2 = _f(
            L, j, L[_P20 + j], L[_P21 + j], L[_P22 + j], L[_P23 + j], L[_T2 + j], L[_I2 + j],
            s, y2, xb, ub,
        )  # fmt: skip
        n1 = f1 + lr * y1
        n2 = f2 + lr * y2
        r2 = L[_R2 + j]
        ylow = L[_E2 + j] * y + hh * ((L[_R1 + j] - r2) * n0 + r2 * n2)
        wgt = L[_WGT + j] * (1.0 + L[_WJ + j] * (abs(j2) - 1.0))
        err = abs(y2 - ylow) * wgt / L[_TOL + j]
        l2 = la + s * L[_AW + j] * (L[_DUB + j] - (y2 - y))
        finite = (abs(y2) < 1e300) & (err < 1e300) & (abs(l2) < 1e300)
        ok = act & finite & (err <= 1.0)
        fac = 0.9 / math.sqrt(max(err, 1e-12))
        fac = 4.0 if not (fac < 4.0) else fac
        fac = 0.2 if not (fac > 0.2) else fac
        fac = fac if finite else 0.2
        # reversal: d = u - f changes sign from the branch's direction to the other
        kx = L[_KX + j]
        xa = L[_XA + j]
        eps = 1e-11 * (
            abs(ua) + abs(ub) + abs(kx) * (abs(xa) + abs(xb)) + abs(lr * y) + abs(L[_LAM + j] * y)
        )
        g0 = s * (ua - L[_F0 + j])
        g1 = s * (um - f1)
        g2 = s * (ub - f2)
        # a dip below zero at mid-step that is over by the end and shallower than DIP of the
        # step's relative velocity moves z by nothing measurable: not a reversal (cutting at it
        # can ping-pong, the cut point's d being zero only to the dense output's accuracy)
        dip = (g2 >= -eps) & (-g1 <= DIP * (abs(g0) + abs(g2)))
        first = (g1 < -eps) & (g0 >= -eps) & (not dip)
        rev = first | ((g1 >= -eps) & (g2 < -eps))
        wrong = (g0 < -eps) & (g1 < -eps) & (g2 < -eps)
        # both branches turning back at once, right after a reversal here: d touched zero
        # without crossing (only to the location's accuracy). Take a short step on this branch
        # (z moves by |d| times a sliver); a flip back would ping-pong.
        touch = wrong & (tau == L[_FLIPT + j])
        wrong = wrong & (not touch)
        sliver = hh <= TOUCH_STEP * dt
        # z passes 0 inside the step and |z|^n has a cusp there (n < 1): cut at it
        cross = (L[_CUSP + j] != 0.0) & (la < 0.0) & (l2 > 0.0) & (not rev) & (not wrong)
        runaway = (L[_FTOP + j] != 0.0) & (l2 > L[_LTOP + j])
        nst = L[_NST + j] + (1.0 if act else 0.0)
        small = hh * fac < MIN_STEP_FRACTION * dt
        bad = act & ((nst > maxs) | small | (not (abs(y) < 1e300)) | (ok & runaway))
        ok_touch = ok & touch & (not sliver)  # first a short step, then take it as it is
        ok = ok & (not ok_touch)
        plain = ok & (not rev) & (not wrong) & (not cross) & (not bad)
        # after a rejection stay below LAST_FRACTION of the rest, or the retry is the same step
        rem = dt - tau
        hr = hh * fac
        hr = LAST_REJECT * rem if (hr >= LAST_FRACTION * rem) & (not ok) else hr
        hr = TOUCH_STEP * dt if ok_touch else hr
        L[_Y + j] = y2 if plain else y
        L[_LB + j] = l2 if plain else la
        L[_TAU + j] = (dt if last else tau + hh) if plain else tau
        L[_H + j] = (hr if plain else (h if (ok & wrong) else hr)) if act else h
        L[_NST + j] = nst
        L[_F2 + j] = f2
        L[_OUTV + j] = L[_FOUT + j] * (f2 if L[_WJ + j] != 0.0 else y2)  # k0 y or c0 w'
        L[_FAIL + j] = 1.0 if bad else 0.0
        evt = (1.0 if first else 3.0) if rev else (2.0 if wrong else 4.0)
        event = ok & (rev | wrong | cross) & (not bad)
        L[_EVT + j] = evt if event else 0.0
        # for the hand-over: 1 the sample is done, 2 an event or a failure, 0 nothing
        L[_CODE + j] = 1.0 if (plain & last) else (2.0 if (event | bad) else 0.0)
        L[_YA + j] = y
        L[_HH + j] = hh
        L[_D1 + j] = 2.0 * (n1 - n0)
        L[_D2 + j] = 2.0 * (n2 - n1) - 2.0 * (n1 - n0)
        L[_G0 + j] = g0
        L[_G1 + j] = g1
        L[_G2 + j] = g2
        L[_FAC + j] = fac
        L[_L2 + j] = l2


@nb.njit(cache=True, error_model="numpy")
def _pass(L, tabs, n, dt, inv_dt, maxs):  # pragma: no cover - compiled
    """One masked trial step in each active lane 0 <= j < n (branch-free, in four vectorised
    phases with the table reads between them).

    Sets row _CODE (1: sample finished, 2: see _FAIL and _EVT), _FAIL, or _EVT (1 or 3: a
    reversal inside the first or second half of the accepted step, to be located; 2: d has
    the wrong sign all through the step: reverse at its start; 4: z passes its cusp at 0
    inside the step, to be located). A lane touches only its own entries of L.
    """
    _setup(L, n, dt, inv_dt)
    _read(L, tabs, n, _K0, _P00)
    _guess(L, n, _start(L, n))
    _read(L, tabs, n, _K1, _P10)
    _read(L, tabs, n, _K2, _P20)
    _newton(L, n)
    _read(L, tabs, n, _K2, _P20)
    _finish(L, n, dt, maxs)
