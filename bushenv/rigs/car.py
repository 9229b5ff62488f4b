"""The quarter car of QuarterCar-v0: its parameters, its pymunk bodies, and its bounds.

``CarParameters`` checks the spec's kwargs (shared by the pymunk env, the array integrator
``quartercar_batch`` and the vector env); ``Car`` builds one car in a pymunk space, ``CarPair``
steps a model car beside its reference twin; ``car_verdict``
decides an episode's end from both cars' bushing forces (``divergence.force_termination``) and
bounds, for one car pair (floats) or N pairs ((N,) arrays) alike.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np
import pymunk

from bushenv.divergence import force_termination
from bushenv.models import BushingModel
from bushenv.models.linear import TABLE1
from bushenv.rigs.actions import check_profile
from bushenv.rigs.car_verdict import CAR, MODEL_ERROR_PREFIX, force_reason  # noqa: F401
from bushenv.rigs.common import (
    MODEL_ERRORS,
    RigError,
    model_error_text,
    model_label,
    positive,
    positive_int,
    resolve_model,
    resolve_reference,
)
from bushenv.rigs.coupling import (
    LONG_ARM_M,
    SplitBushing,
    SplitRotation,
    implicit_euler_damping,
    inverse_mass_along,
    space_stepper,
)

AXES = ("radial", "axial")  # radial: vertical at the arm's inner end; axial: along the arm
DAMPING_ANGLE_STEP = 0.005  # rad; see Car.update_damping
BODIES = ("chassis", "unsprung", "road")


def axis_models(
    spec: Any, dt: float, reference: bool, trust_reference: bool = False
) -> dict[str, BushingModel]:
    """One model per bushing axis: a name or path (the same for both axes, each axis' own
    preset or file), or a dict ``{"radial": ..., "axial": ...}`` of names, paths or objects.
    References go through the one judging setup (vetted, ``rigs.common.resolve_reference``)."""

    def resolve(s: Any, axis: str, dt: float) -> BushingModel:
        if reference:
            return resolve_reference(s, axis, dt, trust_reference=trust_reference, where=CAR)
        return resolve_model(s, axis, dt)

    if isinstance(spec, dict):
        missing = [a for a in AXES if a not in spec]
        if missing or set(spec) - set(AXES):
            raise RigError(f"a per-axis model needs exactly the keys {AXES}, got {sorted(spec)}")
        return {a: resolve(spec[a], a, dt) for a in AXES}
    if isinstance(spec, BushingModel):
        raise RigError(
            "a model object is for one axis; pass {'radial': obj_r, 'axial': obj_a} instead"
        )
    return {a: resolve(spec, a, dt) for a in AXES}


def axis_label(models: dict[str, BushingModel], spec: Any) -> str:
    if isinstance(spec, str | os.PathLike):
        return model_label(models["radial"], spec)
    return "/".join(models[a].name for a in AXES)


def check_road(profile: Any, max_height_m: float, max_step_m: float) -> np.ndarray:
    """A replayable road: finite (T,) or (T, N), |h| <= max_height_m and each sample (the road
    starting at 0) at most ``max_step_m`` from the previous one."""
    return check_profile(
        "road excitation",
        profile,
        "road",
        max_height_m,
        "|h| = {value:.6g} m exceeds max_road_height_m " + f"{max_height_m:.6g} m",
        max_step_m,
        "a change of {value:.6g} m exceeds max_road_step_m "
        + f"{max_step_m:.6g} m (the road starts at 0)",
    )


class CarParameters:
    """The spec's kwargs checked, plus derived quantities. Shared with ``quartercar_batch``."""

    def __init__(self, kwargs: dict[str, Any], resolve_models: bool = True) -> None:
        g = positive
        self.dt = g("dt_s", kwargs["dt_s"])
        self.substeps = positive_int("physics_substeps", kwargs["physics_substeps"])
        self.h = self.dt / self.substeps
        self.m_s = g("sprung_mass_kg", kwargs["sprung_mass_kg"])
        self.m_a = g("arm_mass_kg", kwargs["arm_mass_kg"])
        self.m_w = g("wheel_mass_kg", kwargs["wheel_mass_kg"])
        self.i_w = g("wheel_roll_inertia_kg_m2", kwargs["wheel_roll_inertia_kg_m2"])
        self.L = g("arm_length_m", kwargs["arm_length_m"])
        self.mount = g("spring_mount_fraction", kwargs["spring_mount_fraction"])
        if self.mount > 1:
            raise RigError(f"spring_mount_fraction must be in (0, 1], got {self.mount!r}")
        self.H = g("coilover_length_m", kwargs["coilover_length_m"])
        self.k_s = g("spring_n_per_m", kwargs["spring_n_per_m"])
        self.c_s = g("damper_ns_per_m", kwargs["damper_ns_per_m"])
        self.k_t = g("tyre_n_per_m", kwargs["tyre_n_per_m"])
        self.r_w = g("wheel_radius_m", kwargs["wheel_radius_m"])
        self.gravity = g("gravity_m_per_s2", kwargs["gravity_m_per_s2"])
        self.max_road_step = g("max_road_step_m", kwargs["max_road_step_m"])
        self.max_road = g("max_road_height_m", kwargs["max_road_height_m"])
        self.force_limit = g("force_limit_n", kwargs["force_limit_n"])
        self.max_deflection = g("max_bushing_deflection_m", kwargs["max_bushing_deflection_m"])
        self.max_travel = g("max_suspension_travel_m", kwargs["max_suspension_travel_m"])
        self.max_body = g("max_body_displacement_m", kwargs["max_body_displacement_m"])
        self.force_scale = g("force_scale_n", kwargs["force_scale_n"])
        self.reward_cap = g("reward_cap", kwargs["reward_cap"])
        # the unsprung body: arm (uniform bar 0..L) + wheel assembly at L
        self.m_u = self.m_a + self.m_w
        self.x_cm = (self.m_a * self.L / 2 + self.m_w * self.L) / self.m_u
        self.i_u = (
            self.m_a * self.L**2 / 12
            + self.m_a * (self.L / 2 - self.x_cm) ** 2
            + self.i_w
            + self.m_w * (self.L - self.x_cm) ** 2
        )
        # the tyre's static load: below -tyre_static_n of dynamic force the wheel lifts off
        self.tyre_static_n = (self.m_s + self.m_a + self.m_w) * self.gravity
        self.v_scale = self.max_road_step / self.dt  # fastest road rate, scales velocities
        # the split coupling's in-sub-step linear part: the Table-1 Kelvin-Voigt bushing
        self.k_in = {a: TABLE1[a]["k_n_per_m"] for a in AXES}
        self.c_in = {a: TABLE1[a]["c_ns_per_m"] for a in AXES}
        # a planar arm bushing: one three-axis model for axial, radial and the arm's rotation
        self.arm_bushing = kwargs.get("arm_bushing", "")
        self.planar = not (isinstance(self.arm_bushing, str) and self.arm_bushing == "")
        self.moment_limit = g("arm_moment_limit_nm", kwargs.get("arm_moment_limit_nm", 2500.0))
        self.rotation_in: dict[str, tuple[float, float]] = {}  # car role -> (k_in, c_in)
        if resolve_models and self.planar:
            from bushenv.rigs.car_planar import resolve_arm

            resolve_arm(self, kwargs)
        elif resolve_models:
            self.models = axis_models(kwargs["model"], self.dt, reference=False)
            self.references = axis_models(
                kwargs["reference"],
                self.dt,
                reference=True,
                trust_reference=bool(kwargs.get("trust_reference", False)),
            )
            self.model_name = axis_label(self.models, kwargs["model"])
            self.reference_name = axis_label(self.references, kwargs["reference"])


