"""The rate-independent half of the Bouc-Wen model, tabulated once per parameter set.

seed 002 eqs. 1-2 drive each hysteretic variable by the relative velocity d = u - y' (block 1;
u - w' for block 2): z' = d (A - (gamma + beta sgn d sgn z) |z|^n). Time appears only through
d, so along a stretch where d keeps its sign s, z is a function of the relative travel r =
integral of d. With w = s z and l = s (r - r_0) (travel since the stretch began, l >= 0):

    dw/dl = A - c(w) |w|^n,    c = gamma + beta (w >= 0, "loading"), gamma - beta (w < 0)

one autonomous scalar ODE per block, the same for both directions. Each side of w = 0 in its
natural units, xi = w / W_side and lambda = A l / W_side with W_side = (A / |c|)^(1/n), reads
dxi/dlambda = 1 - sgn(c) xi^n: saturating at 1, linear, or hardening. Its solution through
xi(0) = 0, stored in the block's units (xi = w / W, lambda = A l / W, W the loading side's
scale), is the map: on a stretch z = s W xi(lambda), lambda = lambda_0 + s (A / W)(r - r_0),
exact however sharp the corner of the loop; at a reversal z continues from lambda_r with
xi(lambda_r) = -xi(lambda) (the reflection, tabulated on the loading side).

Nodes at equal spacing per side (finer where the slope's rate of change n xi^(n-1) is larger)
by RK4 next to the cusp at xi = 0 and a degree-4 Taylor step further out; read by cubic
Hermite interpolation. A saturating side ends at saturation (1 - xi^n < SAT_EPS), a hardening
one where the hysteretic force |a z| reaches FORCE_CAP_REF F_REF or, blowing up at finite
travel (n > 1), where its spacing would fall below 1 / RATE_MAX of the default: a history that
travels further fails. Accuracy and cost: docs/boucwen-integration.md.

Parameter sets the map does not cover are refused (``domain_error``): A <= 0 (z must grow
from rest), n <= 0, or an unloading branch that can reach a zero of its slope (beta < 0 with
gamma - beta > max(0, gamma + beta): z then runs away on unloading). The identification's
sets (A = 1, beta >= 0) and seed 002 Table 3 are inside.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from bushenv.models.boucwen.step import hermite_solve

# Parameter rows of a parameter vector (16,), SI.
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
BW_RTOL = 7e-4  # default tolerance on the force, relative to F_REF (boucwen_kernels)
X_REF_M = 1e-3  # F_REF = max(sum |k| X_REF_M, sum |c| V_REF_M_PER_S)
V_REF_M_PER_S = 1e-2
FORCE_CAP_REF = 1e3  # a hardening z whose force |a z| passes this many F_REF fails (runaway)
# A block relaxing faster than 1e-8 of a sample (|lam| dt > LAM_DT_MAX) is eq. 3 or 4 in its
# algebraic limit; y' = ... kx x - lam y ... then cancels terms ~1e8 times its size and loses
# the digits the reversal test needs (c1 = 1e-9 N s/m): refused.
LAM_DT_MAX = 1e8
# Per-block constants, one row of ``bc`` per (parameter set, block), in this order (the kernel
# copies them into its lanes): the block's coefficients (LAM, KX, CU; AAW = aa W, AAA = aa A,
# AW = A / W), the error tolerance TOL = rtol F_REF in N, the error weight WGT (k0, or c0 times
# |df/dy| if WJ = 1), the force factor FOUT (k0 y or c0 y'), the table segments below (OFFD,
# L0D, IDLD, IMD) and above zero (OFFU, IDLU, IMU), LTOP (lambda of the top node) and FTOP (1:
# beyond it the history fails), OK (0: the set was refused), W (the z scale, m), SHIFT (the
# reflection table's offset from the nodes', ``boucwen_step``), CUSP (1 if n < 1: steps are
# cut where z passes 0, where the slope of |z|^n is infinite) and RTOL (the tolerance).
BC_ROWS = tuple(
    "LAM KX CU AAW AAA AW TOL WGT WJ FOUT OFFD L0D IDLD IMD OFFU IDLU IMU LTOP FTOP OK ZW "
    "SHIFT CUSP RTOL".split()
)
SAT_EPS = 1e-4  # a saturating side ends where 1 - xi^n is below this (or 0.1 rtol, if less):
# z is then within SAT_EPS / n of its saturation, and its share of the force (|a| W times that)
# well below rtol F_REF on every set seen (shipped axial: 5e-3 N)
MAX_NODES = 1 << 16  # per side of xi = 0 (the default tolerance needs a few hundred)
# the first node intervals next to xi = 0 (the |xi|^n cusp), with this many RK4 sub-steps each
CUSP_SUBSTEPS = (16, 4, 2)
TAYLOR_FROM = 8.0  # nodes where xi >= this many spacings use the Taylor step
DLAMBDA_DEFAULT = 1.0 / 16.0  # node spacing (natural units) at the default tolerance
CUSP_XI = 0.1  # for n < 1 the curvature is judged at xi = CUSP_XI (it is infinite at 0)
RATE_MAX = 1024.0  # finest spacing dl / RATE_MAX; a blowing-up side ends where it needs finer


@nb.njit(cache=True, error_model="numpy")
def _rk4(xi, step, n_sub, kappa, n):  # pragma: no cover - compiled
    """RK4 on dxi/dlambda = 1 - kappa |xi|^n (one side: xi keeps its sign)."""
    hs = step / n_sub
    for _ in range(n_sub):
        a = 1.0 - kappa * abs(xi) ** n
        b = 1.0 - kappa * abs(xi + 0.5 * hs * a) ** n
        c = 1.0 - kappa * abs(xi + 0.5 * hs * b) ** n
        d = 1.0 - kappa * abs(xi + hs * c) ** n
        xi += hs / 6.0 * (a + 2.0 * b + 2.0 * c + d)
    return xi


@nb.njit(cache=True, error_model="numpy")
def _taylor4(xi, p, step, kappa, n):  # pragma: no cover - compiled
    """One step of the degree-4 Taylor series of dxi/dlambda = 1 - kappa xi^n from xi > 0 with
    p = xi^n: one power per step (RK4 needs four); the series converges for step << xi."""
    q = p / xi  # xi^(n-1)
    r = q / xi  # xi^(n-2)
    w = r / xi  # xi^(n-3)
    d1 = 1.0 - kappa * p
    d2 = -kappa * n * q * d1
    d3 = -kappa * n * ((n - 1.0) * r * d1 * d1 + q * d2)
    d4 = (
        -kappa
        * n
        * ((n - 1.0) * (n - 2.0) * w * d1 * d1 * d1 + 3.0 * (n - 1.0) * r * d1 * d2 + q * d3)
    )
    return xi + step * (d1 + step * (0.5 * d2 + step * (d3 / 6.0 + step * d4 / 24.0)))


@nb.njit(cache=True, error_model="numpy")
def _side(kappa, n, reach, dl, sat_eps):  # pragma: no cover - compiled
    """One side of xi = 0 in its natural units: dxi/dlambda = 1 - kappa xi^n, xi >= 0, kappa
    in {-1, 0, 1}, nodes at lambda = i * spacing until saturation (1 - xi^n < sat_eps),
    xi >= ``reach`` or MAX_NODES. The spacing is dl / (the largest |d slope / d xi| = n
    xi^(n-1) on the side, judged at xi = CUSP_XI for n < 1): near saturation xi approaches 1
    as exp(-n lambda), so the curve's scale in lambda is 1 / that rate.

    Returns (xi (count,), spacing, saturated).
    """
    if kappa == 0.0:  # linear: exact with two nodes
        out = np.empty(2)
        out[0] = 0.0
        out[1] = reach
        return out, reach, False
    if kappa < 0.0 and n > 1.0:
        # hardening towards a blow-up at finite travel: the curve sharpens without end, so the
        # side ends where the finest spacing no longer resolves it
        reach = min(reach, (RATE_MAX / n) ** (1.0 / (n - 1.0)))
    a = (
        (min(reach, 1.0) if n >= 1.0 else CUSP_XI)
        if kappa > 0.0
        else (reach if n >= 1.0 else CUSP_XI)
    )
    rate = n * a ** (n - 1.0)
    spacing = dl / min(RATE_MAX, max(1.0, rate))
    out = np.empty(256)
    out[0] = 0.0
    xi = 0.0
    pw = 0.0
    n_cusp = len(CUSP_SUBSTEPS)
    for i in range(1, MAX_NODES):
        if i <= n_cusp:  # next to the cusp at 0: RK4, finely
            xn = _rk4(xi, spacing, CUSP_SUBSTEPS[i - 1], kappa, n)
        elif xi < TAYLOR_FROM * spacing:
            xn = _rk4(xi, spacing, 1, kappa, n)
        else:  # further out: one power per node
            xn = _taylor4(xi, pw, spacing, kappa, n)
        if not (xn < 1e300):
            return out[:i].copy(), spacing, False
        xi = xn
        pw = xi**n
        if i >= out.shape[0]:
            grown = np.empty(2 * out.shape[0])
            grown[:i] = out[:i]
            out = grown
        out[i] = xi
        if kappa > 0.0 and 1.0 - pw < sat_eps:
            return out[: i + 1].copy(), spacing, True
        if xi >= reach:
            return out[: i + 1].copy(), spacing, False
    return out[:MAX_NODES].copy(), spacing, False


@nb.njit(cache=True, error_model="numpy")
def build_table(c_load, c_unload, A, n, dl, xi_cap, sat_eps):  # pragma: no cover - compiled
    """Tabulate z(travel) for one block: the loading side (w >= 0, coefficient c_load = gamma +
    beta) and the unloading side (w < 0, c_unload = gamma - beta), each in its natural units,
    stored in the block's units: xi = w / W, lambda = A l / W, W = the loading side's scale
    (A / |c_load|)^(1/n) (the unloading side's if c_load = 0; 1 m if both are 0).

    ``xi_cap``: a hardening side (no saturation) ends at xi = xi_cap; a history going further
    fails. Returns (nodes (n_down + n_up, 2): xi and spacing * dxi/dlambda, lambda <= 0 from
    the lowest up to 0 (n_down nodes), then lambda >= 0 from 0 up; n_down; spacing below;
    spacing above; whether lambda beyond the last node is saturation (True) or the end).
    """
    w_up = (A / abs(c_load)) ** (1.0 / n) if c_load != 0.0 else np.inf
    w_down = (A / abs(c_unload)) ** (1.0 / n) if c_unload != 0.0 else np.inf
    W = w_up if c_load != 0.0 else (w_down if c_unload != 0.0 else 1.0)
    k_up = np.sign(c_load)
    k_down = np.sign(c_unload)
    q_up = w_up / W if c_load != 0.0 else 1.0
    up, dl_up, sat_top = _side(k_up, n, xi_cap / q_up, dl, sat_eps)
    # below xi = 0 is only reached by reversing from above: cover down to -xi_top
    q_down = w_down / W if c_unload != 0.0 else 1.0
    down, dl_down, _ = _side(k_down, n, 1.0001 * up[-1] * q_up / q_down, dl, sat_eps)
    n_up = up.shape[0]
    n_down = down.shape[0]
    nodes = np.empty((n_down + n_up, 2))
    for i in range(n_down):  # each segment has its own node at lambda = 0
        xi = down[n_down - 1 - i]
        nodes[i, 0] = -q_down * xi
        nodes[i, 1] = q_down * dl_down * (1.0 - k_down * xi**n)
    for i in range(n_up):
        xi = up[i]
        nodes[n_down + i, 0] = q_up * xi
        nodes[n_down + i, 1] = q_up * dl_up * (1.0 - k_up * xi**n)
    return nodes, n_down, q_down * dl_down, q_up * dl_up, sat_top, W


@nb.njit(cache=True, error_model="numpy")
def _solve_in(nodes, i0, i1, l0, dl, target, hint):  # pragma: no cover - compiled
    """lambda with xi(lambda) = target within nodes i0..i1 (increasing) of one segment, whose
    node i0 sits at lambda = l0 (spacing dl): the interval is found by walking down from node
    ``hint`` (the targets of ``reflection`` decrease), then bisection-safeguarded Newton on its
    Hermite cubic. Returns (lambda, dxi/dlambda there, the interval for the next hint); the
    segment's ends clamp."""
    if target <= nodes[i0, 0]:  # at the end itself (xi = 0) the slope is the node's
        return l0, nodes[i0, 1] / dl if target == nodes[i0, 0] else 0.0, i0
    if target >= nodes[i1, 0]:
        return l0 + (i1 - i0) * dl, nodes[i1, 1] / dl if target == nodes[i1, 0] else 0.0, i1
    lo = min(max(hint, i0), i1 - 1)
    while lo < i1 - 1 and nodes[lo + 1, 0] <= target:
        lo += 1
    while lo > i0 and nodes[lo, 0] > target:
        lo -= 1
    p0, m0 = nodes[lo, 0], nodes[lo, 1]
    p1, m1 = nodes[lo + 1, 0], nodes[lo + 1, 1]
    t, c2, c3 = hermite_solve(p0, m0, p1, m1, target, 8, 1e-15)
    return l0 + (lo - i0 + t) * dl, (m0 + t * (2.0 * c2 + 3.0 * t * c3)) / dl, lo


@nb.njit(cache=True, error_model="numpy")
def reflection(nodes, n_down, dl_down, dl_up):  # pragma: no cover - compiled
    """The reflection lambda_r(lambda) at every node above lambda = 0 (same layout as
    ``nodes``; zero below, where the kernel solves for it): a reversal at lambda continues
    from lambda_r, where xi(lambda_r) = -xi(lambda); its slope is -xi'(lambda) /
    xi'(lambda_r) (0 where -xi is beyond the other segment: clamped)."""
    N = nodes.shape[0]
    out = np.zeros((N, 2))
    l0_down = -(n_down - 1) * dl_down
    hint_down = n_down - 1  # the targets -xi fall as xi rises: walk each segment downwards
    hint_up = N - 1
    for i in range(n_down, N):
        xi = nodes[i, 0]
        up = i >= n_down
        dl = dl_up if up else dl_down
        slope = nodes[i, 1] / dl
        if up:  # -xi <= 0: in the segment below
            lam, s_r, hint_down = _solve_in(nodes, 0, n_down - 1, l0_down, dl_down, -xi, hint_down)
        else:
            lam, s_r, hint_up = _solve_in(nodes, n_down, N - 1, 0.0, dl_up, -xi, hint_up)
        out[i, 0] = lam
        out[i, 1] = dl * (-slope / s_r if s_r > 0.0 else 0.0)
    return out


def domain_error(A: float, beta: float, gamma: float, n: float) -> str:
    """Why the map cannot represent this branch ("" if it can)."""
    vals = (A, beta, gamma, n)
    if not all(math.isfinite(v) for v in vals):
        return f"non-finite coefficient (A, beta, gamma, n) = {vals}"
    if not A > 0.0:
        return f"A = {A:g} must be > 0 (seed 002 eq. 6 asks A >= 1)"
    if not n > 0.0:
        return f"n = {n:g} must be > 0"
    c_load, c_unload = gamma + beta, gamma - beta
    if c_unload > max(0.0, c_load):
        return (
            f"beta = {beta:g} < 0 with gamma - beta = {c_unload:g} > max(0, gamma + beta): z "
            "runs away on unloading (seed 002 eq. 6 asks beta >= 0)"
        )
    for c in (c_load, c_unload):
        if c != 0.0:
            try:
                W = (A / abs(c)) ** (1.0 / n)
            except OverflowError:
                W = math.inf
            if not (math.isfinite(W) and W > 0.0):
                return f"z scale (A / |gamma +- beta|)^(1/n) = {W!r} is out of range"
    return ""


def node_spacing(rtol: float) -> float:
    """Table spacing (natural units) for a kernel tolerance: DLAMBDA_DEFAULT at BW_RTOL and
    below, finer as rtol^(1/4) for tighter tolerances (cubic Hermite error ~ spacing^4), so
    that the table stays below the integration error (tests/models/test_boucwen_tables.py)."""
    return float(DLAMBDA_DEFAULT * min(1.0, (rtol / BW_RTOL) ** 0.25))


def block_coefficients(p: np.ndarray, blk: int) -> dict[str, float]:
    """The block form of eqs. 3-4 (``boucwen_kernels`` docstring) for parameters p (16,)."""
    c0, k0, c1, k1, c2, k2, A1, A2, b1, b2, g1, g2, n1, n2, a1, a2 = (float(v) for v in p)
    if blk == 0:
        lam = (k0 + k1) / c1 if c1 != 0.0 else math.inf
        return dict(lam=lam, kx=k1 / c1 if c1 else math.inf, cu=1.0,
                    aa=a1 / c1 if c1 else math.inf, a=a1, A=A1, beta=b1, gamma=g1, n=n1,
                    wgt=abs(k0), wj=0.0, fout=k0)  # fmt: skip
    mu = c0 + c2
    lam = k2 / mu if mu != 0.0 else math.inf
    return dict(lam=lam, kx=lam, cu=c2 / mu if mu else math.inf, aa=a2 / mu if mu else math.inf,
                a=a2, A=A2, beta=b2, gamma=g2, n=n2, wgt=abs(c0), wj=1.0, fout=c0)  # fmt: skip


def force_scale(p: np.ndarray) -> float:
    """F_REF of a parameter vector (16,): the force scale the tolerance refers to (N)."""
    k = abs(p[1]) + abs(p[3]) + abs(p[5])
    c = abs(p[0]) + abs(p[2]) + abs(p[4])
    return float(max(k * X_REF_M, c * V_REF_M_PER_S))


def _block_error(co: dict[str, float], dt: float) -> str:
    if not all(math.isfinite(co[k]) for k in ("lam", "kx", "cu", "aa", "a", "fout", "wgt")):
        return "a coefficient of eq. 3 or 4 is not finite (c1 = 0 or c0 + c2 = 0?)"
    if abs(co["lam"]) * dt > LAM_DT_MAX:
        return (
            f"the block relaxes in {1.0 / abs(co['lam']):.3g} s, below 1e-8 of a sample: "
            "eq. 3 or 4 is algebraic to working precision"
        )
    return domain_error(co["A"], co["beta"], co["gamma"], co["n"])


# A refused set's rows read this 2-node table (xi = lambda on [0, 1]) so that the lanes' masked
# arithmetic stays in bounds; OK = 0 fails them at their first step.
DUMMY_SEGMENTS = dict(
    OFFD=0.0, L0D=-1.0, IDLD=1.0, IMD=1.0, OFFU=0.0, IDLU=1.0, IMU=1.0, LTOP=1.0, FTOP=0.0, OK=0.0,
    SHIFT=4.0,
)  # fmt: skip


def prepare(vectors: np.ndarray, dt: float, rtol: float) -> tuple[np.ndarray, np.ndarray, list]:
    """Tables and block constants for parameter sets (P, 16) in BW_ORDER.

    Returns (tabs: every table, flat; bc (2 P, len(BC_ROWS)): row 2 p + blk for set p's block
    blk; errors: one string per set, "" where the set is fine, else why it was refused -- its
    rows point at a dummy table and have OK = 0).
    """
    vectors = np.atleast_2d(np.asarray(vectors, dtype=np.float64))
    dl = node_spacing(rtol)
    sat_eps = min(SAT_EPS, 0.1 * rtol)
    # the dummy table: xi = lambda on [0, 1], reflecting to 0
    parts = [np.array([0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0])]
    size = 8
    bc = np.zeros((2 * len(vectors), len(BC_ROWS)))
    col = {name: i for i, name in enumerate(BC_ROWS)}
    errors = []
    for ip, p in enumerate(vectors):
        why = ""
        f_ref = force_scale(p)
        for blk in (0, 1):
            co = block_coefficients(p, blk)
            msg = _block_error(co, dt) if not why else why
            row = bc[2 * ip + blk]
            if msg:
                why = why or f"block {blk + 1}: {msg}"
                continue
            c_load, c_unload = co["gamma"] + co["beta"], co["gamma"] - co["beta"]
            W = _z_scale(co["A"], c_load, c_unload, co["n"])
            z_cap = FORCE_CAP_REF * f_ref / abs(co["a"]) if co["a"] != 0.0 else 1e6 * W
            nodes, n_down, dl_d, dl_u, sat, _ = build_table(
                c_load, c_unload, co["A"], co["n"], dl, max(z_cap / W, 1.0), sat_eps
            )
            refl = reflection(nodes, n_down, dl_d, dl_u)
            n_up = nodes.shape[0] - n_down
            vals = dict(
                LAM=co["lam"], KX=co["kx"], CU=co["cu"], AAW=co["aa"] * W, AAA=co["aa"] * co["A"],
                AW=co["A"] / W, TOL=rtol * f_ref, WGT=co["wgt"], WJ=co["wj"], FOUT=co["fout"],
                OFFD=size, L0D=-(n_down - 1) * dl_d, IDLD=1.0 / dl_d, IMD=n_down - 1,
                OFFU=size + 2 * n_down, IDLU=1.0 / dl_u, IMU=n_up - 1, LTOP=(n_up - 1) * dl_u,
                FTOP=0.0 if (sat or co["a"] == 0.0) else 1.0, OK=1.0, ZW=W, SHIFT=nodes.size,
                CUSP=1.0 if co["n"] < 1.0 else 0.0, RTOL=rtol,
            )  # fmt: skip
            for k, v in vals.items():
                row[col[k]] = v
            parts += [nodes.ravel(), refl.ravel()]
            size += 2 * nodes.size
        if why:
            for row in bc[2 * ip : 2 * ip + 2]:
                for k, v in DUMMY_SEGMENTS.items():
                    row[col[k]] = v
        errors.append(why)
    return np.concatenate(parts), bc, errors


def _z_scale(A: float, c_load: float, c_unload: float, n: float) -> float:
    """W of ``build_table``: the loading side's saturation scale (m)."""
    c = c_load if c_load != 0.0 else c_unload
    return float((A / abs(c)) ** (1.0 / n)) if c != 0.0 else 1.0
