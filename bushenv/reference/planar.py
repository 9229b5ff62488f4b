"""The planar reference rubber: the one-axis reference's physics in three coordinates, coupled.

q = (u_a m, u_r m, theta rad), f = (F_a N, F_r N, M N m), bushing frame, fixed ``dt``::

    f = f_e(q) + C v + sum_j P_j + sum_n z_n + noise

| effect     | parameters                                  | acts on                          |
|------------|---------------------------------------------|----------------------------------|
| coupling   | coupling = (gamma_a, dip, theta_m_rad, u_c_m) | the strain energy (elastic.py) |
| hardening  | hardening_m (L_a m, L_r m, L_t rad)         | + k_i q_i^3 / L_i^2 per coordinate |
| relaxation | relax_weight (J, 3), relax_tau_s (J,)       | the elastic force VECTOR (QLV)   |
| friction   | friction_fmax (3,), friction_x2 (3,)        | the deflection VECTOR (vector Iwan) |
| noise      | noise_std (3,), seed                        | the load cell (measurement)      |

``f_e`` is the gradient of the coupled strain energy of ``elastic.py`` (radial deflection
stiffens axial shear; the radial force falls then rises under rotation, Kadlowec, Wineman &
Hulbert 2003). With ``coupling`` off, f_e is diagonal: k_i q_i (+ hardening).

**Relaxation** is Fung's quasi-linear viscoelasticity: each Maxwell branch j relaxes the
increments of the coupled elastic force, P_j' = G_j (.) d f_e/dt - P_j / tau_j, integrated
exactly for f_e linear between samples; G_j holds one weight per coordinate. A branch thus
remembers the vector history (a rotation relaxes radial force through f_e's coupling). In one
axis without coupling and hardening it is the one-axis reference's branch with k_j = G_j k.

**Friction** is an Iwan model in three coordinates: N elements, each a spring k0_i / N per
coordinate (k0_i = fmax_i / x2_i) in series with a slider whose yield surface is the ellipsoid
sum_i (z_i / f_ni)^2 <= 1 (f_ni = k0_i / N * 2 x2_i (n + 1/2) / N): sliding in one coordinate
lowers the resistance left in the others (``friction_yield="vector"``); ``"axis"`` slides each
coordinate on its own (a box). In one axis both are the one-axis reference's Iwan law.

Not ported from the one-axis reference: thermal softening, load-cell delay and fixture inertia.

Presets (``PlanarRubber.preset()``): axial and radial stiffness, damping, relaxation, friction
and hardening are the one-axis reference's calibrated presets (which reproduce seed 000
Table 1 by linear fit); the rotation is one of two named parameter sets (``ROTATIONS``):

- ``"cardanic"`` (the default; BushRig3-v0's): ASSUMED, typical of a car's control-arm bushing
  in its cardanic (tilt) mode: k_t = 3000 N m/rad (52 N m/deg), damping with the radial loss
  time c_r / k_r, relaxation weights of the radial axis, friction scaled as the radial one
  (fmax = 0.25 k_t theta_1 with theta_1 = 0.05 rad the rotation at amplitude index n = 1, x2 =
  theta_1 * 0.15), hardening at 0.3 rad.
- ``"torsion"`` (the half car's: an arm turns its pivot's bush about the bush's own axis):
  DERIVED from the bush's geometry. For a bonded annulus of radii a < b and length L, axial
  shear gives K_a = 2 pi G L / ln(b/a) (Adkins & Gent, Br. J. Appl. Phys. 5 (1954) 354) and
  torsion K_t = 4 pi G L / (1/a^2 - 1/b^2) (as García Tárrago, Kari, Viñolas & Gil-Negrete use
  it, J. Strain Anal. Eng. Des. 42 (2007) 13), so K_t = K_a * 2 ln(b/a) / (1/a^2 - 1/b^2)
  whatever G and L. Geometry: seed 002 Table 2's bush (inner steel 15 mm, outer steel 50 mm
  with a 3 mm wall, length 63 mm): a = 7.5 mm, b = 22 mm, K_t / K_a = 1.370e-4 m^2/rad; seed
  000 Table 1's axial 379.68 kN/m then gives G = 1.03 MPa (a natural rubber's) and K_t = 52.0
  N m/rad. Torsion shears the rubber as the axial mode does, so the whole rotation row is the
  axial row mapped: moment = axial force * (K_t / K_a) / l, rotation = axial deflection / l,
  with l = 2 mm / theta_1 = 0.04 m/rad (the n = 1 amplitudes): stiffness 27.9 N m/rad (the
  axial backbone's 203.5 kN/m), damping by the axial loss time, the axial relaxation weights,
  the axial friction (the same loop width at n = 1) and load-cell noise alike.
  **Calibrated range** (``calibrated_rotation_rad``): torsion shears the annulus with strain
  gamma(r) = T / (2 pi G L r^2), largest at the inner radius, gamma_a = 2 theta / (1 - a^2/b^2)
  = 2.26 theta; filled rubber stays near-linear in shear up to gamma ~ 0.5-1, so the set holds
  to gamma_a = 1: +-0.442 rad (the cardanic set's 0.15 rad stays an assumption). Hardening is
  the rubber's at a strain, so it is mapped by strain, not by the n = 1 amplitudes: the axial
  16 mm (gamma_a = u / (a ln(b/a)) = 1.98) is 0.876 rad, +25 % secant stiffness at the range's
  end as the axial row at gamma_a = 1 (the amplitude mapping put 0.4 rad, +122 % there). The
  coupling keeps its shape over the range: theta_m = 0.08 rad x 0.442 / 0.15 (0.236 rad), and
  the dip scales with k_t theta_m^2 (the radial-rotation term's share of the rotation's
  tangent as in the cardanic set, so the energy stays convex; tested over the range).

Coupling (assumed magnitudes, Kadlowec's shape): gamma_a = 0.15, dip = 0.15 at theta_m = 0.08
rad (cardanic), u_c = 2 mm. docs/planar.md tabulates the tangent stiffness.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numba as nb
import numpy as np

from bushenv.models.base import PAPER_DT
from bushenv.models.planar_base import PlanarModel, PlanarModelError, as_matrix
from bushenv.reference.planar_elastic import (
    E_D,
    E_GA,
    E_LA,
    E_LR,
    E_LT,
    E_TM,
    E_UC,
    N_EPAR,
    elastic_force,
)
from bushenv.reference.rubber import PRESETS as ONE_AXIS

EFFECTS = ("coupling", "hardening", "relaxation", "friction", "noise")
PHYSICAL_EFFECTS = EFFECTS[:4]
ROTATION_K_NM_PER_RAD = 3000.0  # assumed: a control-arm bushing, cardanic mode (52 N m/deg)
THETA_N1_RAD = 0.05  # rotation peak at amplitude index n = 1 (assumed; 2 mm over a 40 mm arm)
MAX_ROTATION_RAD = 0.15  # the rotation the planar programmes stay within (assumed)
FRICTION_YIELDS = ("vector", "axis")
ROTATIONS = ("cardanic", "torsion")  # the rotation's named parameter sets (module docstring)
# seed 002 Table 2's bush: inner steel diameter 15 mm, outer 50 mm with a 3 mm wall, length 63 mm
BUSH_INNER_RADIUS_M = 7.5e-3
BUSH_OUTER_RADIUS_M = 25.0e-3 - 3.0e-3
BUSH_LENGTH_M = 63.0e-3
PEAK_M_AT_N1 = 2.0e-3  # the translations' peak at n = 1 (bushenv.excitation)
# Filled rubber stays near-linear in shear up to a strain of about 0.5-1 (rubber design
# practice, e.g. Gent, Engineering with Rubber, Hanser 2012); the torsion set is calibrated to
# the upper end, where the hardening mapped by strain from the axial row adds 25 % (docstring)
TORSION_MAX_SHEAR_STRAIN = 1.0
THETA_M_RAD = 0.08  # the coupling's dip rotation in the cardanic set


def torsion_strain_per_rad(
    a_m: float = BUSH_INNER_RADIUS_M, b_m: float = BUSH_OUTER_RADIUS_M
) -> float:
    """Shear strain at the inner radius per rad of torsion of a bonded annulus: the moment's
    shear stress T / (2 pi r^2 L) integrated over r gives gamma_a = 2 theta / (1 - a^2/b^2)."""
    if not 0 < a_m < b_m:
        raise PlanarModelError(f"bush radii must be 0 < a < b, got a={a_m!r}, b={b_m!r}")
    return 2.0 / (1.0 - (a_m / b_m) ** 2)


def axial_strain_per_m(a_m: float = BUSH_INNER_RADIUS_M, b_m: float = BUSH_OUTER_RADIUS_M) -> float:
    """Shear strain at the inner radius per m of axial deflection: gamma_a = u / (a ln(b/a))."""
    if not 0 < a_m < b_m:
        raise PlanarModelError(f"bush radii must be 0 < a < b, got a={a_m!r}, b={b_m!r}")
    return 1.0 / (a_m * math.log(b_m / a_m))


# the torsion set's calibrated rotation: its inner radius at TORSION_MAX_SHEAR_STRAIN (0.442 rad)
TORSION_MAX_ROTATION_RAD = TORSION_MAX_SHEAR_STRAIN / torsion_strain_per_rad()
# each rotation set's calibrated range (PlanarRubber.calibrated_rotation_rad), rad
CALIBRATED_ROTATION_RAD = {"cardanic": MAX_ROTATION_RAD, "torsion": TORSION_MAX_ROTATION_RAD}


def torsion_per_axial(a_m: float = BUSH_INNER_RADIUS_M, b_m: float = BUSH_OUTER_RADIUS_M) -> float:
    """K_t / K_a of a bonded annulus, m^2/rad: K_a = 2 pi G L / ln(b/a) (Adkins & Gent 1954),
    K_t = 4 pi G L / (1/a^2 - 1/b^2) (García Tárrago et al. 2007); G and L cancel."""
    if not 0 < a_m < b_m:
        raise PlanarModelError(f"bush radii must be 0 < a < b, got a={a_m!r}, b={b_m!r}")
    return 2.0 * math.log(b_m / a_m) / (1.0 / a_m**2 - 1.0 / b_m**2)


def shear_modulus_pa(k_axial_n_per_m: float) -> float:
    """G of the stated bush from an axial stiffness: K_a ln(b/a) / (2 pi L)."""
    a, b = BUSH_INNER_RADIUS_M, BUSH_OUTER_RADIUS_M
    return k_axial_n_per_m * math.log(b / a) / (2.0 * math.pi * BUSH_LENGTH_M)


def default_parameters(rotation: str = "cardanic") -> dict[str, Any]:
    """The coupled rubber's default parameters, from the one-axis axial and radial presets;
    ``rotation`` names the rotation's parameter set (``ROTATIONS``, module docstring)."""
    if rotation not in ROTATIONS:
        raise PlanarModelError(f"reference: rotation {rotation!r}; known: {list(ROTATIONS)}")
    ax, rad = ONE_AXIS["axial"], ONE_AXIS["radial"]
    w_ax = np.array(ax["relax_k_n_per_m"]) / ax["k_n_per_m"]
    w_rad = np.array(rad["relax_k_n_per_m"]) / rad["k_n_per_m"]
    dip, theta_m = 0.15, THETA_M_RAD
    if rotation == "cardanic":
        k_t = ROTATION_K_NM_PER_RAD
        loss_s = rad["c_ns_per_m"] / rad["k_n_per_m"]
        fr_scale = rad["friction_x2_m"] / PEAK_M_AT_N1  # x2 over the radial peak at n = 1
        rot = dict(k=k_t, c=k_t * loss_s, w=w_rad, fmax=0.25 * k_t * THETA_N1_RAD,
                   x2=fr_scale * THETA_N1_RAD, hard=0.3, noise=0.2)  # fmt: skip
    else:  # the axial (shear) row mapped to the rotation
        arm = PEAK_M_AT_N1 / THETA_N1_RAD  # m of axial deflection per rad at n = 1
        force = torsion_per_axial() / arm  # N m of moment per N of axial force
        k_t = ax["k_n_per_m"] * force * arm
        # hardening is the rubber's, at a strain: the axial scale at the same inner strain
        hard = ax["hardening_x_m"] * axial_strain_per_m() / torsion_strain_per_rad()
        rot = dict(k=k_t, c=ax["c_ns_per_m"] * force * arm, w=w_ax,
                   fmax=ax["friction_fmax_n"] * force, x2=ax["friction_x2_m"] / arm,
                   hard=hard, noise=ax["noise_std_n"] * force)  # fmt: skip
        # the coupling's shape over the calibrated range as the cardanic set's over its own
        theta_m = THETA_M_RAD * TORSION_MAX_ROTATION_RAD / MAX_ROTATION_RAD
    # the radial-rotation term's share of the rotation's tangent (4 d k_r e / theta_m^2 against
    # k_t) as in the cardanic set, so the energy stays convex
    dip *= k_t / ROTATION_K_NM_PER_RAD * (theta_m / THETA_M_RAD) ** 2
    return dict(
        stiffness=(ax["k_n_per_m"], rad["k_n_per_m"], rot["k"]),
        damping=(ax["c_ns_per_m"], rad["c_ns_per_m"], rot["c"]),
        coupling=(0.15, dip, theta_m, 2.0e-3),
        hardening_m=(ax["hardening_x_m"], rad["hardening_x_m"], rot["hard"]),
        relax_weight=np.stack([w_ax, w_rad, rot["w"]], axis=1),
        relax_tau_s=ax["relax_tau_s"],
        friction_fmax=(ax["friction_fmax_n"], rad["friction_fmax_n"], rot["fmax"]),
        friction_x2=(ax["friction_x2_m"], rad["friction_x2_m"], rot["x2"]),
        noise_std=(ax["noise_std_n"], rad["noise_std_n"], rot["noise"]),
    )


