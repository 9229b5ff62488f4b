"""Vector Bouc-Wen bushing: one hysteretic state on the deflection vector, 3x3 K, C and G.

    f = K q + C v + h (.) z + G3(q) [+ sum_m R_m p_m]   (N, N, N m; ``h`` one force scale per axis)
    G3(q)_i = sum_j G_ij q_i q_j^2             (cubic stiffness: hardening on the diagonal,
                                                stiffening of axis i by a deflection in j off it)
    u = q / d                                  (scaled deflection, d = yield deflection m, m, rad)
    dz = du - |z|^(eta - 2) z [beta |z . du| + gamma (z . du)]

z in R^3 is dimensionless. This is the biaxial Bouc-Wen form of Park, Wen & Ang (1986,
"Random vibration of hysteretic systems under bi-directional ground motions", Earthquake Eng.
Struct. Dyn. 14) with eta = 2, and its generalisation to any eta >= 1 (Wang & Wen 2000,
Harvey & Gavin 2014) in three coordinates. In one coordinate it is the classical law
z' = u' - beta |u'| |z|^(eta-1) z - gamma u' |z|^eta. Its amplitude A is 1 (absorbed into h)
and beta + gamma = 1, so z saturates on the unit sphere |z| = 1: the coordinates share one
yield surface, an ellipsoid |q / d| = 1 in deflection, and yielding in one lowers what is
left in the others (the analogue of the reference's vector Iwan friction). Proof of the
bound, exact flow: d|z|^2 = 2 (z.du)(1 - |z|^eta (gamma +- beta)), <= 0 beyond |z| = 1 when
loading (beta + gamma = 1) and always when unloading (gamma - beta <= 0); so |z| <= max(1,
|z_0|). With beta + gamma = 1, gamma <= beta means beta >= 0.5.

Integration: within a sample q moves on a straight line (du constant), and the law is rate
independent, so z is advanced along the path by classical RK4 in ``ceil(|du| / 0.1)``
substeps (shorter ones where eta (beta + |gamma|) > 5, for stability; at most
``MAX_SUBSTEPS``). The linear part is summed in the same compiled kernel, so a loop of
``step`` equals a batched ``simulate`` bit for bit.

``yield_surface="axis"`` runs the classical law on each coordinate alone (three independent
Bouc-Wen elements, a box of yield limits, no shared surface): the per-axis kind of the same
model, for measuring what the shared surface is worth.

Optionally a relaxation (``relax_tau`` (M,) s, ``relax_gain`` (M, 3, 3)): the Prony series of
``relaxation.py`` on the deflection vector. Files written before it existed have none.
``relaxation_form="qlv"`` relaxes the elastic force K q + G3(q) instead (the quasi-linear
form of ``relaxation.py``; ``relax_gain`` then dimensionless): the relaxing force follows the
hardening and the coupled stiffening. Files without the setting are of the constant form and
give the forces they always gave.

State (6 + 3 M, B): z (3), the previous deflection (3), the branches' deflections (3 M; their
elastic forces in the quasi-linear form), at rest zero.
"""

from __future__ import annotations

from typing import Any

import numba as nb
import numpy as np

from bushenv.models.base import PAPER_DT
from bushenv.models.boucwen import relaxation
from bushenv.models.planar_base import PlanarModel, PlanarModelError, as_matrix

SUBSTEP = 0.1  # path length of one RK4 substep in scaled deflection (accurate: |h lambda| < 0.5)
MAX_SUBSTEPS = 2000
ETA_RANGE = (1.0, 8.0)
YIELD_SURFACES = ("vector", "axis")


@nb.njit(cache=True)
def _scalar(z, d, beta, gamma, eta):
    """The classical one-coordinate law (the "axis" yield surface)."""
    if z == 0.0:
        return d
    return d - abs(z) ** (eta - 2.0) * (beta * abs(z * d) + gamma * z * d) * z


