"""Compiled Bouc-Wen free run (seed 002 eqs. 1-5): the driver, its lanes and the reversals.

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
  (lambda reflected: xi(lambda_new) = -xi(lambda)); for n < 1 a step is also cut where z passes
  0, the cusp of |z|^n.

Lanes: a tile holds BW_TILE lanes (one block of BW_TILE profiles, their columns of x, v and out
staged in contiguous buffers); each pass (``boucwen_pass``) makes one trial step in every lane
(vectorised, branch-free) and the hand-over loop here acts on its outcome: a reversal to
locate, a failure, or a finished sample, whose lane takes its next one at once. A lane reads and
writes only its own entries, with no fused multiply-add, so a profile gives the same bits alone,
in any tile, in one call or one sample per call.

A lane fails (NaN from then on, counted) when a sample needs more than ``max_substeps`` trial
steps, the step falls below 1e-14 dt, the state is no longer finite, z leaves a hardening
table (the solution runs away), or the parameter set was refused when the tables were built
(``boucwen_tables.prepare``). The plain reference is ``boucwen_reference``.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from bushenv.models.boucwen.passes import (  # noqa: F401  (row offsets: the scratch layout)
    _AAW,
    _ACT,
    _AW,
    _CODE,
    _CU,
    _D1,
    _D2,
    _DU,
    _DX,
    _EVT,
    _F2,
    _FAC,
    _FAIL,
    _FLIPT,
    _FOUT,
    _G0,
    _G1,
    _G2,
    _H,
    _HH,
    _IDLD,
    _IDLU,
    _IMD,
    _IMU,
    _KX,
    _L0D,
    _L2,
    _LAM,
    _LB,
    _LR,
    _N0,
    _N_BC,
    _N_ROWS,
    _NST,
    _OFFD,
    _OFFU,
    _OK,
    _OUTV,
    _RTOL,
    _S,
    _SHIFT,
    _TAU,
    _U0,
    _U1,
    _UA,
    _WJ,
    _X0,
    _X1,
    _Y,
    _YA,
    _ZW,
    BW_TILE,
    JIT,
    _pass,
)
from bushenv.models.boucwen.step import (
    hermite,
    inverse,
    locate,
    locate_tolerance,
    locate_zero_crossing,
)
from bushenv.models.boucwen.tables import BW_ORDER, BW_RTOL, V_REF_M_PER_S, X_REF_M

# State rows: y, w, z1, z2 (z: written for inspection, not read), x_prev, v_prev, trial steps in
# the last sample (both blocks, diagnostic), next step size of block 1 and 2 (s; 0 = one step
# per sample), lambda of block 1 and 2, direction of travel of block 1 and 2 (< 0: -1, else +1).
BW_N_STATE = 13
BW_MAX_SUBSTEPS = 20_000  # trial steps per sample and block; beyond: not integrable here
__all__ = ["BW_ORDER", "BW_RTOL", "X_REF_M", "V_REF_M_PER_S", "BW_N_STATE", "BW_TILE"]


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
        L[_G0 + j], L[_G1 + j], L[_G2 + j], first, ua, du_dt, locate_tolerance(L[_RTOL + j]),
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
def _load_lane(L, j, b, blk, xs, vs, state, bc, k, dt):  # pragma: no cover - compiled
    """Lane j takes block ``blk`` of profile b (constants: row k of bc) at the call's first
    sample; xs, vs: the tile's staged columns."""
    for r in range(_N_BC):
        L[r * BW_TILE + j] = bc[k, r]
    L[_Y + j] = state[blk, b]
    L[_LB + j] = state[9 + blk, b]
    L[_S + j] = -1.0 if state[11 + blk, b] < 0.0 else 1.0
    h0 = state[7 + blk, b]
    L[_H + j] = h0 if h0 > 0.0 else dt
    L[_TAU + j] = 0.0
    L[_NST + j] = 0.0
    _take_sample(L, j, state[4, b], state[5, b], xs[0, j], vs[0, j])
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
    L[_FLIPT + j] = -1.0


