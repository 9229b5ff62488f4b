"""Compiled Bouc-Wen free run (seed 002 eqs. 1-5): the production kernel and a plain reference.

Eqs. 1-4 are two independent 2 x 2 systems driven by the same x(t): (y, z1) by eqs. 1 and 3,
(w, z2) by eqs. 2 and 4. Each is one *block* of the same form,

    y' = f = cu u + kx x - lam y + aa z,  d = u - y',  z' = d (A - (gamma + beta sgn d sgn z) |z|^n)

block 1: lam = (k0 + k1)/c1, kx = k1/c1, cu = 1, aa = a1/c1; block 2 (y is w): lam = kx = k2/mu,
cu = c2/mu, aa = a2/mu, mu = c0 + c2. u is the velocity input and x the displacement, both
linear within a sample. F = k0 y + c0 w' (eq. 5) is block 1's k0 y plus block 2's c0 f.

z is rate independent: along a stretch where d keeps its sign s it is an exact function of the
relative travel, tabulated once per parameter set (``boucwen_tables``): z = s W xi(lambda),
lambda = lambda_a + s (A / W)(U(t) - U(t_a) - (y - y_a)), U the integral of u. What is left is
one scalar ODE for y per block, stiff (lam dt up to 22 on the identified sets, and the z
feedback up to ten times that after a reversal) with a known nonlinearity. ``boucwen_kernel``
integrates it with exponential collocation (docs/boucwen-integration.md):

* L = -df/dy at the step's start; y(t_a + theta h) = e^(-L h theta) y_a + integral of e^(-L (.))
  N with N = f + L y interpolated through its values at theta = 0, 1/2, 1 (one implicit
  2 x 2 system, one Newton step from the linearised solution); exact for the linear decay and
  any input ramp, so a kink of the input at a sample boundary costs nothing;
* error control on the force: |y - y_low| (y_low: the same with N linear through 0 and 1)
  weighted by k0 (block 1) or c0 |df/dy| (block 2) must stay below rtol F_REF, F_REF =
  max(sum |k| x 1 mm, sum |c| x 10 mm/s); step sizes are carried from sample to sample;
* reversals: when d changes sign inside an accepted step, the step is cut where the dense
  output's d = 0 (Newton on the exact exponential form) and z continues on the other branch
  (lambda reflected: xi(lambda_new) = -xi(lambda)).

Lanes: a tile holds BW_TILE lanes (one block of BW_TILE profiles); each pass makes one trial
step in every lane (vectorised, branch-free) and a lane that finishes its sample is handed its
next one at once. A lane reads and writes only its own entries, with no fused multiply-add,
so a profile gives the same bits alone, in any tile, in one call or one sample per call.

A lane fails (NaN from then on, counted) when a sample needs more than ``max_substeps`` trial
steps, the step falls below 1e-14 dt, the state is no longer finite, z leaves a hardening
table (its hysteretic force beyond 1e3 F_REF: the solution runs away), or the parameter set
was refused when the tables were built (``boucwen_tables.prepare``).

``boucwen_fixed_step`` is the reference: classical RK4 with a fixed number of equal sub-steps
per sample on eqs. 1-4 as printed (libm pow), obviously right and slow.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

from bushenv.models.boucwen_step import (
    SMALL_Z,
    hermite,
    hermite_values,
    inverse,
    locate,
    locate_zero_crossing,
    phis_half_and_full,
    segment_index,
)
from bushenv.models.boucwen_tables import (
    BC_ROWS,
    BW_ORDER,
    BW_RTOL,
    V_REF_M_PER_S,
    X_REF_M,
)

# error_model="numpy": no zero-division guard branches, so the loops over lanes vectorise.
JIT = dict(cache=True, fastmath=False, nogil=True, error_model="numpy")

# State rows: y, w, z1, z2 (z: written for inspection, not read), x_prev, v_prev, trial steps in
# the last sample (both blocks, diagnostic), next step size of block 1 and 2 (s; 0 = one step
# per sample), lambda of block 1 and 2, direction of travel of block 1 and 2 (< 0: -1, else +1).
BW_N_STATE = 13
BW_MAX_SUBSTEPS = 20_000  # trial steps per sample and block; beyond: not integrable here
MIN_STEP_FRACTION = 1e-14  # of dt
LAST_FRACTION = 0.8  # a step reaching this far into the rest of the sample takes all of it
LAST_REJECT = 0.75  # a rejected step is retried with at most this much of the rest
DIP = 1e-3  # a reversal and its return within one step, this shallow, are ignored
BW_TILE = 16  # lanes per tile: two 8-double AVX-512 vectors
__all__ = ["BW_ORDER", "BW_RTOL", "X_REF_M", "V_REF_M_PER_S", "BW_N_STATE", "BW_TILE"]

PREFETCH_SAMPLES = 8  # a lane taking sample t asks the caches for sample t + this


@intrinsic
def _prefetch(typingctx, arr, i, j):
    """Hint the caches to fetch arr[i, j] (2-D float64; never faults). The lanes of a tile walk
    x, v and out (T, B) each at its own pace: without it every new sample waits for memory."""
    if not (isinstance(arr, types.Array) and arr.ndim == 2):
        return None

    def codegen(context, builder, signature, args):
        a, ii, jj = args
        ary = context.make_array(signature.args[0])(context, builder, a)
        ptr = cgutils.get_item_pointer(
            context, builder, signature.args[0], ary, [ii, jj], wraparound=False
        )
        i8p = ir.IntType(8).as_pointer()
        i32 = ir.IntType(32)
        fnty = ir.FunctionType(ir.VoidType(), [i8p, i32, i32, i32])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.prefetch.p0i8")
        # read, high locality, data cache
        builder.call(fn, [builder.bitcast(ptr, i8p), i32(0), i32(3), i32(1)])
        return context.get_dummy_value()

    return types.void(arr, i, j), codegen


# The tile scratch L is flat: row r of lane j is L[r * BW_TILE + j]. Offsets known at compile
# time let LLVM tell the rows apart and vectorise over lanes. The first len(BC_ROWS) rows are
# the block's constants (``boucwen_tables.BC_ROWS``), copied from ``bc``.
_ROWS = BC_ROWS + tuple(
    (
        # lane state, the sample's input, flags
        "Y LB S H TAU NST X0 DX U0 DU X1 U1 ACT CODE FAIL EVT OUTV "
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
    _OFFD, _L0D, _IDLD, _IMD, _OFFU, _IDLU, _IMU, _LTOP, _FTOP, _OK, _ZW, _SHIFT, _CUSP,
    _Y, _LB, _S, _H, _TAU, _NST, _X0, _DX, _U0, _DU, _X1, _U1, _ACT, _CODE, _FAIL, _EVT, _OUTV,
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
        # z passes 0 inside the step and |z|^n has a cusp there (n < 1): cut at it
        cross = (L[_CUSP + j] != 0.0) & (la < 0.0) & (l2 > 0.0) & (not rev) & (not wrong)
        runaway = (L[_FTOP + j] != 0.0) & (l2 > L[_LTOP + j])
        nst = L[_NST + j] + (1.0 if act else 0.0)
        small = hh * fac < MIN_STEP_FRACTION * dt
        bad = act & ((nst > maxs) | small | (not (abs(y) < 1e300)) | (ok & runaway))
        plain = ok & (not rev) & (not wrong) & (not cross) & (not bad)
        # after a rejection stay below LAST_FRACTION of the rest, or the retry is the same step
        rem = dt - tau
        hr = hh * fac
        hr = LAST_REJECT * rem if (hr >= LAST_FRACTION * rem) & (not ok) else hr
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


@nb.njit(cache=True, error_model="numpy")
def _reverse(L, tabs, j):  # pragma: no cover - compiled
    """Reflect lambda of lane j (z unchanged, direction of travel flipped). From z on its
    loading side (lambda >= 0) the reflection table (read like the nodes, SHIFT entries on);
    from the unloading side by solving xi(lambda_r) = -xi(lambda): there the reflection runs
    into the saturation of the loading side, where lambda_r grows without bound."""
    lam = L[_LB + j]
    sh = L[_SHIFT + j]
    a = (
        L[_OFFD + j],
        L[_L0D + j],
        L[_IDLD + j],
        L[_IMD + j],
        L[_OFFU + j],
        L[_IDLU + j],
        L[_IMU + j],
    )
    if lam >= 0.0:
        lr, _ = hermite(tabs, lam, a[0] + sh, a[1], a[2], a[3], a[4] + sh, a[5], a[6])
    else:
        xi, _ = hermite(tabs, lam, a[0], a[1], a[2], a[3], a[4], a[5], a[6])
        lr = inverse(tabs, -xi, a[0], a[1], a[2], a[3], a[4], a[5], a[6])
    L[_LB + j] = lr
    L[_S + j] = -1.0 if L[_S + j] >= 0.0 else 1.0


@nb.njit(cache=True, error_model="numpy")
def _cut_at_reversal(L, tabs, j, dt, inv_dt, first):  # pragma: no cover - compiled
    """Lane j's accepted step holds a reversal (in its ``first`` half or the second): move to
    it on the dense output and reflect."""
    s = -1.0 if L[_S + j] < 0.0 else 1.0
    hh = L[_HH + j]
    du_dt = L[_DU + j] * inv_dt
    ya = L[_YA + j]
    ua = L[_UA + j]
    th, y = locate(
        ya, L[_LR + j], hh, L[_N0 + j], L[_D1 + j], L[_D2 + j], s,
        L[_G0 + j], L[_G1 + j], L[_G2 + j], first, ua, du_dt,
    )  # fmt: skip
    tau = L[_TAU + j]
    dt_r = th * hh
    du_int = dt_r * (ua + 0.5 * du_dt * dt_r)  # integral of u from the step's start
    L[_LB + j] = L[_LB + j] + s * L[_AW + j] * (du_int - (y - ya))
    L[_Y + j] = y
    L[_TAU + j] = dt if th >= 1.0 or tau + dt_r >= dt else tau + dt_r
    L[_H + j] = hh * L[_FAC + j]
    _reverse(L, tabs, j)


@nb.njit(cache=True, error_model="numpy")
def _cut_at_zero(L, j, dt, inv_dt):  # pragma: no cover - compiled
    """Lane j's accepted step takes z through 0 (a cusp, n < 1): move there on the dense
    output, so that the next step starts at the cusp instead of straddling it."""
    s = -1.0 if L[_S + j] < 0.0 else 1.0
    hh = L[_HH + j]
    du_dt = L[_DU + j] * inv_dt
    ya = L[_YA + j]
    th, y = locate_zero_crossing(
        ya, L[_LR + j], hh, L[_N0 + j], L[_D1 + j], L[_D2 + j], s, L[_AW + j], L[_LB + j],
        L[_L2 + j], L[_UA + j], du_dt,
    )  # fmt: skip
    dt_r = th * hh
    L[_LB + j] = 0.0  # exactly at the cusp (to the location's tolerance, 1e-7 of the step)
    L[_Y + j] = y
    tau = L[_TAU + j]
    L[_TAU + j] = dt if th >= 1.0 or tau + dt_r >= dt else tau + dt_r
    L[_H + j] = hh * L[_FAC + j]


@nb.njit(cache=True, error_model="numpy")
def _f_at_end(L, tabs, j):  # pragma: no cover - compiled
    """y' at the end of the sample from lane j's state (block 2's share of eq. 5)."""
    s = -1.0 if L[_S + j] < 0.0 else 1.0
    xi, _ = hermite(
        tabs, L[_LB + j], L[_OFFD + j], L[_L0D + j], L[_IDLD + j], L[_IMD + j],
        L[_OFFU + j], L[_IDLU + j], L[_IMU + j],
    )  # fmt: skip
    xb = L[_X0 + j] + L[_DX + j]
    ub = L[_U0 + j] + L[_DU + j]
    return L[_CU + j] * ub + L[_KX + j] * xb - L[_LAM + j] * L[_Y + j] + s * L[_AAW + j] * xi


@nb.njit(cache=True, error_model="numpy")
def _load_lane(L, j, b, blk, x, v, state, bc, k, dt):  # pragma: no cover - compiled
    """Lane j takes block ``blk`` of profile b (constants: row k of bc) at the call's first
    sample."""
    for r in range(_N_BC):
        L[r * BW_TILE + j] = bc[k, r]
    L[_Y + j] = state[blk, b]
    L[_LB + j] = state[9 + blk, b]
    L[_S + j] = -1.0 if state[11 + blk, b] < 0.0 else 1.0
    h0 = state[7 + blk, b]
    L[_H + j] = h0 if h0 > 0.0 else dt
    L[_TAU + j] = 0.0
    L[_NST + j] = 0.0
    _take_sample(L, j, state[4, b], state[5, b], x[0, b], v[0, b])
    L[_ACT + j] = 1.0
    L[_CODE + j] = 0.0
    L[_EVT + j] = 0.0
    # a refused parameter set fails at its first pass
    L[_FAIL + j] = 0.0
    if L[_OK + j] == 0.0:
        L[_Y + j] = np.nan


@nb.njit(cache=True, inline="always", error_model="numpy")
def _take_sample(L, j, x0, u0, x1, u1):  # pragma: no cover - compiled
    """Lane j starts the sample from (x0, u0) to (x1, u1)."""
    L[_X0 + j] = x0
    L[_DX + j] = x1 - x0
    L[_U0 + j] = u0
    L[_DU + j] = u1 - u0
    L[_X1 + j] = x1
    L[_U1 + j] = u1
    L[_TAU + j] = 0.0
    L[_NST + j] = 0.0


@nb.njit(cache=True, error_model="numpy")
def _event(L, tabs, out, state, tidx, bad_col, b, j, dt, inv_dt):  # pragma: no cover - compiled
    """Lane j failed (returns True) or holds a reversal to act on."""
    if L[_FAIL + j] != 0.0:
        bad_col[b] = True
        for t in range(tidx[j], out.shape[0]):
            out[t, b] = np.nan
        state[6, b] += L[_NST + j]
        L[_Y + j] = np.nan
        L[_LB + j] = np.nan
        L[_ACT + j] = 0.0
        L[_CODE + j] = 0.0
        return True
    evt = L[_EVT + j]
    if evt == 2.0:
        _reverse(L, tabs, j)
    else:
        if evt == 4.0:
            _cut_at_zero(L, j, dt, inv_dt)
        else:
            _cut_at_reversal(L, tabs, j, dt, inv_dt, evt == 1.0)
        if L[_TAU + j] >= dt:  # the reversal is the sample's end
            f = _f_at_end(L, tabs, j) if L[_WJ + j] != 0.0 else L[_Y + j]
            L[_OUTV + j] = L[_FOUT + j] * f
            L[_CODE + j] = 1.0
            return False
    L[_CODE + j] = 0.0
    return False


@nb.njit(**JIT)
def _hand_over(
    L, tabs, x, v, out, state, tidx, bad_col, lo, n, blk, dt, inv_dt
):  # pragma: no cover
    """After a pass, per lane (scalar): fail, reverse, or on finishing a sample write its share
    of eq. 5 and take the next sample. Returns how many lanes finished the call's last sample
    or failed."""
    T = x.shape[0]
    n_out = 0
    for j in range(n):
        code = L[_CODE + j]
        if code == 0.0:
            continue
        b = lo + j
        if code == 2.0:
            if _event(L, tabs, out, state, tidx, bad_col, b, j, dt, inv_dt):
                n_out += 1
            if L[_CODE + j] != 1.0:
                continue
        t = tidx[j]
        if blk == 0:
            out[t, b] = L[_OUTV + j]
        else:
            out[t, b] = out[t, b] + L[_OUTV + j]
        if t == T - 1:
            state[6, b] += L[_NST + j]
            L[_ACT + j] = 0.0
            L[_CODE + j] = 0.0
            n_out += 1
            continue
        t += 1
        tidx[j] = t
        tp = min(t + PREFETCH_SAMPLES, T - 1)
        _prefetch(x, tp, b)
        _prefetch(v, tp, b)
        _prefetch(out, tp, b)
        _take_sample(L, j, L[_X1 + j], L[_U1 + j], x[t, b], v[t, b])
    return n_out


@nb.njit(**JIT)
def boucwen_kernel(x, v, state, tabs, bc, tab_index, dt, max_substeps, out):  # pragma: no cover
    """Free run of B histories over T samples (see the module docstring).

    x, v, out (T, B); state (BW_N_STATE, B) updated in place; tabs, bc from
    ``boucwen_tables.prepare``; tab_index (2, B) int: the row of bc for each block of each
    profile. Returns how many histories failed in this call (their forces are NaN from the
    failing sample on; the model raises, the identification scores them inf).
    """
    T, B = x.shape
    W = BW_TILE
    L = np.zeros(_N_ROWS * W)
    tidx = np.zeros(W, dtype=np.int64)
    bad_col = np.zeros(B, dtype=np.bool_)
    inv_dt = 1.0 / dt
    maxs = float(max_substeps)
    for b in range(B):
        state[6, b] = 0.0
    if T == 0:
        return 0
    for blk in range(2):
        for lo in range(0, B, W):
            n_lanes = min(W, B - lo)
            for j in range(n_lanes):
                _load_lane(L, j, lo + j, blk, x, v, state, bc, tab_index[blk, lo + j], dt)
                tidx[j] = 0
            n_live = n_lanes
            while n_live > 0:
                _pass(L, tabs, n_lanes, dt, inv_dt, maxs)
                n_live -= _hand_over(
                    L, tabs, x, v, out, state, tidx, bad_col, lo, n_lanes, blk, dt, inv_dt
                )
            for j in range(n_lanes):
                b = lo + j
                state[blk, b] = L[_Y + j]
                state[9 + blk, b] = L[_LB + j]
                state[11 + blk, b] = L[_S + j]
                state[7 + blk, b] = L[_H + j]
                xi, _ = hermite(
                    tabs, L[_LB + j], L[_OFFD + j], L[_L0D + j], L[_IDLD + j], L[_IMD + j],
                    L[_OFFU + j], L[_IDLU + j], L[_IMU + j],
                )  # fmt: skip
                state[2 + blk, b] = L[_S + j] * L[_ZW + j] * xi
    n_bad = 0
    for b in range(B):
        state[4, b] = x[T - 1, b]
        state[5, b] = v[T - 1, b]
        if bad_col[b]:
            n_bad += 1
    return n_bad


# ----- reference: fixed-step RK4 on eqs. 1-4 as printed ---------------------------------------
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