@nb.njit(cache=True)
def _dz(z0, z1, z2, d0, d1, d2, beta, gamma, eta, vector, out):
    if not vector:
        out[0] = _scalar(z0, d0, beta, gamma, eta)
        out[1] = _scalar(z1, d1, beta, gamma, eta)
        out[2] = _scalar(z2, d2, beta, gamma, eta)
        return
    nz = np.sqrt(z0 * z0 + z1 * z1 + z2 * z2)
    zd = z0 * d0 + z1 * d1 + z2 * d2
    g = 0.0
    if nz > 0.0:
        g = nz ** (eta - 2.0) * (beta * abs(zd) + gamma * zd)
    out[0] = d0 - g * z0
    out[1] = d1 - g * z1
    out[2] = d2 - g * z2


@nb.njit(cache=True)
def vector_boucwen_kernel(q, v, state, k, c, g, h, d, beta, gamma, eta, vector, out):
    """(T, B, 3) q, v -> out; state rows: z (3), previous q (3)."""
    T, B, _ = q.shape
    k1 = np.empty(3)
    k2 = np.empty(3)
    k3 = np.empty(3)
    k4 = np.empty(3)
    du = np.empty(3)
    # RK4 is stable for |h lambda| < 2.78; the law's Jacobian is at most eta (beta + |gamma|)
    # on the unit ball, so h lambda stays below 0.5
    h_step = min(SUBSTEP, 0.5 / (eta * (beta + abs(gamma))))
    for t in range(T):
        for b in range(B):
            size = 0.0
            for i in range(3):
                du[i] = (q[t, b, i] - state[3 + i, b]) / d[i]
                size += du[i] * du[i]
            m = int(np.ceil(np.sqrt(size) / h_step))
            m = min(max(m, 1), MAX_SUBSTEPS)
            s0 = du[0] / m
            s1 = du[1] / m
            s2 = du[2] / m
            z0 = state[0, b]
            z1 = state[1, b]
            z2 = state[2, b]
            for _ in range(m):
                _dz(z0, z1, z2, s0, s1, s2, beta, gamma, eta, vector, k1)
                _dz(
                    z0 + 0.5 * k1[0], z1 + 0.5 * k1[1], z2 + 0.5 * k1[2],
                    s0, s1, s2, beta, gamma, eta, vector, k2,
                )  # fmt: skip
                _dz(
                    z0 + 0.5 * k2[0], z1 + 0.5 * k2[1], z2 + 0.5 * k2[2],
                    s0, s1, s2, beta, gamma, eta, vector, k3,
                )  # fmt: skip
                _dz(z0 + k3[0], z1 + k3[1], z2 + k3[2], s0, s1, s2, beta, gamma, eta, vector,
                    k4)  # fmt: skip
                z0 += (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]) / 6.0
                z1 += (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]) / 6.0
                z2 += (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2]) / 6.0
            state[0, b] = z0
            state[1, b] = z1
            state[2, b] = z2
            for i in range(3):
                state[3 + i, b] = q[t, b, i]
            for i in range(3):
                acc = h[i] * state[i, b]
                for j in range(3):
                    acc += k[i, j] * q[t, b, j] + c[i, j] * v[t, b, j]
                    acc += g[i, j] * q[t, b, i] * q[t, b, j] * q[t, b, j]
                out[t, b, i] = acc