@nb.njit(cache=True, error_model="numpy")
def _event(L, tabs, fs, state, tidx, bad_col, b, j, dt, inv_dt):  # pragma: no cover - compiled
    """Lane j (profile b) failed (returns True) or holds a reversal to act on."""
    if L[_FAIL + j] != 0.0:
        bad_col[b] = True
        for t in range(tidx[j], fs.shape[0]):
            fs[t, j] = np.nan
        state[6, b] += L[_NST + j]
        L[_Y + j] = np.nan
        L[_LB + j] = np.nan
        L[_ACT + j] = 0.0
        L[_CODE + j] = 0.0
        return True
    evt = L[_EVT + j]
    if evt == 2.0:
        _reverse(L, tabs, j)
        L[_FLIPT + j] = L[_TAU + j]
    else:
        if evt == 4.0:
            _cut_at_zero(L, j, dt, inv_dt)
        else:
            _cut_at_reversal(L, tabs, j, dt, inv_dt, evt == 1.0)
            L[_FLIPT + j] = L[_TAU + j]
        if L[_TAU + j] >= dt:  # the reversal is the sample's end
            f = _f_at_end(L, tabs, j) if L[_WJ + j] != 0.0 else L[_Y + j]
            L[_OUTV + j] = L[_FOUT + j] * f
            L[_CODE + j] = 1.0
            return False
    L[_CODE + j] = 0.0
    return False


@nb.njit(**JIT)
def _hand_over(
    L, tabs, xs, vs, fs, state, tidx, bad_col, lo, n, blk, dt, inv_dt
):  # pragma: no cover
    """After a pass, per lane (scalar): fail, reverse, or on finishing a sample write its share
    of eq. 5 and take the next sample (xs, vs, fs: the tile's staged columns of x, v, out).
    Returns how many lanes finished the call's last sample or failed."""
    T = xs.shape[0]
    n_out = 0
    for j in range(n):
        code = L[_CODE + j]
        if code == 0.0:
            continue
        b = lo + j
        if code == 2.0:
            if _event(L, tabs, fs, state, tidx, bad_col, b, j, dt, inv_dt):
                n_out += 1
            if L[_CODE + j] != 1.0:
                continue
        t = tidx[j]
        if blk == 0:
            fs[t, j] = L[_OUTV + j]
        else:
            fs[t, j] = fs[t, j] + L[_OUTV + j]
        if t == T - 1:
            state[6, b] += L[_NST + j]
            L[_ACT + j] = 0.0
            L[_CODE + j] = 0.0
            n_out += 1
            continue
        t += 1
        tidx[j] = t
        _take_sample(L, j, L[_X1 + j], L[_U1 + j], xs[t, j], vs[t, j])
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
    # A tile's columns of x, v and out are staged in contiguous (T, BW_TILE) buffers: the lanes
    # walk them at their own paces, and in (T, B) every sample of every lane was another page.
    xs = np.empty((T, W))
    vs = np.empty((T, W))
    fs = np.empty((T, W))
    for lo in range(0, B, W):
        n_lanes = min(W, B - lo)
        for t in range(T):
            for j in range(n_lanes):
                xs[t, j] = x[t, lo + j]
                vs[t, j] = v[t, lo + j]
        for blk in range(2):
            for j in range(n_lanes):
                _load_lane(L, j, lo + j, blk, xs, vs, state, bc, tab_index[blk, lo + j], dt)
                tidx[j] = 0
            n_live = n_lanes
            while n_live > 0:
                _pass(L, tabs, n_lanes, dt, inv_dt, maxs)
                n_live -= _hand_over(
                    L, tabs, xs, vs, fs, state, tidx, bad_col, lo, n_lanes, blk, dt, inv_dt
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
        for t in range(T):
            for j in range(n_lanes):
                out[t, lo + j] = fs[t, j]
    n_bad = 0
    for b in range(B):
        state[4, b] = x[T - 1, b]
        state[5, b] = v[T - 1, b]
        if bad_col[b]:
            n_bad += 1
    return n_bad
