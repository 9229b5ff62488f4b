"""Compiled Bouc-Wen free run (seed 002 eqs. 1-5): the vectorised kernel and the reference one.

Both integrate eqs. 1-4 over each sample with RK4 sub-steps, x and x' interpolated linearly
inside the sample, and choose every sub-step the same way: before it, the stiffest eigenvalue
magnitude ``rate`` is estimated at the current state and h = remaining / ceil(remaining * rate
/ RK4_STABLE_FRACTION), so every sub-step sits inside RK4's stability interval and the last one
ends exactly on the sample. F follows from eq. 5.

``boucwen_kernel_reference`` is the original one-profile-at-a-time loop (libm ``pow``; the rate
estimate re-evaluates the right-hand side). ``boucwen_kernel`` is the same algorithm arranged
so that LLVM vectorises it over profiles:

* profiles are processed in tiles of BW_TILE lanes in lockstep: each pass of the inner loop
  over the lanes does one sub-step for every lane that still has one to do; a lane keeps its
  own tau, h and sub-step count, and finished or failed lanes are masked (branch-free selects),
  so a lane's numbers never depend on its neighbours (B = 1 and batched agree bit for bit);
* ``|z| ** n`` is ``fastpow.pow_abs`` (arithmetic only, within ~1e-14 of libm);
* the rate estimate reuses RK4's first stage (the same right-hand side at the same point) and
  its ``|z| ** n``; ``|z| ** (n - 1)`` is ``|z| ** n / |z|``.

The two kernels therefore differ only by the rounding of ``pow`` (and of the division above),
which can move a ceil() by one and so change a sub-step count; the forces agree to RK4's
truncation error at the stability-limited step (measured below 1e-8 of the peak force on the
shipped parameters, ``tests/models/test_boucwen_kernels.py``).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from bushenv.models.fastpow import pow_abs

# error_model="numpy": no zero-division guard branches, so the loops over profiles vectorise.
JIT = dict(cache=True, fastmath=False, nogil=True, error_model="numpy")

# Parameter rows of ``p`` (16, B), SI: see BW_ORDER. State rows: y, w, z1, z2, x_prev, v_prev,
# substeps used in the last sample (diagnostic).
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
BW_N_STATE = 7
RK4_STABLE_FRACTION = 2.0  # RK4 is stable for h*|lambda| < 2.785 on the real axis; keep ~70 %
BW_MAX_SUBSTEPS = 200_000  # per sample; beyond this the parameters are not integrable here
Z_FLOOR = 1e-6  # |z|^(n-1) in the rate is evaluated no closer to 0 than |A| * Z_FLOOR

# Lanes per tile of the vectorised kernel: a multiple of the 8-double AVX-512 vector.
BW_TILE = 16

# rows of the per-tile lane scratch (one float64 row of BW_TILE lanes each)
_P = 0  # 16 parameter rows, BW_ORDER
_PRE1 = 16  # (|A1| Z_FLOOR) ** (n1 - 1), libm, once per call
_PRE2 = 17
_FL1 = 18  # |A1| Z_FLOOR
_FL2 = 19
_Y = 20
_W = 21
_Z1 = 22
_Z2 = 23
_X0 = 24
_U0 = 25
_X1 = 26
_U1 = 27
_TAU = 28
_NSUB = 29
_ACT = 30
_FAIL = 31
_N_ROWS = 32


# ----- reference: the original scalar kernel -----------------------------------------------
@nb.njit(**JIT)
def _sgn(a):  # pragma: no cover - compiled
    if a > 0.0:
        return 1.0
    if a < 0.0:
        return -1.0
    return 0.0


@nb.njit(**JIT)
def _bw_rhs(p, b, xx, u, y, w, z1, z2):  # pragma: no cover - compiled
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
    dz1 = d1 * (p[6, b] - (p[10, b] + p[8, b] * _sgn(d1) * _sgn(z1)) * abs(z1) ** p[12, b])  # 1
    dz2 = d2 * (p[7, b] - (p[11, b] + p[9, b] * _sgn(d2) * _sgn(z2)) * abs(z2) ** p[13, b])  # 2
    return dy, dw, dz1, dz2


@nb.njit(**JIT)
def _bw_rate(p, b, xx, u, y, w, z1, z2):  # pragma: no cover - compiled
    """Upper estimate of the stiffest eigenvalue magnitude of eqs. 1-4 at this state (1/s).

    Linearising eqs. 1 and 3 in (y, z1) gives eigenvalues 0 and -(k0 + k1 + a1 G1) / c1 with
    G1 = A1 - (gamma1 + beta1 s) |z1|^n1, plus d1 * dG1/dz1 from the |z1|^n1 term; likewise
    (k2 + a2 G2) / (c0 + c2) for eqs. 2 and 4. Absolute values make it an upper estimate.
    For n < 1, |z|^(n-1) is evaluated no closer to 0 than A * 1e-6 m (one micrometre's worth of
    hysteretic variable): the singular slope at z = 0 is crossed, not dwelt in.
    """
    c0 = p[0, b]
    k0 = p[1, b]
    c1 = p[2, b]
    k1 = p[3, b]
    c2 = p[4, b]
    k2 = p[5, b]
    dy, dw, _, _ = _bw_rhs(p, b, xx, u, y, w, z1, z2)
    d1 = abs(u - dy)
    d2 = abs(u - dw)
    bg1 = abs(p[8, b]) + abs(p[10, b])
    bg2 = abs(p[9, b]) + abs(p[11, b])
    az1 = abs(z1)
    az2 = abs(z2)
    g1 = abs(p[6, b]) + bg1 * az1 ** p[12, b]
    g2 = abs(p[7, b]) + bg2 * az2 ** p[13, b]
    zf1 = max(az1, abs(p[6, b]) * Z_FLOOR)
    zf2 = max(az2, abs(p[7, b]) * Z_FLOOR)
    s1 = d1 * bg1 * abs(p[12, b]) * zf1 ** (p[12, b] - 1.0)
    s2 = d2 * bg2 * abs(p[13, b]) * zf2 ** (p[13, b] - 1.0)
    r1 = (abs(k0) + abs(k1) + abs(p[14, b]) * g1) / abs(c1) + s1
    r2 = (abs(k2) + abs(p[15, b]) * g2) / abs(c0 + c2) + s2
    return r1 + r2


@nb.njit(**JIT)
def boucwen_kernel_reference(x, v, state, p, dt, max_substeps, out):  # pragma: no cover
    """The original scalar kernel (kept to test the vectorised one against; same contract).

    Returns the number of (column, sample) pairs that needed more than ``max_substeps`` in one
    sample or went non-finite (their output is NaN from then on).
    """
    T, B = x.shape
    n_bad = 0
    for t in range(T):
        for b in range(B):
            y = state[0, b]
            w = state[1, b]
            z1 = state[2, b]
            z2 = state[3, b]
            x0 = state[4, b]
            u0 = state[5, b]
            x1 = x[t, b]
            u1 = v[t, b]
            tau = 0.0
            n_sub = 0
            ok = True
            while tau < dt:
                remaining = dt - tau
                s = tau / dt
                rate = _bw_rate(p, b, x0 + s * (x1 - x0), u0 + s * (u1 - u0), y, w, z1, z2)
                if not (rate < 1e300):  # NaN or inf: no finite step is stable
                    ok = False
                    break
                n_left = math.ceil(remaining * rate / RK4_STABLE_FRACTION)
                if n_left < 1:
                    n_left = 1
                if n_sub + n_left > max_substeps:
                    ok = False
                    break
                h = remaining / n_left
                sa = tau / dt
                sm = (tau + 0.5 * h) / dt
                se = (tau + h) / dt
                if n_left == 1:
                    se = 1.0
                xa = x0 + sa * (x1 - x0)
                ua = u0 + sa * (u1 - u0)
                xm = x0 + sm * (x1 - x0)
                um = u0 + sm * (u1 - u0)
                xe = x0 + se * (x1 - x0)
                ue = u0 + se * (u1 - u0)
                ky1, kw1, kz11, kz21 = _bw_rhs(p, b, xa, ua, y, w, z1, z2)
                hh = 0.5 * h
                ky2, kw2, kz12, kz22 = _bw_rhs(
                    p, b, xm, um, y + hh * ky1, w + hh * kw1, z1 + hh * kz11, z2 + hh * kz21
                )
                ky3, kw3, kz13, kz23 = _bw_rhs(
                    p, b, xm, um, y + hh * ky2, w + hh * kw2, z1 + hh * kz12, z2 + hh * kz22
                )
                ky4, kw4, kz14, kz24 = _bw_rhs(
                    p, b, xe, ue, y + h * ky3, w + h * kw3, z1 + h * kz13, z2 + h * kz23
                )
                h6 = h / 6.0
                y += h6 * (ky1 + 2.0 * ky2 + 2.0 * ky3 + ky4)
                w += h6 * (kw1 + 2.0 * kw2 + 2.0 * kw3 + kw4)
                z1 += h6 * (kz11 + 2.0 * kz12 + 2.0 * kz13 + kz14)
                z2 += h6 * (kz21 + 2.0 * kz22 + 2.0 * kz23 + kz24)
                n_sub += 1
                if n_left == 1:
                    tau = dt
                else:
                    tau += h
            if not ok:
                n_bad += 1
                y = np.nan
                w = np.nan
                z1 = np.nan
                z2 = np.nan
            c0 = p[0, b]
            c2 = p[4, b]
            dw = (c2 * u1 + p[5, b] * (x1 - w) + p[15, b] * z2) / (c0 + c2)
            out[t, b] = p[1, b] * y + c0 * dw  # eq. 5
            state[0, b] = y
            state[1, b] = w
            state[2, b] = z1
            state[3, b] = z2
            state[4, b] = x1
            state[5, b] = u1
            state[6, b] = n_sub
    return n_bad


# ----- the vectorised kernel ---------------------------------------------------------------
@nb.njit(cache=True, inline="always", error_model="numpy")
def _rhs_v(c0, k0, c1, k1, c2, k2, A1, A2, be1, be2, ga1, ga2, n1, n2, a1, a2, xx, u, y, w, z1, z2):
    # pragma: no cover - compiled. Same expressions, same order as _bw_rhs (bit for bit, but
    # for pow); also returns |z1|^n1 and |z2|^n2 for the rate estimate. Signs are selects.
    dy = (c1 * u + k1 * (xx - y) - k0 * y + a1 * z1) / c1  # eq. 3
    dw = (c2 * u + k2 * (xx - w) + a2 * z2) / (c0 + c2)  # eq. 4
    d1 = u - dy
    d2 = u - dw
    sd1 = 1.0 if d1 > 0.0 else (-1.0 if d1 < 0.0 else 0.0)
    sz1 = 1.0 if z1 > 0.0 else (-1.0 if z1 < 0.0 else 0.0)
    sd2 = 1.0 if d2 > 0.0 else (-1.0 if d2 < 0.0 else 0.0)
    sz2 = 1.0 if z2 > 0.0 else (-1.0 if z2 < 0.0 else 0.0)
    pz1 = pow_abs(z1, n1)
    pz2 = pow_abs(z2, n2)
    dz1 = d1 * (A1 - (ga1 + be1 * sd1 * sz1) * pz1)  # eq. 1
    dz2 = d2 * (A2 - (ga2 + be2 * sd2 * sz2) * pz2)  # eq. 2
    return dy, dw, dz1, dz2, pz1, pz2


@nb.njit(**JIT)
def boucwen_kernel(x, v, state, p, dt, max_substeps, out):  # pragma: no cover - compiled
    """Vectorised free run (see the module docstring); same contract as the reference kernel.

    x, v, out (T, B); state (BW_N_STATE, B) updated in place; p (16, B). Returns the number of
    (column, sample) pairs whose integration failed: more than ``max_substeps`` sub-steps in a
    sample, or a non-finite rate. Such a column holds NaN from then on (the model raises, the
    identification scores it infeasible).
    """
    T, B = x.shape
    W = BW_TILE
    n_bad = 0
    L = np.zeros(_N_ROWS * W)
    maxs = float(max_substeps)
    for lo in range(0, B, W):
        n = min(W, B - lo)
        # Unused lanes of a last, partial tile copy lane 0's parameters and stay at rest: they
        # run the same loop (no remainder loop) and their results are dropped.
        for j in range(W):
            b = lo + j if j < n else lo
            for r in range(16):
                L[(_P + r) * W + j] = p[r, b]
            fl1 = abs(p[6, b]) * Z_FLOOR
            fl2 = abs(p[7, b]) * Z_FLOOR
            L[_FL1 * W + j] = fl1
            L[_FL2 * W + j] = fl2
            L[_PRE1 * W + j] = fl1 ** (p[12, b] - 1.0)  # as the reference (libm)
            L[_PRE2 * W + j] = fl2 ** (p[13, b] - 1.0)
            live = j < n
            L[_Y * W + j] = state[0, b] if live else 0.0
            L[_W * W + j] = state[1, b] if live else 0.0
            L[_Z1 * W + j] = state[2, b] if live else 0.0
            L[_Z2 * W + j] = state[3, b] if live else 0.0
            L[_X0 * W + j] = state[4, b] if live else 0.0
            L[_U0 * W + j] = state[5, b] if live else 0.0
            L[_X1 * W + j] = 0.0
            L[_U1 * W + j] = 0.0
        for t in range(T):
            for j in range(n):
                L[_X1 * W + j] = x[t, lo + j]
                L[_U1 * W + j] = v[t, lo + j]
            for j in range(W):
                L[_TAU * W + j] = 0.0
                L[_NSUB * W + j] = 0.0
                L[_ACT * W + j] = 1.0 if 0.0 < dt else 0.0
                L[_FAIL * W + j] = 0.0
            if n == W:
                n_act = W
                while n_act > 0:
                    n_act = _substep_tile(L, dt, maxs, 0, W)
            else:  # partial tile: each lane alone (no wasted sub-steps; same arithmetic)
                for j in range(n):
                    while _substep_tile(L, dt, maxs, j, j + 1):
                        pass
            for j in range(n):
                b = lo + j
                failed = L[_FAIL * W + j] != 0.0
                if failed:
                    n_bad += 1
                    L[_Y * W + j] = np.nan
                    L[_W * W + j] = np.nan
                    L[_Z1 * W + j] = np.nan
                    L[_Z2 * W + j] = np.nan
                y = L[_Y * W + j]
                w = L[_W * W + j]
                z2 = L[_Z2 * W + j]
                x1 = L[_X1 * W + j]
                u1 = L[_U1 * W + j]
                c0 = L[(_P + 0) * W + j]
                c2 = L[(_P + 4) * W + j]
                dw = (c2 * u1 + L[(_P + 5) * W + j] * (x1 - w) + L[(_P + 15) * W + j] * z2) / (
                    c0 + c2
                )
                out[t, b] = L[(_P + 1) * W + j] * y + c0 * dw  # eq. 5
                state[6, b] = L[_NSUB * W + j]
            for j in range(W):
                L[_X0 * W + j] = L[_X1 * W + j]
                L[_U0 * W + j] = L[_U1 * W + j]
        for j in range(n):
            b = lo + j
            state[0, b] = L[_Y * W + j]
            state[1, b] = L[_W * W + j]
            state[2, b] = L[_Z1 * W + j]
            state[3, b] = L[_Z2 * W + j]
            state[4, b] = L[_X0 * W + j]
            state[5, b] = L[_U0 * W + j]
    return n_bad


@nb.njit(**JIT)
def _substep_tile(L, dt, maxs, j0, j1):  # pragma: no cover - compiled
    """One masked RK4 sub-step for each active lane j0 <= j < j1 of a tile (branch-free).

    Returns how many of those lanes stay active. A lane reads and writes only its own entries
    of L, so it gives the same bits whether it runs with the whole tile (vectorised) or alone.
    """
    W = BW_TILE
    n_act = 0
    for j in range(j0, j1):
        c0 = L[(_P + 0) * W + j]
        k0 = L[(_P + 1) * W + j]
        c1 = L[(_P + 2) * W + j]
        k1 = L[(_P + 3) * W + j]
        c2 = L[(_P + 4) * W + j]
        k2 = L[(_P + 5) * W + j]
        A1 = L[(_P + 6) * W + j]
        A2 = L[(_P + 7) * W + j]
        be1 = L[(_P + 8) * W + j]
        be2 = L[(_P + 9) * W + j]
        ga1 = L[(_P + 10) * W + j]
        ga2 = L[(_P + 11) * W + j]
        n1 = L[(_P + 12) * W + j]
        n2 = L[(_P + 13) * W + j]
        a1 = L[(_P + 14) * W + j]
        a2 = L[(_P + 15) * W + j]
        y = L[_Y * W + j]
        w = L[_W * W + j]
        z1 = L[_Z1 * W + j]
        z2 = L[_Z2 * W + j]
        x0 = L[_X0 * W + j]
        u0 = L[_U0 * W + j]
        x1 = L[_X1 * W + j]
        u1 = L[_U1 * W + j]
        tau = L[_TAU * W + j]
        nsub = L[_NSUB * W + j]
        act = L[_ACT * W + j] != 0.0
        fail = L[_FAIL * W + j] != 0.0

        remaining = dt - tau
        sa = tau / dt
        xa = x0 + sa * (x1 - x0)
        ua = u0 + sa * (u1 - u0)
        ky1, kw1, kz11, kz21, pz1, pz2 = _rhs_v(
            c0, k0, c1, k1, c2, k2, A1, A2, be1, be2, ga1, ga2, n1, n2, a1, a2, xa, ua, y, w, z1, z2
        )
        # rate: _bw_rate at the same point, from stage 1's values
        d1 = abs(ua - ky1)
        d2 = abs(ua - kw1)
        bg1 = abs(be1) + abs(ga1)
        bg2 = abs(be2) + abs(ga2)
        az1 = abs(z1)
        az2 = abs(z2)
        g1 = abs(A1) + bg1 * pz1
        g2 = abs(A2) + bg2 * pz2
        fl1 = L[_FL1 * W + j]
        fl2 = L[_FL2 * W + j]
        zp1 = L[_PRE1 * W + j] if az1 <= fl1 else pz1 / az1
        zp2 = L[_PRE2 * W + j] if az2 <= fl2 else pz2 / az2
        s1 = d1 * bg1 * abs(n1) * zp1
        s2 = d2 * bg2 * abs(n2) * zp2
        r1 = (abs(k0) + abs(k1) + abs(a1) * g1) / abs(c1) + s1
        r2 = (abs(k2) + abs(a2) * g2) / abs(c0 + c2) + s2
        rate = r1 + r2
        n_left = np.ceil(remaining * rate / RK4_STABLE_FRACTION)
        n_left = 1.0 if n_left < 1.0 else n_left
        bad = (not (rate < 1e300)) | (nsub + n_left > maxs)
        bad = bad & act
        go = act & (not bad)
        last = n_left == 1.0
        h = remaining / n_left
        sm = (tau + 0.5 * h) / dt
        se = 1.0 if last else (tau + h) / dt
        xm = x0 + sm * (x1 - x0)
        um = u0 + sm * (u1 - u0)
        xe = x0 + se * (x1 - x0)
        ue = u0 + se * (u1 - u0)
        hh = 0.5 * h
        ky2, kw2, kz12, kz22, _, _ = _rhs_v(
            c0,
            k0,
            c1,
            k1,
            c2,
            k2,
            A1,
            A2,
            be1,
            be2,
            ga1,
            ga2,
            n1,
            n2,
            a1,
            a2,
            xm,
            um,
            y + hh * ky1,
            w + hh * kw1,
            z1 + hh * kz11,
            z2 + hh * kz21,
        )
        ky3, kw3, kz13, kz23, _, _ = _rhs_v(
            c0,
            k0,
            c1,
            k1,
            c2,
            k2,
            A1,
            A2,
            be1,
            be2,
            ga1,
            ga2,
            n1,
            n2,
            a1,
            a2,
            xm,
            um,
            y + hh * ky2,
            w + hh * kw2,
            z1 + hh * kz12,
            z2 + hh * kz22,
        )
        ky4, kw4, kz14, kz24, _, _ = _rhs_v(
            c0,
            k0,
            c1,
            k1,
            c2,
            k2,
            A1,
            A2,
            be1,
            be2,
            ga1,
            ga2,
            n1,
            n2,
            a1,
            a2,
            xe,
            ue,
            y + h * ky3,
            w + h * kw3,
            z1 + h * kz13,
            z2 + h * kz23,
        )
        h6 = h / 6.0
        yn = y + h6 * (ky1 + 2.0 * ky2 + 2.0 * ky3 + ky4)
        wn = w + h6 * (kw1 + 2.0 * kw2 + 2.0 * kw3 + kw4)
        z1n = z1 + h6 * (kz11 + 2.0 * kz12 + 2.0 * kz13 + kz14)
        z2n = z2 + h6 * (kz21 + 2.0 * kz22 + 2.0 * kz23 + kz24)
        taun = dt if last else tau + h
        L[_Y * W + j] = yn if go else y
        L[_W * W + j] = wn if go else w
        L[_Z1 * W + j] = z1n if go else z1
        L[_Z2 * W + j] = z2n if go else z2
        tau = taun if go else tau
        L[_TAU * W + j] = tau
        L[_NSUB * W + j] = nsub + 1.0 if go else nsub
        fail = fail | bad
        L[_FAIL * W + j] = 1.0 if fail else 0.0
        still = go & (tau < dt)
        L[_ACT * W + j] = 1.0 if still else 0.0
        n_act += 1 if still else 0
    return n_act
