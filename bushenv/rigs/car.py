"""The quarter car of QuarterCar-v0: its parameters and its pymunk bodies.

``CarParameters`` checks the spec's kwargs (shared by the pymunk env, the array integrator
``quartercar_batch`` and the vector env) and resolves the arm's bushing models
(``car_bushings``: one per axis, or one over the arm's three coordinates); ``Car`` builds one
car in a pymunk space, ``CarPair`` steps a model car beside its reference twin, its bushing
sampled alike whatever its number of coordinates. ``car_verdict`` decides an episode's end from
both cars' bushing forces and bounds.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pymunk

from bushenv.models import BushingModel
from bushenv.models.linear import TABLE1
from bushenv.rigs.actions import check_profile
from bushenv.rigs.car_bushings import (
    ARM_COORDS,
    AXES,
    arm_models,
    axis_label,
    axis_models,
    carried,
)
from bushenv.rigs.car_verdict import MODEL_ERROR_PREFIX, force_reason, moment_reason
from bushenv.rigs.common import (
    MODEL_ERRORS,
    RigError,
    model_error_text,
    positive,
    positive_int,
)
from bushenv.rigs.coupling import (
    LONG_ARM_M,
    SplitBushing,
    SplitRotation,
    implicit_euler_damping,
    inverse_mass_along,
    space_stepper,
)

DAMPING_ANGLE_STEP = 0.005  # rad; see Car.update_damping
BODIES = ("chassis", "unsprung", "road")


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
        # the arm's bushing: one model per axis, or one over ARM_COORDS (``arm_bushing``)
        self.arm_bushing = kwargs.get("arm_bushing", "")
        self.planar = not (isinstance(self.arm_bushing, str) and self.arm_bushing == "")
        self.moment_limit = g("arm_moment_limit_nm", kwargs.get("arm_moment_limit_nm", 2500.0))
        self.rotation_in: dict[str, tuple[float, float]] = {}  # car role -> (k_in, c_in)
        self.carried: dict[str, tuple[int, ...]] = {}  # model key -> its ARM_COORDS
        if resolve_models and self.planar:
            arm_models(self, kwargs)
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
        if resolve_models:
            self.carried = {k: carried(k, m) for k, m in self.models.items()}

    def split(self, role: str) -> list[tuple[float, float]]:
        """(k_in, c_in) per ``ARM_COORDS`` inside the sub-steps for car ``role`` ("model" or
        "reference"): the Table-1 axes, the rotation's split when the bushing carries it."""
        rotation = self.rotation_in.get(role, (0.0, 0.0))
        return [(self.k_in[a], self.c_in[a]) for a in ARM_COORDS[:2]] + [rotation]


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
        """(motion, forces, why) of ``car`` at t_k: the bushing's (x, v) per axis, its forces
        (radial, axial N; the moment N m when it carries the rotation), and why they cannot be
        applied ("" if they can). A force that raised, is not finite or exceeds its limit is
        judged *before* it is applied and never applied (the car keeps the last held
        remainder, so its state stays finite); otherwise the remainders are held for the
        coming step."""
        car.update_damping()
        motion = car.bushing_motion()
        xr, vr, xa, va = motion
        turn = car.bushing_rotation() if car.rotation is not None else (0.0, 0.0)
        q, w = (xa, xr, turn[0]), (va, vr, turn[1])
        n = 2 if car.rotation is None else 3
        f: list[Any] = [0.0] * len(ARM_COORDS)
        try:
            for key, model in models.items():
                index = self.p.carried[key]
                if len(index) == 1:
                    f[index[0]] = model.step(q[index[0]], w[index[0]])
                    continue
                out = model.step(np.array([q[i] for i in index]), np.array([w[i] for i in index]))
                for j, i in enumerate(index):
                    f[i] = float(out[j])
        except MODEL_ERRORS as exc:  # a model refusing to go on, 1/0, overflow, ...
            return motion, (math.nan,) * n, f"model raised {type(exc).__name__}: {exc}"
        except Exception as exc:  # the model's own bug: ends the episode, not a divergence
            return motion, (math.nan,) * n, MODEL_ERROR_PREFIX + model_error_text(exc)
        forces = (f[1], f[0], f[2])[:n]
        p = self.p
        why = force_reason(forces[0], forces[1], p.force_limit)
        if n == 3:
            why = why or moment_reason(forces[2], p.moment_limit)
        if not why:
            car.radial.hold(forces[0], xr, vr)
            car.axial.hold(forces[1], xa, va)
            if n == 3:
                car.rotation.hold(forces[2], *turn)
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