@nb.njit(cache=True)
def planar_rubber_kernel(q, v, noise, state, epar, cdamp, relax, kel, slip, vector_yield, out):
    """(T, B, 3) q, v, noise -> out; state rows: q_prev 3, f_e prev 3, P (J*3), z (N*3)."""
    T, B, _ = q.shape
    nj = relax.shape[0]
    nz = slip.shape[0]
    fe = np.empty(3)
    zt = np.empty(3)
    for t in range(T):
        for b in range(B):
            elastic_force(q[t, b, 0], q[t, b, 1], q[t, b, 2], epar, fe)
            for i in range(3):
                out[t, b, i] = fe[i] + cdamp[i] * v[t, b, i] + noise[t, b, i]
            for j in range(nj):  # relax[j] = (decay, gain, w_a, w_r, w_t)
                for i in range(3):
                    r = 6 + 3 * j + i
                    state[r, b] = state[r, b] * relax[j, 0] + relax[j, 2 + i] * relax[j, 1] * (
                        fe[i] - state[3 + i, b]
                    )
                    out[t, b, i] += state[r, b]
            r0 = 6 + 3 * nj
            for n in range(nz):
                ratio = 0.0
                for i in range(3):
                    zt[i] = state[r0 + 3 * n + i, b] + kel[i] * (q[t, b, i] - state[i, b])
                    if vector_yield:
                        ratio += (zt[i] / slip[n, i]) ** 2
                    else:
                        zt[i] = min(max(zt[i], -slip[n, i]), slip[n, i])
                scale = 1.0 / np.sqrt(ratio) if ratio > 1.0 else 1.0
                for i in range(3):
                    state[r0 + 3 * n + i, b] = zt[i] * scale
                    out[t, b, i] += zt[i] * scale
            for i in range(3):
                state[i, b] = q[t, b, i]
                state[3 + i, b] = fe[i]