class Car:
    """One quarter car in a pymunk space (no gravity: motion about static equilibrium). Cars
    share a space without touching (no shapes), so one ``space.step`` moves them all.

    Bodies: the chassis (sprung mass) on a vertical GrooveJoint, not rotating; the unsprung body
    (control arm, a uniform bar from the bushing at x = 0 to x = L, with the wheel and knuckle
    fixed at its outer end -- seen from the front the wheel turns with the arm, a swing arm);
    the road (kinematic, under the wheel). Springs: the coil-over from the chassis to the arm
    at ``mount`` L (DampedSpring); the tyre from the road to the wheel centre (a long-arm spring,
    vertical, unilateral: it never pulls harder than the static load, so the wheel lifts off);
    the bushing from the chassis to the arm's inner end, radial (vertical) and axial
    (horizontal), each a ``SplitBushing``. Dampers act as implicit Euler
    (``implicit_euler_damping``).
    """

    def __init__(
        self, p: CarParameters, space: pymunk.Space | None = None, role: str = "model"
    ) -> None:
        self.p = p
        self.role = role  # "model" or "reference": which bushing's rotation split it uses
        self.space = space = space if space is not None else pymunk.Space()
        ground = space.static_body
        L = p.L
        self.chassis = pymunk.Body(p.m_s, math.inf)
        self.unsprung = pymunk.Body(p.m_u, p.i_u)
        self.road = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        space.add(self.chassis, self.unsprung, self.road)
        # local points of the unsprung body (origin at its centre of mass)
        self.arm_inner = (-p.x_cm, 0.0)
        self.arm_mount = (p.mount * L - p.x_cm, 0.0)
        self.wheel_centre = (L - p.x_cm, 0.0)
        self.coil_top = (p.mount * L, p.H)
        self.groove = pymunk.GrooveJoint(ground, self.chassis, (0.0, -1.0), (0.0, 1.0), (0, 0))
        self.coil = pymunk.DampedSpring(
            self.chassis, self.unsprung, self.coil_top, self.arm_mount, p.H, p.k_s, p.c_s
        )
        self.tyre = pymunk.DampedSpring(
            self.road, self.unsprung, (0.0, -LONG_ARM_M), self.wheel_centre, LONG_ARM_M, p.k_t, 0
        )
        k_t, lift = p.k_t, -p.tyre_static_n

        def tyre_force(spring, dist):  # unilateral: no pull beyond the static load
            f = k_t * (LONG_ARM_M - dist)
            return f if f > lift else lift

        self.tyre.force_func = tyre_force
        space.add(self.groove, self.coil, self.tyre)
        self.radial = SplitBushing(
            space, self.chassis, self.unsprung, (0.0, 0.0), self.arm_inner, (0.0, 1.0),
            p.k_in["radial"], p.c_in["radial"], p.h,
        )  # fmt: skip
        self.axial = SplitBushing(
            space, self.chassis, self.unsprung, (0.0, 0.0), self.arm_inner, (1.0, 0.0),
            p.k_in["axial"], p.c_in["axial"], p.h,
        )  # fmt: skip
        self.rotation = None
        if p.planar:  # the bushing also carries the arm's rotation (a moment)
            k_in, c_in = p.rotation_in[role]
            self.rotation = SplitRotation(space, self.chassis, self.unsprung, k_in, c_in, p.h)
        self._damping_angle = 0.0  # the arm's angle the dampers were last computed for
        self.reset()

    def reset(self) -> None:
        """Back to ride height at rest. Callers wanting bit-exact repeatability build a new
        ``Car`` instead: chipmunk warm-starts its constraints from the last impulses."""
        p = self.p
        for body, pos in (
            (self.chassis, (0.0, 0.0)),
            (self.unsprung, (p.x_cm, 0.0)),
            (self.road, (p.L, 0.0)),
        ):
            body.position = pos
            body.velocity = (0.0, 0.0)
            body.angle = 0.0
            body.angular_velocity = 0.0
        self.radial.release()
        self.axial.release()
        if self.rotation is not None:
            self.rotation.release()
        self._damping_angle = 0.0
        self.update_damping(force=True)

    def update_damping(self, force: bool = False) -> None:
        """Implicit-Euler dampers for the current configuration. The effective masses they use
        change only with the arm's angle, so they are recomputed when it has moved by more
        than ``DAMPING_ANGLE_STEP`` (0.3 degree) since the last time (or when ``force``)."""
        angle = self.unsprung.angle
        if not force and abs(angle - self._damping_angle) < DAMPING_ANGLE_STEP:
            return
        self._damping_angle = angle
        self.radial.update_damping()
        self.axial.update_damping()
        top = self.chassis.local_to_world(self.coil_top)
        bottom = self.unsprung.local_to_world(self.arm_mount)
        dx, dy = bottom.x - top.x, bottom.y - top.y
        n = math.hypot(dx, dy)
        k = inverse_mass_along(
            self.chassis, self.unsprung, self.coil_top, self.arm_mount, (dx / n, dy / n)
        )
        self.coil.damping = implicit_euler_damping(self.p.c_s, self.p.h, k)

    def bushing_motion(self) -> tuple[float, float, float, float]:
        """(x_radial, v_radial, x_axial, v_axial): the arm's inner end relative to the chassis'
        bushing centre (the chassis does not rotate, so its frame is the world's)."""
        cp = self.chassis.position
        cv = self.chassis.velocity
        pb = self.unsprung.local_to_world(self.arm_inner)
        vb = self.unsprung.velocity_at_local_point(self.arm_inner)
        return pb.y - cp.y, vb.y - cv.y, pb.x - cp.x, vb.x - cv.x

    def bushing_rotation(self) -> tuple[float, float]:
        """(theta, omega): the arm's rotation relative to the chassis, rad and rad/s."""
        u, c = self.unsprung, self.chassis
        return u.angle - c.angle, u.angular_velocity - c.angular_velocity

    def body_state(self) -> tuple[float, float, float, float]:
        """(chassis y, chassis vy, wheel centre y, wheel centre vy) from ride height."""
        w = self.unsprung.local_to_world(self.wheel_centre)
        vw = self.unsprung.velocity_at_local_point(self.wheel_centre)
        return self.chassis.position.y, self.chassis.velocity.y, w.y, vw.y

    # ----- pickling: a car continues bit for bit in a new pymunk space ---------------------------
    def _springs(self) -> dict[str, pymunk.DampedSpring]:
        return {"radial": self.radial.spring, "axial": self.axial.spring, "coil": self.coil}

    def snapshot(self) -> dict[str, Any]:
        """The car's state between two model steps: the bodies' motion, the springs' rest
        lengths (the held remainders) and damping coefficients, and the damping angle."""
        return {
            "bodies": {
                name: (tuple(b.position), tuple(b.velocity), b.angle, b.angular_velocity)
                for name in BODIES
                for b in (getattr(self, name),)
            },
            "springs": {k: (s.rest_length, s.damping) for k, s in self._springs().items()},
            "held_n": (self.radial.held_n, self.axial.held_n),
            "damping_angle": self._damping_angle,
            **(
                {}
                if self.rotation is None
                else {"rotation": (self.rotation.spring.rest_angle, self.rotation.held_nm)}
            ),
        }

    def restore(self, snapshot: dict[str, Any]) -> None:
        """Set the state ``snapshot`` recorded (on this car or another with equal parameters)."""
        for name, (position, velocity, angle, omega) in snapshot["bodies"].items():
            body = getattr(self, name)
            body.position, body.velocity = position, velocity
            body.angle, body.angular_velocity = angle, omega
        for key, (rest_length, damping) in snapshot["springs"].items():
            spring = self._springs()[key]
            spring.rest_length, spring.damping = rest_length, damping
        self.radial.held_n, self.axial.held_n = snapshot["held_n"]
        self._damping_angle = snapshot["damping_angle"]
        if "rotation" in snapshot:
            self.rotation.spring.rest_angle, self.rotation.held_nm = snapshot["rotation"]

    def __getstate__(self) -> dict[str, Any]:
        # pymunk drops a spring's force_func when pickling (the unilateral tyre): rebuild instead
        return {"p": self.p, "snapshot": self.snapshot(), "role": self.role}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(state["p"], role=state.get("role", "model"))
        self.restore(state["snapshot"])


