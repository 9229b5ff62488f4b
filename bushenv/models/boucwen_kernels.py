"""Compiled Bouc-Wen free run (seed 002 eqs. 1-5): the production kernel and a plain reference.

Eqs. 1-4 are two independent 2 x 2 systems driven by the same x(t): (y, z1) by eqs. 1 and 3,
(w, z2) by eqs. 2 and 4. Each is one *block* of the same form,

    y' = cu u + kx x - lam y + aa z,   d = u - y',   z' = d (A - (gamma + beta sgn d sgn z) |z|^n)

block 1: lam = (k0 + k1)/c1, kx = k1/c1, cu = 1, aa = a1/c1; block 2 (y is w): lam = kx = k2/mu,
cu = c2/mu, aa = a2/mu, mu = c0 + c2. F = k0 y + c0 w' (eq. 5) is block 1's k0 y plus block 2's
c0 w' at the sample's end.

Why not one RK4 step per sample: the identified sets are stiff (lam up to ~1300 /s, 1/dt = 205
/s) and, worse, z saturates within ~0.1 mm of relative travel, so it turns the corner of each
hysteresis loop *inside* a sample; the unloading branch is up to ten times steeper still. A
stability-limited explicit step (the previous kernel) needed 6-37 RK4 sub-steps per sample on
both blocks and was accurate only as a side effect of its conservative step: a set with a soft
block 1 and a sharp block 2 gave 7 % of peak error on a 4 mm step. Measured alternatives and
why not them: docs/benchmarks.md.

``boucwen_kernel`` integrates each block with ROS34PW2 (Rang & Angermann 2005: a 4-stage
Rosenbrock-W method of order 3, L-stable, stiffly accurate, with an embedded order-2 solution):

* linearly implicit: a 2 x 2 solve per stage, so stiffness costs nothing (a held step takes one
  or two steps per sample); a W-method keeps order 3 for any Jacobian, so the |z|^(n-1) slope
  is floored near z = 0 (as before) and the branch of sgn d sgn z frozen over a step;
* error control on the force: local errors weighted by how they reach F (block 1: k0 |e_y| +
  k0 aa / max(lam, 1/dt) |e_z|; block 2: c0 lam |e_w| + c0 aa |e_z|) must stay below
  ``rtol * F_REF``, F_REF = max(sum |k| * 1 mm, sum |c| * 10 mm/s); the step size is carried
  from sample to sample. Measured against a converged solution (``boucwen_fixed_step``) at the
  default rtol: within 2e-3 of max(peak force, F_REF) on random, step, 80 Hz, out-of-band and
  zig-zag inputs, for the shipped sets, Table 3 and random identification candidates; for the
  shipped sets and Table 3 that is 2e-3 of the peak (tests/models/test_boucwen_kernels.py);
* lanes: a tile holds BW_TILE lanes of one block type for BW_TILE profiles; each pass makes one
  trial step in every lane (vectorised, branch-free), and a lane that finishes its sample is
  handed its next sample at once, so no lane waits for the slowest one of its tile. A lane
  reads and writes only its own entries, with no fused multiply-add, so a profile gives the
  same bits alone, in any tile, in one call or one sample per call (``step``).

A lane fails (NaN from then on, counted) when a sample needs more than ``max_substeps`` trial
steps, the step falls below 1e-14 dt, the state is no longer finite (a solution that blows up,
e.g. a < 0 with hardening, beta + gamma < 0 and n > 1), or a block relaxes faster than 1e-8 of
a sample (``LAM_DT_MAX``: eq. 3 or 4 is then algebraic and this form loses its digits).

``boucwen_fixed_step`` is the reference: classical RK4 with a fixed number of equal sub-steps
per sample on eqs. 1-4 as printed (libm pow), obviously right and slow.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from bushenv.models.fastpow import pow_abs

# error_model="numpy": no zero-division guard branches, so the loops over lanes vectorise.
JIT = dict(cache=True, fastmath=False, nogil=True, error_model="numpy")

# Parameter rows of ``p`` (16, B), SI.
BW_ORDER = (
    "c0",
    "k0",
    "c1",
    "k1",
    "c2",
    "k2",
    "A1",
    "A2",
    "beta1",
    "beta2",
    "gamma1",
    "gamma2",
    "n1",
    "n2",
    "a1",
    "a2",
)
# State rows: y, w, z1, z2, x_prev, v_prev, trial steps in the last sample (both blocks,
# diagnostic), next step size of block 1 and of block 2 (s; 0 = start with one step per sample).
BW_N_STATE = 9
BW_RTOL = 3e-5  # default tolerance on the force, relative to F_REF (see the module docstring)
BW_MAX_SUBSTEPS = 20_000  # trial steps per sample and block; beyond: not integrable here
X_REF_M = 1e-3
V_REF_M_PER_S = 1e-2
Z_FLOOR = 1e-6  # |z|^(n-1) in the Jacobian is evaluated no closer to 0 than |A| * Z_FLOOR
MIN_STEP_FRACTION = 1e-14  # of dt
# A block relaxing faster than 1e-8 of a sample (|lam| dt > LAM_DT_MAX) is eq. 3 or 4 in its
# algebraic limit; y' = ... kx x - lam y ... then cancels terms ~1e8 times its size and loses the
# digits the error estimate needs (c1 = 1e-9 N s/m gave a plausible, wrong force): refused.
LAM_DT_MAX = 1e8
BW_TILE = 16  # lanes per tile: two 8-double AVX-512 vectors

# ROS34PW2, Hairer-Wanner form: (I - h g J) k_i = h f(t + c_i h, y + sum a_ij k_j)
#   + h J sum g_ij k_j + gs_i h^2 f_t; y1 = y + sum b_i k_i; error = sum e_i k_i.
RG = 4.3586652150845900e-01
RA21 = 8.7173304301691801e-01
RA31 = 8.4457060015369423e-01
RA32 = -1.1299064236484185e-01
RG21 = -8.7173304301691801e-01
RG31 = -9.0338057013044082e-01
RG32 = 5.4180672388095326e-02
RG41 = 2.4212380706095346e-01
RG42 = -1.2232505839045147e00
RG43 = 5.4526025533510214e-01
RB1 = 2.4212380706095346e-01
RB2 = -1.2232505839045147e00
RB3 = 1.5452602553351020e00
RB4 = 4.3586652150845900e-01
RE1 = RB1 - 3.7810903145819369e-01
RE2 = RB2 + 9.6042292212423178e-02
RE3 = RB3 - 0.5
RE4 = RB4 - 2.1793326075422950e-01
RC2 = RA21
RC3 = RA31 + RA32
RGS1 = RG
RGS2 = RG + RG21
RGS3 = RG + RG31 + RG32
RGS4 = RG + RG41 + RG42 + RG43

# The tile scratch L is flat: row r of lane j is L[r * BW_TILE + j]. Offsets known at compile
# time let LLVM tell the rows apart and vectorise over lanes (a 2-D array's runtime row stride
# made it give up: "too many memory checks"). The names below are those offsets.
# F0-F4: this block's share of eq. 5, kept here so that finishing a sample does not read p
# (16, B) at five cache lines.
_ROWS = (
    "LAM KX CU AA A BE GA N WY WZ TOL FL PRE Y Z H X0 U0 DX DU TAU NST ACT FAIL DONE F0 F1 F2 F3 F4"
).split()
_N_ROWS = len(_ROWS)
(
    _LAM, _KX, _CU, _AA, _A, _BE, _GA, _N, _WY, _WZ, _TOL, _FL, _PRE,
    _Y, _Z, _H, _X0, _U0, _DX, _DU, _TAU, _NST, _ACT, _FAIL, _DONE, _F0, _F1, _F2, _F3, _F4,
) = (r * BW_TILE for r in range(_N_ROWS))  # fmt: skip


@nb.njit(cache=True, inline="always", error_model="numpy")
def _block_rhs(lam, kx, cu, aa, A, be, ga, n, xx, u, y, z):  # pragma: no cover - compiled
    """Right-hand side of one block; also d, the branch coefficient, |z|^n, G and sgn z."""
    dy = cu * u + kx * xx - lam * y + aa * z
    d = u - dy
    sd = 1.0 if d > 0.0 else (-1.0 if d < 0.0 else 0.0)
    sz = 1.0 if z > 0.0 else (-1.0 if z < 0.0 else 0.0)
    coef = ga + be * sd * sz
    pz = pow_abs(z, n)
    g = A - coef * pz
    return dy, d * g, d, coef, pz, g, sz


@nb.njit(**JIT)
def _ros34_pass(L, j1, dt, inv_dt, maxs):  # pragma: no cover - compiled
    """One masked ROS34PW2 trial step in each active lane 0 <= j < j1 (branch-free).

    Sets row _DONE to 1 for lanes that completed their sample and row _FAIL for lanes that
    failed; both leave _ACT at 0. A lane touches only its own entries of L.
    """
    for j in range(j1):
        lam = L[_LAM + j]
        kx = L[_KX + j]
        cu = L[_CU + j]
        aa = L[_AA + j]
        A = L[_A + j]
        be = L[_BE + j]
        ga = L[_GA + j]
        n = L[_N + j]
        y = L[_Y + j]
        z = L[_Z + j]
        h = L[_H + j]
        x0 = L[_X0 + j]
        u0 = L[_U0 + j]
        dx = L[_DX + j]
        du = L[_DU + j]
        tau = L[_TAU + j]
        nst = L[_NST + j]
        act = L[_ACT + j] != 0.0

        rem = dt - tau
        last = h >= rem * (1.0 - 1e-12)
        hh = rem if last else h
        sx = dx * inv_dt  # dx/dt and du/dt: f_t of the non-autonomous system
        su = du * inv_dt
        s = tau * inv_dt
        f1y, f1z, d, coef, pz, g, sz = _block_rhs(
            lam, kx, cu, aa, A, be, ga, n, x0 + s * dx, u0 + s * du, y, z
        )
        az = abs(z)
        pre = L[_PRE + j]  # loaded unconditionally: a select, not a branch
        zp = pre if az <= L[_FL + j] else pz / az
        j11 = -lam
        j12 = aa
        j21 = lam * g
        j22 = -aa * g - d * coef * n * zp * sz
        fty = kx * sx + cu * su
        ftz = (su - fty) * g
        hg = hh * RG
        m11 = 1.0 - hg * j11
        m12 = -hg * j12
        m21 = -hg * j21
        m22 = 1.0 - hg * j22
        idet = 1.0 / (m11 * m22 - m12 * m21)
        h2 = hh * hh
        # stage 1
        r1 = hh * f1y + RGS1 * h2 * fty
        r2 = hh * f1z + RGS1 * h2 * ftz
        k1y = (m22 * r1 - m12 * r2) * idet
        k1z = (m11 * r2 - m21 * r1) * idet
        # stage 2
        s = (tau + RC2 * hh) * inv_dt
        fy, fz, _, _, _, _, _ = _block_rhs(
            lam, kx, cu, aa, A, be, ga, n, x0 + s * dx, u0 + s * du, y + RA21 * k1y, z + RA21 * k1z
        )
        qy = RG21 * k1y
        qz = RG21 * k1z
        r1 = hh * (fy + j11 * qy + j12 * qz) + RGS2 * h2 * fty
        r2 = hh * (fz + j21 * qy + j22 * qz) + RGS2 * h2 * ftz
        k2y = (m22 * r1 - m12 * r2) * idet
        k2z = (m11 * r2 - m21 * r1) * idet
        # stage 3
        s = (tau + RC3 * hh) * inv_dt
        fy, fz, _, _, _, _, _ = _block_rhs(
            lam,
            kx,
            cu,
            aa,
            A,
            be,
            ga,
            n,
            x0 + s * dx,
            u0 + s * du,
            y + RA31 * k1y + RA32 * k2y,
            z + RA31 * k1z + RA32 * k2z,
        )
        qy = RG31 * k1y + RG32 * k2y
        qz = RG31 * k1z + RG32 * k2z
        r1 = hh * (fy + j11 * qy + j12 * qz) + RGS3 * h2 * fty
        r2 = hh * (fz + j21 * qy + j22 * qz) + RGS3 * h2 * ftz
        k3y = (m22 * r1 - m12 * r2) * idet
        k3z = (m11 * r2 - m21 * r1) * idet
        # stage 4, at the step's end (stiffly accurate: its state is y + k3)
        s = 1.0 if last else (tau + hh) * inv_dt
        fy, fz, _, _, _, _, _ = _block_rhs(
            lam, kx, cu, aa, A, be, ga, n, x0 + s * dx, u0 + s * du, y + k3y, z + k3z
        )
        qy = RG41 * k1y + RG42 * k2y + RG43 * k3y
        qz = RG41 * k1z + RG42 * k2z + RG43 * k3z
        r1 = hh * (fy + j11 * qy + j12 * qz) + RGS4 * h2 * fty
        r2 = hh * (fz + j21 * qy + j22 * qz) + RGS4 * h2 * ftz
        k4y = (m22 * r1 - m12 * r2) * idet
        k4z = (m11 * r2 - m21 * r1) * idet

        ey = RE1 * k1y + RE2 * k2y + RE3 * k3y + RE4 * k4y
        ez = RE1 * k1z + RE2 * k2z + RE3 * k3z + RE4 * k4z
        err = (L[_WY + j] * abs(ey) + L[_WZ + j] * abs(ez)) / L[_TOL + j]
        yn = y + RB1 * k1y + RB2 * k2y + RB3 * k3y + RB4 * k4y
        zn = z + RB1 * k1z + RB2 * k2z + RB3 * k3z + RB4 * k4z
        finite = (abs(yn) < 1e300) & (abs(zn) < 1e300) & (err < 1e300)
        ok = act & finite & (err <= 1.0)
        # step-size controller: h 0.9 / sqrt(err), within [0.2, 4] h. The textbook exponent for
        # an embedded order 2 is 1/3; 1/2 took 8 % fewer trial steps here (the kinks at
        # reversals and z = 0 lower the effective order) and a square root is cheaper than pow.
        fac = 0.9 / math.sqrt(max(err, 1e-12))
        fac = 4.0 if not (fac < 4.0) else fac
        fac = 0.2 if not (fac > 0.2) else fac
        fac = fac if finite else 0.2
        hn = hh * fac
        hnew = (max(h, hn) if last else hn) if ok else hn
        nst = nst + 1.0 if act else nst
        bad = act & ((nst > maxs) | (hn < MIN_STEP_FRACTION * dt) | (not (abs(y) < 1e300)))
        done = ok & last
        L[_Y + j] = yn if ok else y
        L[_Z + j] = zn if ok else z
        L[_H + j] = hnew if act else h
        L[_TAU + j] = (dt if last else tau + hh) if ok else tau
        L[_NST + j] = nst
        L[_DONE + j] = 1.0 if (done & (not bad)) else 0.0
        L[_FAIL + j] = 1.0 if bad else 0.0
        L[_ACT + j] = 1.0 if (act & (not done) & (not bad)) else 0.0


@nb.njit(**JIT)
def boucwen_kernel(x, v, state, p, dt, max_substeps, rtol, out):  # pragma: no cover - compiled
    """Free run of B histories over T samples (see the module docstring).

    x, v, out (T, B); state (BW_N_STATE, B) updated in place; p (16, B); ``rtol`` the error
    tolerance on the force. Returns how many histories failed in this call (their forces are
    NaN from the failing sample on; the model raises, the identification scores them inf).
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
                b = lo + j
                c0 = p[0, b]
                k0 = p[1, b]
                c1 = p[2, b]
                k1 = p[3, b]
                c2 = p[4, b]
                k2 = p[5, b]
                f_ref = max(
                    (abs(k0) + abs(k1) + abs(k2)) * X_REF_M,
                    (abs(c0) + abs(c1) + abs(c2)) * V_REF_M_PER_S,
                )
                if blk == 0:
                    lam = (k0 + k1) / c1
                    aa = p[14, b] / c1
                    L[_LAM + j] = lam
                    L[_KX + j] = k1 / c1
                    L[_CU + j] = 1.0
                    L[_AA + j] = aa
                    L[_WY + j] = abs(k0)
                    L[_WZ + j] = abs(k0) * abs(aa) / max(abs(lam), inv_dt)
                    L[_F0 + j] = k0
                else:
                    mu = c0 + c2
                    lam = k2 / mu
                    aa = p[15, b] / mu
                    L[_LAM + j] = lam
                    L[_KX + j] = lam
                    L[_CU + j] = c2 / mu
                    L[_AA + j] = aa
                    L[_WY + j] = abs(c0) * abs(lam)
                    L[_WZ + j] = abs(c0) * abs(aa)
                    L[_F0 + j] = c0
                    L[_F1 + j] = c2
                    L[_F2 + j] = k2
                    L[_F3 + j] = p[15, b]
                    L[_F4 + j] = mu
                A = p[6 + blk, b]
                n = p[12 + blk, b]
                L[_A + j] = A
                L[_BE + j] = p[8 + blk, b]
                L[_GA + j] = p[10 + blk, b]
                L[_N + j] = n
                L[_TOL + j] = rtol * f_ref
                fl = abs(A) * Z_FLOOR
                L[_FL + j] = fl
                L[_PRE + j] = fl ** (n - 1.0)
                L[_Y + j] = state[blk, b]
                L[_Z + j] = state[2 + blk, b]
                h0 = state[7 + blk, b]
                L[_H + j] = h0 if h0 > 0.0 else dt
                # first sample of this call
                L[_X0 + j] = state[4, b]
                L[_U0 + j] = state[5, b]
                L[_DX + j] = x[0, b] - state[4, b]
                L[_DU + j] = v[0, b] - state[5, b]
                L[_TAU + j] = 0.0
                L[_NST + j] = 0.0
                L[_ACT + j] = 1.0
                # a lane that cannot be integrated fails at its first pass (state NaN)
                ill = not (abs(L[_LAM + j]) * dt <= LAM_DT_MAX)
                L[_Y + j] = np.nan if ill else L[_Y + j]
                L[_FAIL + j] = 0.0
                L[_DONE + j] = 0.0
                tidx[j] = 0
            n_live = n_lanes
            while n_live > 0:
                _ros34_pass(L, n_lanes, dt, inv_dt, maxs)
                for j in range(n_lanes):
                    done = L[_DONE + j] != 0.0
                    failed = L[_FAIL + j] != 0.0
                    if not (done or failed):
                        continue
                    b = lo + j
                    t = tidx[j]
                    if failed:
                        bad_col[b] = True
                        L[_Y + j] = np.nan
                        L[_Z + j] = np.nan
                    # this block's share of eq. 5 at the sample's end
                    while True:
                        x1 = x[t, b]
                        u1 = v[t, b]
                        yy = L[_Y + j]
                        if blk == 0:
                            out[t, b] = L[_F0 + j] * yy  # k0 y
                        else:  # c0 w', eq. 4
                            zz = L[_Z + j]
                            dw = (L[_F1 + j] * u1 + L[_F2 + j] * (x1 - yy) + L[_F3 + j] * zz) / L[
                                _F4 + j
                            ]
                            out[t, b] = out[t, b] + L[_F0 + j] * dw
                        if t == T - 1 or not failed:
                            break
                        t += 1  # a failed lane: NaN for every remaining sample
                    if t == T - 1:
                        state[6, b] += L[_NST + j]
                        L[_DONE + j] = 0.0
                        L[_FAIL + j] = 0.0
                        L[_ACT + j] = 0.0
                        n_live -= 1
                        tidx[j] = T
                        continue
                    t += 1
                    tidx[j] = t
                    L[_X0 + j] = x[t - 1, b]
                    L[_U0 + j] = v[t - 1, b]
                    L[_DX + j] = x[t, b] - x[t - 1, b]
                    L[_DU + j] = v[t, b] - v[t - 1, b]
                    L[_TAU + j] = 0.0
                    L[_NST + j] = 0.0
                    L[_DONE + j] = 0.0
                    L[_ACT + j] = 1.0
            for j in range(n_lanes):
                b = lo + j
                state[blk, b] = L[_Y + j]
                state[2 + blk, b] = L[_Z + j]
                state[7 + blk, b] = L[_H + j]
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