class PlanarRubber(PlanarModel):
    """The planar reference rubber; see the module docstring for the force law."""

    name = "rubber"  # files written as "reference" before load through MODELS' alias
    EFFECTS: ClassVar[tuple[str, ...]] = EFFECTS
    param_names = (
        "stiffness",
        "damping",
        "coupling",
        "hardening_m",
        "relax_weight",
        "relax_tau_s",
        "friction_fmax",
        "friction_x2",
        "noise_std",
    )

    def __init__(
        self,
        stiffness: Any,
        damping: Any,
        coupling: Any = (0.0, 0.0, 1.0, 1.0),
        hardening_m: Any = (0.0, 0.0, 0.0),
        relax_weight: Any = None,
        relax_tau_s: Any = (),
        friction_fmax: Any = (0.0, 0.0, 0.0),
        friction_x2: Any = (0.0, 0.0, 0.0),
        noise_std: Any = (0.0, 0.0, 0.0),
        friction_elements: int = 10,
        friction_yield: str = "vector",
        seed: int = 0,
        effects: Any = None,
        dt: float = PAPER_DT,
        calibrated_rotation_rad: float = MAX_ROTATION_RAD,
    ) -> None:
        # beyond it the law is an extrapolation (docs/planar.md): a judge out of range
        self.calibrated_rotation_rad = float(calibrated_rotation_rad)
        if not self.calibrated_rotation_rad > 0:
            raise PlanarModelError(
                f"reference: calibrated_rotation_rad must be > 0, got {calibrated_rotation_rad!r}"
            )
        vec = {"stiffness": stiffness, "damping": damping, "hardening_m": hardening_m}
        vec |= {"friction_fmax": friction_fmax, "friction_x2": friction_x2, "noise_std": noise_std}
        for key, value in vec.items():
            a = as_matrix(f"reference: {key}", value, (3,))
            if np.any(a < 0) or (key == "stiffness" and np.any(a <= 0)):
                raise PlanarModelError(f"reference: {key} must be >= 0 (stiffness > 0), got {a}")
            setattr(self, key, a)
        self.coupling = as_matrix("reference: coupling", coupling, (4,))
        if self.coupling[2] <= 0 or self.coupling[3] <= 0 or self.coupling[1] < 0:
            raise PlanarModelError(
                "reference: coupling = (gamma_a, dip >= 0, theta_m_rad > 0, u_c_m > 0), "
                f"got {self.coupling}"
            )
        tau = np.array(relax_tau_s, dtype=np.float64).reshape(-1)
        if relax_weight is None:
            relax_weight = np.zeros((tau.size, 3))
        self.relax_weight = as_matrix("reference: relax_weight", relax_weight, (tau.size, 3))
        self.relax_tau_s = as_matrix("reference: relax_tau_s", tau, (tau.size,))
        if np.any(self.relax_tau_s <= 0) or np.any(self.relax_weight < 0):
            raise PlanarModelError("reference: relax_tau_s must be > 0 and relax_weight >= 0")
        if friction_yield not in FRICTION_YIELDS:
            raise PlanarModelError(
                f"reference: friction_yield {friction_yield!r}; known: {list(FRICTION_YIELDS)}"
            )
        self.friction_yield = friction_yield
        self.friction_elements = int(friction_elements)
        if not 1 <= self.friction_elements <= 64:
            raise PlanarModelError(
                f"reference: friction_elements must be 1..64, got {friction_elements}"
            )
        self.seed = int(seed)
        self.effects = self._switched_on(effects)
        self.dt = float(dt)
        self._n_rel, self._n_fric, self._args = self._kernel_args()
        self._rng = np.random.default_rng(self.seed)  # the noise's draws; reset restarts them
        super().__init__(dt)

    def _configured(self) -> tuple[str, ...]:
        has = {
            "coupling": self.coupling[0] != 0 or self.coupling[1] != 0,
            "hardening": bool(np.any(self.hardening_m > 0)),
            "relaxation": bool(np.any(self.relax_weight > 0)),
            "friction": bool(np.all(self.friction_fmax > 0) and np.all(self.friction_x2 > 0)),
            "noise": bool(np.any(self.noise_std > 0)),
        }
        return tuple(e for e in EFFECTS if has[e])

    def _switched_on(self, effects: Any) -> tuple[str, ...]:
        configured = self._configured()
        if effects is None:
            return configured
        wanted = (effects,) if isinstance(effects, str) else tuple(effects)
        unknown = [e for e in wanted if e not in EFFECTS]
        if unknown:
            raise PlanarModelError(
                f"reference: unknown effect(s) {unknown}; known: {list(EFFECTS)}"
            )
        missing = [e for e in wanted if e not in configured]
        if missing:
            raise PlanarModelError(f"reference: effect(s) {missing} switched on but not configured")
        return tuple(e for e in EFFECTS if e in wanted)

    def only_effects(self, names: Any) -> PlanarRubber:
        """A copy with exactly ``names`` switched on (parameters kept)."""
        return type(self).from_params(self.params, self.dt, {**self.extra_meta(), "effects": names})

    def without_effects(self, names: Any) -> PlanarRubber:
        names = (names,) if isinstance(names, str) else tuple(names)
        unknown = [n for n in names if n not in EFFECTS]
        if unknown:
            raise PlanarModelError(
                f"reference: unknown effect(s) {unknown}; known: {list(EFFECTS)}"
            )
        return self.only_effects(tuple(e for e in self.effects if e not in names))

    def elastic_params(self) -> np.ndarray:
        """The parameter vector of ``elastic.py`` with this model's switched-off parts zeroed."""
        p = np.zeros(N_EPAR)
        p[:3] = self.stiffness
        p[E_TM], p[E_UC] = self.coupling[2], self.coupling[3]
        if "coupling" in self.effects:
            p[E_GA], p[E_D] = self.coupling[0], self.coupling[1]
        if "hardening" in self.effects:
            p[E_LA], p[E_LR], p[E_LT] = self.hardening_m
        return p

    def _kernel_args(self) -> tuple[int, int, tuple]:
        """(relaxation branches, friction elements, the kernel's parameter arguments)."""
        on = set(self.effects)
        if "relaxation" in on:
            tau = self.relax_tau_s
            decay = np.exp(-self.dt / tau)
            gain = -np.expm1(-self.dt / tau) * tau / self.dt  # exact for f_e linear in a sample
            relax = np.column_stack([decay, gain, self.relax_weight])
        else:
            relax = np.zeros((0, 5))
        n = self.friction_elements if "friction" in on else 0
        k0 = self.friction_fmax / np.where(self.friction_x2 > 0, self.friction_x2, 1.0)
        kel = k0 / max(n, 1)
        slip = kel * 2.0 * self.friction_x2 * ((np.arange(n) + 0.5) / max(n, 1))[:, None]
        args = (
            self.elastic_params(),
            self.damping.copy(),
            np.ascontiguousarray(relax),
            kel,
            np.ascontiguousarray(slip.reshape(n, 3)),
            self.friction_yield == "vector",
        )
        return relax.shape[0], n, args

    @property
    def n_state(self) -> int:
        return 6 + 3 * getattr(self, "_n_rel", 0) + 3 * getattr(self, "_n_fric", 0)

    def reset(self, batch_size: int = 1) -> None:
        super().reset(batch_size)
        self._rng = np.random.default_rng(self.seed)

    def _advance(self, q: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        if self.state.shape[1] != q.shape[1]:
            raise PlanarModelError(
                f"reference: state for {self.state.shape[1]} histories, input has {q.shape[1]}"
            )
        if "noise" in self.effects:
            noise = self._rng.standard_normal(q.shape) * self.noise_std
        else:
            noise = np.zeros(q.shape)
        epar, cdamp, relax, kel, slip, vector_yield = self._args
        planar_rubber_kernel(
            q, v, noise, self.state, epar, cdamp, relax, kel, slip, vector_yield, out
        )

    def extra_meta(self) -> dict[str, Any]:
        meta = {
            "friction_elements": self.friction_elements,
            "friction_yield": self.friction_yield,
            "seed": self.seed,
            "effects": list(self.effects),
        }
        if self.calibrated_rotation_rad != MAX_ROTATION_RAD:  # the cardanic files as before
            meta["calibrated_rotation_rad"] = self.calibrated_rotation_rad
        return meta

    @classmethod
    def preset(
        cls,
        effects: Any = None,
        measurement: bool = True,
        seed: int = 0,
        dt: float = PAPER_DT,
        rotation: str = "cardanic",
        **overrides: Any,
    ) -> PlanarRubber:
        """The preset specimen: ``effects=None`` switches on the physical effects, and
        ``measurement`` adds the load cell's noise; ``rotation`` names the rotation's
        parameter set (``ROTATIONS``: ``"cardanic"`` a tilt, ``"torsion"`` a car's arm pivot);
        ``overrides`` replace preset parameters (or set ``friction_yield``,
        ``friction_elements``)."""
        params = default_parameters(rotation)
        unknown = [
            k
            for k in overrides
            if k not in params and k not in ("friction_yield", "friction_elements")
        ]
        if unknown:
            raise PlanarModelError(
                f"reference: unknown preset override(s) {unknown}; known: {sorted(params)}"
            )
        chosen = PHYSICAL_EFFECTS if effects is None else effects
        chosen = ((chosen,) if isinstance(chosen, str) else tuple(chosen)) + (
            ("noise",) if measurement else ()
        )
        return cls(dt=dt, seed=seed, effects=chosen, **{**params, **overrides},
                   calibrated_rotation_rad=CALIBRATED_ROTATION_RAD[rotation])  # fmt: skip

    def __repr__(self) -> str:
        return f"PlanarRubber(effects={list(self.effects)}, friction_yield={self.friction_yield!r})"
