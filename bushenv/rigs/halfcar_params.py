"""HalfCar-v0's parameters: the spec's kwargs checked, the double-wishbone geometry and its
kinematics (motion ratios, camber gain, scrub, roll centre), the bushing models per pivot, and
the analytic figures the tests check the pymunk car against (wheel rate, roll gradient).

Frame: a front view, x lateral (positive towards the car's left, the left corner at x > 0), y up
from the road at rest; the right corner is the left one mirrored. Points in the spec are the
left corner's ``[x, y]`` in m.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.rigs.common import RigError, positive, positive_int

ENV_ID = "HalfCar-v0"
SIDES = ("left", "right")
ARMS = ("lower", "upper")
# the four inner arm pivots, in the order of the model's batch columns
POSITIONS = ("lower_left", "upper_left", "lower_right", "upper_right")
POINTS = (
    "lower_arm_inner_m", "lower_arm_outer_m", "upper_arm_inner_m", "upper_arm_outer_m",
    "spring_chassis_m", "spring_arm_m", "wheel_centre_m",
)  # fmt: skip
SPLIT_K_FLOOR = 1e-3  # a split spring needs a stiffness (N/m, N m/rad); this one is nil
# An arm turns its inner pivot's bush about the bush's own axis: the rotation is a torsion, the
# reference's "torsion" parameter set (reference/planar.py), 30-60x softer than a tilt.
PIVOT_ROTATION = "torsion"
REFERENCE = "rubber-torsion"  # the registered names of that set: the judge's rubber ...
LINEAR = "linear-torsion"  # ... and the linear preset (the split's in-sub-step part)


def _point(name: str, value: Any) -> np.ndarray:
    try:
        p = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        p = np.zeros(0)
    if p.shape != (2,) or not np.isfinite(p).all():
        raise RigError(f"{ENV_ID}: {name} must be [x, y] in m (left corner), got {value!r}")
    return p


def _rotate(v: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _angle(v: np.ndarray) -> float:
    return math.atan2(v[1], v[0])


def _line_intersection(p1, d1, p2, d2) -> np.ndarray:
    """Where p1 + s d1 meets p2 + t d2 (2-D)."""
    m = np.array([[d1[0], -d2[0]], [d1[1], -d2[1]]])
    s, _ = np.linalg.solve(m, p2 - p1)
    return p1 + s * d1


class Geometry:
    """The left double wishbone at design and moved: ``pose(alpha)`` gives the lower arm turned
    by ``alpha`` (rad, CCW) about its inner pivot, the upper arm and the upright that close the
    loop (the upper ball joint on its arm's circle at the upright's fixed ball-joint distance)."""

    def __init__(self, pts: dict[str, np.ndarray], wheel_radius_m: float) -> None:
        self.pts = pts
        self.r_w = wheel_radius_m
        self.len_lower = float(np.hypot(*(pts["lower_arm_outer_m"] - pts["lower_arm_inner_m"])))
        self.len_upper = float(np.hypot(*(pts["upper_arm_outer_m"] - pts["upper_arm_inner_m"])))
        self.kingpin = pts["upper_arm_outer_m"] - pts["lower_arm_outer_m"]
        self.len_kingpin = float(np.hypot(*self.kingpin))
        if min(self.len_lower, self.len_upper, self.len_kingpin) < 1e-3:
            raise RigError(f"{ENV_ID}: the arm and upright points coincide: {pts!r}")
        self.contact = pts["wheel_centre_m"] - np.array([0.0, wheel_radius_m])

    def pose(self, alpha: float) -> dict[str, Any]:
        p = self.pts
        bl = p["lower_arm_inner_m"] + _rotate(
            p["lower_arm_outer_m"] - p["lower_arm_inner_m"], alpha
        )
        pu = p["upper_arm_inner_m"]
        d = pu - bl
        dist = float(np.hypot(*d))
        a, r = self.len_kingpin, self.len_upper
        along = (a * a - r * r + dist * dist) / (2 * dist)
        h2 = a * a - along * along
        if h2 < 0:
            raise RigError(f"{ENV_ID}: the wishbones do not close at arm angle {alpha:.3g} rad")
        e = d / dist
        n = np.array([-e[1], e[0]])
        cands = [bl + along * e + s * math.sqrt(h2) * n for s in (1.0, -1.0)]
        bu = min(cands, key=lambda c: np.hypot(*(c - p["upper_arm_outer_m"])))
        psi = _angle(bu - bl) - _angle(self.kingpin)  # the upright's rotation
        beta = _angle(bu - pu) - _angle(p["upper_arm_outer_m"] - pu)
        wheel = bl + _rotate(p["wheel_centre_m"] - p["lower_arm_outer_m"], psi)
        contact = wheel + _rotate(np.array([0.0, -self.r_w]), psi)
        spring_arm = p["lower_arm_inner_m"] + _rotate(
            p["spring_arm_m"] - p["lower_arm_inner_m"], alpha
        )
        spring_len = float(np.hypot(*(spring_arm - p["spring_chassis_m"])))
        return {
            "alpha": alpha, "beta": beta, "psi": psi, "lower_ball": bl, "upper_ball": bu,
            "wheel": wheel, "contact": contact, "spring_len": spring_len,
        }  # fmt: skip

    def rates(self, eps: float = 1e-5) -> dict[str, float]:
        """Derivatives per metre of vertical wheel-centre travel at design (central
        differences): arm and upright angles, contact lateral motion (scrub), spring length."""
        lo, hi = self.pose(-eps), self.pose(eps)
        dz = hi["wheel"][1] - lo["wheel"][1]
        return {
            "dalpha": 2 * eps / dz,
            "dbeta": (hi["beta"] - lo["beta"]) / dz,
            "dpsi": (hi["psi"] - lo["psi"]) / dz,
            "dx_contact": (hi["contact"][0] - lo["contact"][0]) / dz,
            "dx_wheel": (hi["wheel"][0] - lo["wheel"][0]) / dz,
            "dspring": (hi["spring_len"] - lo["spring_len"]) / dz,
        }

    def roll_centre_height(self) -> float:
        """Kinematic roll centre: the line from the contact patch through the instant centre
        (where the two arms' lines meet) crosses the car's centre plane x = 0 at this height."""
        p = self.pts
        ic = _line_intersection(
            p["lower_arm_inner_m"], p["lower_arm_outer_m"] - p["lower_arm_inner_m"],
            p["upper_arm_inner_m"], p["upper_arm_outer_m"] - p["upper_arm_inner_m"],
        )  # fmt: skip
        c = self.contact
        return float(c[1] + (ic[1] - c[1]) * (0.0 - c[0]) / (ic[0] - c[0]))


def bar_inertia(m: float, a: np.ndarray, b: np.ndarray) -> float:
    """A uniform bar's moment of inertia about its centre, kg m^2."""
    return m * float(np.sum((b - a) ** 2)) / 12.0


class HalfCarParameters:
    """The spec's kwargs checked, plus the geometry and derived figures (``equivalent_corner``,
    ``roll_gradient``)."""

    def __init__(self, kwargs: dict[str, Any], resolve_models: bool = True) -> None:
        g = positive
        self.dt = g("dt_s", kwargs["dt_s"])
        self.substeps = positive_int("physics_substeps", kwargs["physics_substeps"])
        self.h = self.dt / self.substeps
        self.m_s = g("sprung_mass_kg", kwargs["sprung_mass_kg"])
        self.i_s = g("sprung_roll_inertia_kg_m2", kwargs["sprung_roll_inertia_kg_m2"])
        self.h_cg = g("cg_height_m", kwargs["cg_height_m"])
        self.m_lower = g("lower_arm_mass_kg", kwargs["lower_arm_mass_kg"])
        self.m_upper = g("upper_arm_mass_kg", kwargs["upper_arm_mass_kg"])
        self.m_w = g("upright_mass_kg", kwargs["upright_mass_kg"])
        self.i_w = g("upright_roll_inertia_kg_m2", kwargs["upright_roll_inertia_kg_m2"])
        self.pts = {k: _point(k, kwargs[k]) for k in POINTS}
        self.r_w = g("wheel_radius_m", kwargs["wheel_radius_m"])
        self.k_s = g("spring_n_per_m", kwargs["spring_n_per_m"])
        self.c_s = g("damper_ns_per_m", kwargs["damper_ns_per_m"])
        self.k_bj = g("ball_joint_n_per_m", kwargs["ball_joint_n_per_m"])
        self.c_bj = _non_negative("ball_joint_ns_per_m", kwargs["ball_joint_ns_per_m"])
        self.k_t = g("tyre_n_per_m", kwargs["tyre_n_per_m"])
        self.c_t = _non_negative("tyre_damping_ns_per_m", kwargs["tyre_damping_ns_per_m"])
        self.k_y = g("tyre_lateral_n_per_m", kwargs["tyre_lateral_n_per_m"])
        self.c_y = _non_negative("tyre_lateral_ns_per_m", kwargs["tyre_lateral_ns_per_m"])
        self.gravity = g("gravity_m_per_s2", kwargs["gravity_m_per_s2"])
        self.max_road_step = g("max_road_step_m", kwargs["max_road_step_m"])
        self.max_road = g("max_road_height_m", kwargs["max_road_height_m"])
        self.max_ay = g("max_lateral_accel_m_per_s2", kwargs["max_lateral_accel_m_per_s2"])
        self.max_ay_step = g(
            "max_lateral_accel_step_m_per_s2", kwargs["max_lateral_accel_step_m_per_s2"]
        )
        self.force_limit = g("force_limit_n", kwargs["force_limit_n"])
        self.moment_limit = g("moment_limit_nm", kwargs["moment_limit_nm"])
        self.max_deflection = g("max_bushing_deflection_m", kwargs["max_bushing_deflection_m"])
        self.max_travel = g("max_suspension_travel_m", kwargs["max_suspension_travel_m"])
        self.max_body = g("max_body_displacement_m", kwargs["max_body_displacement_m"])
        self.max_roll = g("max_roll_rad", kwargs["max_roll_rad"])
        self.force_scale = g("force_scale_n", kwargs["force_scale_n"])
        self.reward_cap = g("reward_cap", kwargs["reward_cap"])
        self.geometry = Geometry(self.pts, self.r_w)
        if abs(self.pts["wheel_centre_m"][1] - self.r_w) > 1e-9:
            raise RigError(
                f"{ENV_ID}: wheel_centre_m's height {self.pts['wheel_centre_m'][1]!r} m must "
                f"equal wheel_radius_m {self.r_w!r} m (y is measured from the road)"
            )
        self.track = 2.0 * float(self.geometry.contact[0])
        self.m_u = self.m_lower + self.m_upper + self.m_w  # per side
        # the tyre's static load, the threshold below which a wheel lifts off
        self.tyre_static_n = (self.m_s / 2 + self.m_u) * self.gravity
        self.v_scale = self.max_road_step / self.dt
        self.roll_rate_scale = 2 * self.v_scale / self.track
        self.h_rc = self.geometry.roll_centre_height()
        from bushenv.models.planar_linear import PlanarLinear

        # the split coupling's in-sub-step part
        preset = PlanarLinear.preset(dt=self.dt, rotation=PIVOT_ROTATION)
        self.k_in, self.c_in = np.diag(preset.k_matrix).copy(), np.diag(preset.c_matrix).copy()
        self.split = {}  # car role -> (4, 2, 3): each pivot's (k_in, c_in) per coordinate
        if resolve_models:
            self.models, self.model_name = resolve_bushings(kwargs["model"], self.dt, "model")
            self.references, self.reference_name = resolve_bushings(
                kwargs["reference"], self.dt, "reference"
            )
            self.split = {"model": self.pivot_splits(self.models),
                          "reference": self.pivot_splits(self.references)}  # fmt: skip

    def pivot_splits(self, models: Any) -> np.ndarray:
        """(4, 2, 3) (k_in, c_in) of each pivot's split coupling: what a model states (a linear
        model's diagonal K, C: its held remainder is then exactly zero, as in the quarter car's
        ``car_bushings.rotation_split``), else the planar linear torsion preset's (the reference
        rubber's tangent at rest)."""
        out = np.empty((len(POSITIONS), 2, 3))
        for i, k in enumerate(POSITIONS):
            m = models[k] if isinstance(models, dict) else models
            km, cm = getattr(m, "k_matrix", None), getattr(m, "c_matrix", None)
            if km is None or cm is None:
                out[i] = self.k_in, self.c_in
            else:
                out[i, 0] = np.maximum(np.diag(km), SPLIT_K_FLOOR)
                out[i, 1] = np.maximum(np.diag(cm), 0.0)
        return out

    # ----- analytic figures -------------------------------------------------------------------
    def equivalent_corner(self, k_bushing=None, c_bushing=None) -> dict[str, float]:
        """One corner as a vertical spring-damper-mass at the wheel centre, for small motion
        about design: wheel rate and damping (coil through its motion ratio, the two arm
        bushings' rotation stiffness and damping through the arms' angle rates, the lateral
        tyre through the scrub) and the unsprung mass (arms and upright, kinetic energy per
        wheel speed^2). ``k_bushing``, ``c_bushing``: (3,) diagonal of the arm bushings (default
        the linear torsion preset's, ``LINEAR``)."""
        k_b = self.k_in if k_bushing is None else np.asarray(k_bushing)
        c_b = self.c_in if c_bushing is None else np.asarray(c_bushing)
        g, p = self.geometry, self.pts
        r = g.rates()
        k_w = self.k_s * r["dspring"] ** 2 + k_b[2] * (r["dalpha"] ** 2 + r["dbeta"] ** 2)
        c_w = self.c_s * r["dspring"] ** 2 + c_b[2] * (r["dalpha"] ** 2 + r["dbeta"] ** 2)
        k_lat, c_lat = self.k_y * r["dx_contact"] ** 2, self.c_y * r["dx_contact"] ** 2
        i_lo = bar_inertia(self.m_lower, p["lower_arm_inner_m"], p["lower_arm_outer_m"])
        i_up = bar_inertia(self.m_upper, p["upper_arm_inner_m"], p["upper_arm_outer_m"])
        m_eff = (
            (i_lo + self.m_lower * g.len_lower**2 / 4) * r["dalpha"] ** 2
            + (i_up + self.m_upper * g.len_upper**2 / 4) * r["dbeta"] ** 2
            + self.m_w * (1.0 + r["dx_wheel"] ** 2)
            + self.i_w * r["dpsi"] ** 2
        )
        return {
            "wheel_rate_n_per_m": k_w, "wheel_damping_ns_per_m": c_w,
            "scrub_rate_n_per_m": k_lat, "scrub_damping_ns_per_m": c_lat,
            "unsprung_mass_kg": m_eff, **r,
        }  # fmt: skip

    def roll_gradient(self, k_bushing=None) -> float:
        """Steady body roll per lateral acceleration, rad per m/s^2 (small angles)::

            phi / a_y = m_s (h_cg - h_rc) / K_s + 2 dF_z / (k_t T a_y),
            K_s = k_w T^2 / 2,  dF_z = a_y (m_s h_cg + 2 m_u r_w) / T

        K_s the suspension's roll stiffness from the wheel rate k_w (coil and the arm
        bushings' rotation, ``equivalent_corner``) at track T; h_rc the kinematic roll centre;
        the second term the roll of the axle on its tyres under the load transfer dF_z (the
        unsprung masses taken at the wheel centre). Gravity's overturning moment m_s g
        (h_cg - h_rc) phi is absent, as in the car (motion about static equilibrium)."""
        k_w = self.equivalent_corner(k_bushing)["wheel_rate_n_per_m"]
        t = self.track
        k_roll = k_w * t * t / 2
        d_fz = (self.m_s * self.h_cg + 2 * self.m_u * self.r_w) / t
        return self.m_s * (self.h_cg - self.h_rc) / k_roll + 2 * d_fz / (self.k_t * t)


def _non_negative(name: str, value: Any) -> float:
    v = positive(name, value) if value != 0 else 0.0
    return float(v)


def resolve_bushings(spec: Any, dt: float, what: str) -> tuple[Any, str]:
    """The four pivots' models: one spec for all four (a registered three-axis name, a
    three-axis ``.npz`` or a model object), run as ONE model with four histories (one batched
    step per car), or a table ``{lower_left = ..., upper_left = ..., lower_right = ...,
    upper_right = ...}`` of four, each its own model. Returns (model or dict, label)."""
    from bushenv.rigs.common import resolve_model

    def one(value: Any, where: str):
        if what == "reference" and isinstance(value, str) and value == "none":
            raise RigError(f"{ENV_ID}: {where}: the car runs a reference twin; give one")
        return resolve_model(value, dt=dt, coords=3, what=where, env_id=ENV_ID)

    if isinstance(spec, dict):
        if sorted(spec) != sorted(POSITIONS):
            raise RigError(
                f"{ENV_ID}: {what} as a table needs exactly the keys {list(POSITIONS)}, got "
                f"{sorted(spec)}"
            )
        models = {k: one(spec[k], f"{what}.{k}") for k in POSITIONS}
        for m in models.values():
            m.reset(1)
        return models, "/".join(models[k].name for k in POSITIONS)
    model = one(spec, what)
    model.reset(len(POSITIONS))
    label = Path(str(spec)).name if isinstance(spec, str | Path) else model.name
    return model, label