class CarPair:
    """The model car and its reference twin over one road, each in its own pymunk space:
    nothing the model car does (a blow-up, a NaN) can reach the twin through a shared solver or
    body. Built fresh at every episode (no warm-start impulses from the last one); pickles and
    deep-copies as its two cars do."""

    def __init__(self, p: CarParameters) -> None:
        self.p = p
        self.car = Car(p, pymunk.Space())
        self.twin = Car(p, pymunk.Space(), "reference")
        self._space_steps = self._steppers()

    def _steppers(self) -> tuple:
        """The two spaces' step calls (chipmunk handles: rebuilt, never pickled)."""
        return space_stepper(self.car.space), space_stepper(self.twin.space)

    def __getstate__(self) -> dict[str, Any]:
        return {"p": self.p, "car": self.car, "twin": self.twin}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._space_steps = self._steppers()

    def sample(self, car: Car, models: dict[str, BushingModel]):
        """(motion, forces, why) of ``car`` at t_k: the bushing's (x, v) per axis, both axis
        models' forces, and why they cannot be applied ("" if they can). A force that raised,
        is not finite or exceeds ``force_limit_n`` is judged *before* it is applied and never
        applied (the car keeps the last held remainder, so its state stays finite); otherwise
        the remainders are held for the coming step."""
        car.update_damping()
        motion = car.bushing_motion()
        if "arm" in models:
            from bushenv.rigs.car_planar import sample_planar

            return motion, *sample_planar(self.p, car, models["arm"], motion)
        xr, vr, xa, va = motion
        try:
            forces = (models["radial"].step(xr, vr), models["axial"].step(xa, va))
        except MODEL_ERRORS as exc:  # a model refusing to go on, 1/0, overflow, ...
            return motion, (math.nan, math.nan), f"model raised {type(exc).__name__}: {exc}"
        except Exception as exc:  # the model's own bug: ends the episode, not a divergence
            return motion, (math.nan, math.nan), MODEL_ERROR_PREFIX + model_error_text(exc)
        why = force_reason(*forces, self.p.force_limit)
        if not why:
            car.radial.hold(forces[0], xr, vr)
            car.axial.hold(forces[1], xa, va)
        return motion, forces, why

    def integrate(self, h0: float, h: float) -> None:
        """Both cars through ``physics_substeps`` pymunk steps, the road moving h0 -> h."""
        p = self.p
        road_v = (h - h0) / p.dt
        self.car.road.velocity = (0.0, road_v)
        self.twin.road.velocity = (0.0, road_v)
        h_sub = p.h
        for step in self._space_steps:
            for _ in range(p.substeps):
                step(h_sub)
        for car in (self.car, self.twin):  # exact road position, no drift from integrating
            car.road.position = (p.L, h)
            car.road.velocity = (0.0, 0.0)