class PlanarBoucWen(PlanarModel):
    """Vector Bouc-Wen + 3x3 stiffness, damping and cubic stiffness; see the module docstring."""

    name = "boucwen"
    param_names = (
        "k_matrix", "c_matrix", "h_force", "d_yield", "shape", "g_cubic", "relax_tau",
        "relax_gain",
    )  # fmt: skip
    optional_params = ("relax_tau", "relax_gain")  # files from before the relaxation lack them

    def __init__(
        self,
        k_matrix: Any,
        c_matrix: Any,
        h_force: Any,
        d_yield: Any,
        shape: Any = (0.5, 0.5, 2.0),
        g_cubic: Any = None,
        yield_surface: str = "vector",
        dt: float = PAPER_DT,
        relax_tau: Any = None,
        relax_gain: Any = None,
        relaxation_form: str = "constant",
    ) -> None:
        self.relax_tau, self.relax_gain = relaxation.check(relax_tau, relax_gain)
        if relaxation_form not in relaxation.FORMS:
            raise PlanarModelError(
                f"boucwen: relaxation_form {relaxation_form!r}; known: {list(relaxation.FORMS)}"
            )
        self.relaxation_form = relaxation_form
        if yield_surface not in YIELD_SURFACES:
            raise PlanarModelError(
                f"boucwen: yield_surface {yield_surface!r}; known: {list(YIELD_SURFACES)}"
            )
        self.yield_surface = yield_surface
        self.k_matrix = as_matrix("boucwen: k_matrix", k_matrix)
        self.c_matrix = as_matrix("boucwen: c_matrix", c_matrix)
        self.h_force = as_matrix("boucwen: h_force", h_force, (3,))
        self.d_yield = as_matrix("boucwen: d_yield", d_yield, (3,))
        self.shape = as_matrix("boucwen: shape", shape, (3,))
        g = np.zeros((3, 3)) if g_cubic is None else g_cubic
        self.g_cubic = as_matrix("boucwen: g_cubic", g)
        beta, gamma, eta = self.shape
        if np.any(self.d_yield <= 0):
            raise PlanarModelError(f"boucwen: d_yield must be > 0 (m, m, rad), got {self.d_yield}")
        if not (beta > 0 and abs(beta + gamma - 1.0) < 1e-9 and gamma <= beta):
            raise PlanarModelError(
                f"boucwen: shape (beta, gamma, eta) needs beta > 0, beta + gamma = 1 and "
                f"gamma <= beta, got {self.shape.tolist()}"
            )
        if not ETA_RANGE[0] <= eta <= ETA_RANGE[1]:
            raise PlanarModelError(f"boucwen: eta must lie in {list(ETA_RANGE)}, got {eta}")
        super().__init__(dt)

    @classmethod
    def preset(cls, dt: float = PAPER_DT) -> PlanarBoucWen:
        """The linear preset (seed 000 Table 1, the assumed rotation) plus the reference's
        friction as one hysteretic element: h = its friction force, d = its slip deflection."""
        from bushenv.models.planar_linear import PlanarLinear
        from bushenv.reference.planar import default_parameters

        lin, ref = PlanarLinear.preset(dt), default_parameters()
        return cls(
            lin.k_matrix,
            lin.c_matrix,
            ref["friction_fmax"],
            ref["friction_x2"],
            (0.5, 0.5, 1.0),
            dt=dt,
        )

    @property
    def n_state(self) -> int:
        return 6 + 3 * self.relax_tau.shape[0]

    def extra_meta(self) -> dict[str, Any]:
        meta: dict[str, Any] = {"yield_surface": self.yield_surface}
        if self.relaxation_form != "constant":  # files of the constant form stay as they were
            meta["relaxation_form"] = self.relaxation_form
        return meta

    def _advance(self, q: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        if self.state.shape[1] != q.shape[1]:
            raise PlanarModelError(
                f"boucwen: state for {self.state.shape[1]} histories, input has {q.shape[1]}"
            )
        beta, gamma, eta = (float(x) for x in self.shape)
        q_before = self.state[3:6].copy()
        vector_boucwen_kernel(
            q, v, self.state, self.k_matrix, self.c_matrix, self.g_cubic, self.h_force,
            self.d_yield,
            beta, gamma, eta, self.yield_surface == "vector", out,
        )  # fmt: skip
        if self.relax_tau.shape[0]:
            a, b = relaxation.coefficients(self.relax_tau, self.dt)
            if self.relaxation_form == "qlv":
                relaxation.qlv_kernel(q, q_before, self.state[6:], a, b, self.relax_gain,
                                      self.k_matrix, self.g_cubic, out)  # fmt: skip
            else:
                relaxation.relaxation_kernel(
                    q, q_before, self.state[6:], a, b, self.relax_gain, out
                )

    def hysteretic_state(self, q: np.ndarray) -> np.ndarray:
        """z along ``q`` ((T, 3) -> (T, 3)) from rest: the run with K = C = 0 and h = 1."""
        unit = type(self)(np.zeros((3, 3)), np.zeros((3, 3)), np.ones(3), self.d_yield,
                          self.shape, yield_surface=self.yield_surface, dt=self.dt)  # fmt: skip
        return unit.simulate(q, np.zeros_like(q))