def beyond_bounds(p: CarParameters, yc, yw, xr, xa):
    """Whether a car's state left its physical bounds: chassis and wheel heights ``yc``, ``yw``
    and bushing deflections ``xr``, ``xa`` (m; floats or (N,) arrays) not finite, a deflection
    beyond ``max_bushing_deflection_m``, travel beyond ``max_suspension_travel_m`` or a body
    beyond ``max_body_displacement_m``."""
    with np.errstate(invalid="ignore"):
        finite = np.isfinite(yc) & np.isfinite(yw) & np.isfinite(xr) & np.isfinite(xa)
        deflection = (np.abs(xr) > p.max_deflection) | (np.abs(xa) > p.max_deflection)
        travel = np.abs(yw - yc) > p.max_travel
        body = (np.abs(yc) > p.max_body) | (np.abs(yw) > p.max_body)
    return ~finite | deflection | travel | body


def car_verdict(p: CarParameters, forces_model, forces_reference, bounds_model, bounds_reference):
    """(terminated, truncated) of the model car beside its twin.

    ``forces_*``: (2,) or (2, N) radial and axial bushing forces, N (with a planar arm bushing
    (3,) or (3, N), the moment last, N m, judged by ``arm_moment_limit_nm``); ``bounds_*``: the
    cars' ``beyond_bounds``. The force criteria are ``divergence.force_termination``'s (not
    finite, or beyond ``force_limit_n`` while the twin's is within); the twin beyond its own
    bounds or force limit truncates (the road is too harsh to judge), and that comes first."""
    limit = p.force_limit
    if len(forces_model) == 3:  # a planar arm bushing: radial, axial, moment
        limit = np.array([p.force_limit, p.force_limit, p.moment_limit])
        limit = limit[:, None] if np.ndim(forces_model) == 2 else limit
    non_finite, model_over, reference_over = force_termination(
        forces_model, forces_reference, limit
    )
    twin_out = reference_over.any(axis=0) | bounds_reference
    model_out = non_finite.any(axis=0) | model_over.any(axis=0) | bounds_model
    return model_out & ~twin_out, twin_out


def out_of_bounds(p: CarParameters, yc, yw, xr, xa, fr, fa) -> str:
    """Why a car's state left its physical bounds ("" if it did not)."""
    values = (yc, yw, xr, xa, fr, fa)
    if not all(math.isfinite(v) for v in values):
        return "state or bushing force is not finite"
    if abs(fr) > p.force_limit or abs(fa) > p.force_limit:
        return f"|bushing force| = {max(abs(fr), abs(fa)):.6g} N exceeds {p.force_limit:.6g} N"
    if abs(xr) > p.max_deflection or abs(xa) > p.max_deflection:
        return (
            f"bushing deflection {max(abs(xr), abs(xa)) * 1e3:.4g} mm exceeds "
            f"{p.max_deflection * 1e3:.4g} mm"
        )
    if abs(yw - yc) > p.max_travel:
        return f"suspension travel {abs(yw - yc):.4g} m exceeds {p.max_travel:.4g} m"
    if abs(yc) > p.max_body or abs(yw) > p.max_body:
        return f"body displacement {max(abs(yc), abs(yw)):.4g} m exceeds {p.max_body:.4g} m"
    return ""
