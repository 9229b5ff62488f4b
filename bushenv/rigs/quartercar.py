"""QuarterCar-v0: a planar quarter car whose control arm hangs on the bushing (Gymnasium env)."""

from __future__ import annotations

import math
import os
from typing import Any

import gymnasium as gym
import numpy as np
import pymunk
from gymnasium import spaces

from bushenv.models import BushingModel
from bushenv.models.linear import TABLE1
from bushenv.rigs.common import (
    LONG_ARM_M,
    MODEL_ERRORS,
    Canvas,
    ForceDeviationReward,
    RigError,
    SplitBushing,
    Trace,
    call_reset,
    check_hook,
    check_options,
    check_profile,
    implicit_euler_damping,
    inverse_mass_along,
    model_label,
    plot_traces,
    positive,
    positive_int,
    resolve_model,
    resolve_reference,
    space_stepper,
    spec_kwargs,
    unit_action,
)

ENV_ID = "QuarterCar-v0"
AXES = ("radial", "axial")  # radial: vertical at the arm's inner end; axial: along the arm
OBS_SIZE = 12
DAMPING_ANGLE_STEP = 0.005  # rad; see Car.update_damping


def axis_models(spec: Any, dt: float, reference: bool) -> dict[str, BushingModel]:
    """One model per bushing axis: a name or path (the same for both axes, each axis' own
    preset or file), or a dict ``{"radial": ..., "axial": ...}`` of names, paths or objects."""
    resolve = resolve_reference if reference else resolve_model
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
        self.episode_steps = positive_int("episode_steps", kwargs["episode_steps"])
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
        if resolve_models:
            self.models = axis_models(kwargs["model"], self.dt, reference=False)
            self.references = axis_models(kwargs["reference"], self.dt, reference=True)
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

    def __init__(self, p: CarParameters, space: pymunk.Space | None = None) -> None:
        self.p = p
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

    def body_state(self) -> tuple[float, float, float, float]:
        """(chassis y, chassis vy, wheel centre y, wheel centre vy) from ride height."""
        w = self.unsprung.local_to_world(self.wheel_centre)
        vw = self.unsprung.velocity_at_local_point(self.wheel_centre)
        return self.chassis.position.y, self.chassis.velocity.y, w.y, vw.y


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


class QuarterCarEnv(gym.Env):
    """
    ## Description

    A planar quarter car (seed 001 §5 drove a full car over 400/700/1000 mm bumps; this is the
    smallest vehicle that loads a suspension bushing the same way). The chassis (sprung mass)
    slides vertically; the lower control arm hangs on the chassis *through the bushing* -- no
    joint, the bushing carries the arm's inner end in two directions, radial (vertical) and
    axial (along the arm), one bushing model per direction -- and rotates freely about it. The
    wheel is pinned to the arm's outer end, a coil-over joins chassis and arm, and the tyre is a
    stiff spring to the road, unilateral (the wheel can lift off). A twin car with the reference
    bushing drives over the same road. The agent shapes the road to make the two cars differ or
    the model car's bushing diverge. One step is one bushing-model sample (204.8 Hz).

    Coupling (fixed rate, as the papers coupled ADAMS to the network): each step the bushing
    models see the deflection and its velocity, and their forces are applied over the next
    ``physics_substeps`` pymunk steps split as k_in x(t) + c_in v(t) (the Table-1 linear bushing,
    inside every sub-step) plus the held remainder F_model - (k_in x_k + c_in v_k). For the
    linear model the remainder is zero and the coupling is the continuous system; docs/envs.md
    gives the stability margins.

    ## Action Space

    ``Box(-1, 1, (1,), float32)``: the road height change under the wheel this step::

        h_k = clip(h_{k-1} + a * max_road_step_m, -max_road_height_m, max_road_height_m)

    (50 mm per step and +-150 mm by default: curbs, potholes and the papers' bumps fit). The
    road moves linearly within the step. NaN counts as 0; beyond +-1 (and +-inf) as +-1. An
    action that is not one real number (text, None, an array of another shape) is refused with
    a ``RigError`` naming the action space and the expected shape (1,).

    ## Observation Space

    ``Box(-1, 1, (12,), float32)``, each entry clipped to [-1, 1], NaN shown as 0:

    | index | observation (model car unless stated)                 | scale                   |
    |-------|-------------------------------------------------------|-------------------------|
    | 0     | road height                                           | max_road_height_m       |
    | 1     | chassis displacement from ride height                 | max_body_displacement_m |
    | 2     | chassis velocity                                      | v_s = max_road_step/dt  |
    | 3     | wheel displacement                                    | max_body_displacement_m |
    | 4     | wheel velocity                                        | v_s                     |
    | 5     | radial bushing deflection                             | max_bushing_deflection_m|
    | 6     | axial bushing deflection                              | max_bushing_deflection_m|
    | 7     | radial bushing force, model car                       | force_limit_n           |
    | 8     | axial bushing force, model car                        | force_limit_n           |
    | 9     | radial bushing force, reference car                   | force_limit_n           |
    | 10    | axial bushing force, reference car                    | force_limit_n           |
    | 11    | chassis displacement, model car minus reference car   | max_body_displacement_m |

    ## Rewards

    ``ForceDeviationReward`` on ``info["error_n"]`` = hypot(radial, axial) difference of the two
    cars' bushing forces: r = min(error / force_scale_n, reward_cap). Replace with
    ``reward_fn(info)``.

    ## Starting State

    Both cars at rest at ride height on a flat road (an exact equilibrium), models reset.
    Deterministic: every seed gives the same episode for the same actions.

    ## Episode End

    Termination (``info["diverged"]``): the model car leaves its physical bounds while the
    reference car does not -- non-finite state or force, |bushing force| > ``force_limit_n``,
    bushing deflection > ``max_bushing_deflection_m``, suspension travel >
    ``max_suspension_travel_m``, chassis or wheel beyond ``max_body_displacement_m`` -- or the
    model raised an error (``ValueError`` or ``ArithmeticError``), or ``divergence_monitor(info)``
    is truthy. A model force that is not finite or beyond ``force_limit_n`` is judged before it
    is applied and is never applied, so the car's state stays finite; the twin runs in its own
    pymunk space, so nothing the model car does reaches it. Truncation:
    ``episode_steps``, the end of a replayed road, or the reference car itself leaving its
    bounds (``info["physical_limit"]``: the road is too harsh to judge anything).

    ## Info

    Plain Python values: ``time_s``, ``step``, ``road_height_m``; for the model car
    ``chassis_y_m``, ``chassis_vy_m_per_s``, ``wheel_y_m``, ``wheel_vy_m_per_s``,
    ``suspension_travel_m``, ``tyre_force_n``, ``radial_deflection_m``, ``axial_deflection_m``,
    ``force_radial_model_n``, ``force_axial_model_n``; the same with the prefix
    ``reference_`` for the twin car (its forces ``force_radial_reference_n``,
    ``force_axial_reference_n``); ``error_n``, ``chassis_y_error_m``, ``model_out_of_bounds``,
    ``reference_out_of_bounds``, ``monitor_verdict``, ``diverged``, ``physical_limit``,
    ``divergence_reason``.

    ## Arguments

    Every key of ``envs/QuarterCar-v0.toml`` ``[kwargs]``, plus ``reward_fn``,
    ``divergence_monitor`` and ``render_mode``::

        env = gym.make("QuarterCar-v0", model="hybrid")
        env = gym.make("QuarterCar-v0", model={"radial": "r.npz", "axial": "a.npz"})
        obs, info = env.reset(options={"excitation": road})  # replay road heights exactly

    ## Vectorized environment

    Use ``gym.make_vec(..., vectorization_mode="sync")``; for road searches over many roads
    ``bushenv.rigs.quartercar_batch.QuarterCarBatch`` integrates the same car as arrays.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 50}

    def __init__(
        self,
        *,
        render_mode: str | None = None,
        reward_fn=None,
        divergence_monitor=None,
        **spec_overrides: Any,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise RigError(f"render_mode must be one of {self.metadata['render_modes']}")
        p = CarParameters(spec_kwargs(ENV_ID, spec_overrides))
        self.params = p
        self.render_mode = render_mode
        self.models, self.references = p.models, p.references
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.observation_space = spaces.Box(-1.0, 1.0, shape=(OBS_SIZE,), dtype=np.float32)
        self.reward_fn = check_hook("reward_fn", reward_fn) or ForceDeviationReward(
            p.force_scale, p.reward_cap
        )
        self.divergence_monitor = check_hook("divergence_monitor", divergence_monitor)
        self._build_cars()
        self._road = 0.0
        self._t = 0
        self._replay: np.ndarray | None = None
        self._end = p.episode_steps
        self._obs = np.zeros(OBS_SIZE, dtype=np.float32)
        self._canvas: Canvas | None = None
        self._trace = Trace(3) if render_mode else None
        self._info_last: dict[str, Any] = {}

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        p = self.params
        self._replay = None
        self._end = p.episode_steps
        options = check_options(ENV_ID, options)
        if options.get("excitation") is not None:
            h = check_road(options["excitation"], p.max_road, p.max_road_step)
            if h.ndim != 1:
                raise RigError(f"road excitation for one car must be (T,), got {h.shape}")
            self._replay = h
            self._end = h.shape[0]
        for m in (*self.models.values(), *self.references.values()):
            m.reset(1)
        call_reset(self.reward_fn)
        call_reset(self.divergence_monitor)
        self._build_cars()  # fresh bodies: no warm-start impulses from the last episode
        self._road = 0.0
        self._t = 0
        self._obs[:] = 0.0
        if self._trace is not None:
            self._trace.clear()
        zero = (0.0,) * 4
        info = self._info(zero, zero, zero, zero, zero, zero, "", "", "")
        self._info_last = info
        if self.render_mode == "human":
            self.render()
        return self._obs.copy(), info

    def _build_cars(self) -> None:
        """The model car and its twin, each in its own pymunk space: nothing the model car
        does (a blow-up, a NaN) can reach the twin through a shared solver or body."""
        self.car = Car(self.params, pymunk.Space())
        self.twin = Car(self.params, pymunk.Space())
        self.space = self.car.space
        self._space_steps = (space_stepper(self.car.space), space_stepper(self.twin.space))

    def _bushing_forces(self, car: Car, models: dict[str, BushingModel]):
        """Sample the bushing, step both axis models and judge their forces *before* applying
        them: a force that raised, is not finite or exceeds ``force_limit_n`` is the verdict
        (returned as the reason) and is not applied -- the car keeps the last held remainder,
        so its state stays finite. Otherwise hold the remainders for the coming step."""
        car.update_damping()
        xr, vr, xa, va = car.bushing_motion()
        motion = (xr, vr, xa, va)
        try:
            fr = models["radial"].step(xr, vr)
            fa = models["axial"].step(xa, va)
        except MODEL_ERRORS as exc:  # a model refusing to go on, 1/0, overflow, ...
            return motion, (math.nan, math.nan), f"model raised {type(exc).__name__}: {exc}"
        limit = self.params.force_limit
        if abs(fr) <= limit and abs(fa) <= limit:  # also False for NaN
            car.radial.hold(fr, xr, vr)
            car.axial.hold(fa, xa, va)
            return motion, (fr, fa), ""
        reason = ""
        for axis, f in (("radial", fr), ("axial", fa)):
            if not math.isfinite(f):
                reason = f"{axis} bushing force {f!r} N is not finite"
                break
            if abs(f) > limit:
                reason = f"|{axis} bushing force| = {abs(f):.6g} N exceeds {limit:.6g} N"
                break
        return motion, (fr, fa), reason

    def step(self, action):
        p = self.params
        h0 = self._road
        if self._replay is None:
            h = h0 + unit_action(action, ENV_ID) * p.max_road_step
            if h > p.max_road:
                h = p.max_road
            elif h < -p.max_road:
                h = -p.max_road
        else:
            h = float(self._replay[min(self._t, self._end - 1)])
        self._road = h
        self._t += 1

        # sample both bushings at t_k (the state the previous step left), then integrate
        motion_m, force_m, verdict_m = self._bushing_forces(self.car, self.models)
        motion_r, force_r, verdict_r = self._bushing_forces(self.twin, self.references)
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
        body_m = self.car.body_state()
        body_r = self.twin.body_state()

        why_m = verdict_m or out_of_bounds(
            p, body_m[0], body_m[2], motion_m[0], motion_m[2], *force_m
        )
        why_r = verdict_r or out_of_bounds(
            p, body_r[0], body_r[2], motion_r[0], motion_r[2], *force_r
        )
        terminated = truncated = False
        reason = ""
        if why_r:
            truncated = True
        elif why_m:
            terminated = True
            reason = why_m
        info = self._info(
            motion_m, force_m, body_m, motion_r, force_r, body_r, why_m, why_r, reason
        )
        if self.divergence_monitor is not None and not (terminated or truncated):
            verdict = self.divergence_monitor(info)
            if verdict:
                terminated = True
                info["monitor_verdict"] = True
                info["divergence_reason"] = (
                    verdict if isinstance(verdict, str) else "divergence monitor"
                )
        info["diverged"] = terminated
        if self._t >= self._end:
            truncated = True
        reward = float(self.reward_fn(info))
        self._observe(info)
        self._info_last = info
        if self._trace is not None:
            self._trace.push(h, info["force_radial_model_n"], info["force_radial_reference_n"])
        if self.render_mode == "human":
            self.render()
        return self._obs.copy(), reward, terminated, truncated, info

    def _observe(self, info: dict[str, Any]) -> None:
        p, o = self.params, self._obs
        values = (
            info["road_height_m"] / p.max_road,
            info["chassis_y_m"] / p.max_body,
            info["chassis_vy_m_per_s"] / p.v_scale,
            info["wheel_y_m"] / p.max_body,
            info["wheel_vy_m_per_s"] / p.v_scale,
            info["radial_deflection_m"] / p.max_deflection,
            info["axial_deflection_m"] / p.max_deflection,
            info["force_radial_model_n"] / p.force_limit,
            info["force_axial_model_n"] / p.force_limit,
            info["force_radial_reference_n"] / p.force_limit,
            info["force_axial_reference_n"] / p.force_limit,
            info["chassis_y_error_m"] / p.max_body,
        )
        for i, v in enumerate(values):
            o[i] = 0.0 if v != v else (1.0 if v > 1.0 else (-1.0 if v < -1.0 else v))

    def _info(self, motion_m, force_m, body_m, motion_r, force_r, body_r, why_m, why_r, reason):
        p = self.params
        h = self._road
        e = math.hypot(force_m[0] - force_r[0], force_m[1] - force_r[1])
        return {
            "time_s": self._t * p.dt,
            "step": self._t,
            "road_height_m": h,
            "chassis_y_m": body_m[0],
            "chassis_vy_m_per_s": body_m[1],
            "wheel_y_m": body_m[2],
            "wheel_vy_m_per_s": body_m[3],
            "suspension_travel_m": body_m[2] - body_m[0],
            "tyre_force_n": max(p.k_t * (h - body_m[2]), -p.tyre_static_n),  # dynamic part
            "radial_deflection_m": motion_m[0],
            "axial_deflection_m": motion_m[2],
            "force_radial_model_n": force_m[0],
            "force_axial_model_n": force_m[1],
            "reference_chassis_y_m": body_r[0],
            "reference_chassis_vy_m_per_s": body_r[1],
            "reference_wheel_y_m": body_r[2],
            "reference_wheel_vy_m_per_s": body_r[3],
            "reference_suspension_travel_m": body_r[2] - body_r[0],
            "reference_tyre_force_n": max(p.k_t * (h - body_r[2]), -p.tyre_static_n),
            "reference_radial_deflection_m": motion_r[0],
            "reference_axial_deflection_m": motion_r[2],
            "force_radial_reference_n": force_r[0],
            "force_axial_reference_n": force_r[1],
            "error_n": e,
            "chassis_y_error_m": body_m[0] - body_r[0],
            "model_out_of_bounds": why_m,
            "reference_out_of_bounds": why_r,
            "monitor_verdict": False,
            "diverged": False,
            "physical_limit": bool(why_r),
            "divergence_reason": reason,
        }

    # ----- drawing ---------------------------------------------------------------------------
    def render(self):
        if self.render_mode is None:
            gym.logger.warn(
                "render() without a render_mode; pass render_mode='rgb_array' to gym.make"
            )
            return None
        if self._canvas is None:
            self._canvas = Canvas(600, 400, self.render_mode, self.metadata["render_fps"], ENV_ID)
        c, p = self._canvas, self.params
        info = self._info_last
        c.clear()
        c.text(f"{ENV_ID}  model={p.model_name}  reference={p.reference_name}", (10, 8))
        c.text(
            f"t = {self._t * p.dt:6.3f} s   road = {self._road * 1e3:+7.1f} mm   "
            f"chassis = {info.get('chassis_y_m', 0.0) * 1e3:+7.2f} mm",
            (10, 28),
            small=True,
        )
        scale = 260.0  # px per m
        origin = (90.0, 215.0)  # the bushing centre at ride height
        r_px = p.r_w * scale

        def to_px(x, y):
            return origin[0] + scale * x, origin[1] - scale * y

        # the road: past heights to the left of the contact point (2 px per step), filled below
        x_w = to_px(p.L, 0.0)[0]
        hist = [self._road]
        if self._trace is not None and self._trace.count > 0:
            hist = list(self._trace.ordered()[0][-120:])
        pts = [
            (x_w - 2 * (len(hist) - 1 - i), origin[1] - scale * hv + r_px)
            for i, hv in enumerate(hist)
        ]
        pts = [(0.0, pts[0][1])] + pts + [(320.0, pts[-1][1]), (320.0, 400.0), (0.0, 400.0)]
        c.polygon(pts, (205, 195, 170))
        for car, solid, col in (
            (self.twin, False, (70, 110, 210)),
            (self.car, True, (40, 40, 40)),
        ):
            cy = car.chassis.position.y
            tl = to_px(-0.3, cy + p.H + 0.08)
            br = to_px(0.05, cy + 0.06)
            if solid:
                c.rect(tl[0], tl[1], br[0] - tl[0], br[1] - tl[1], (215, 215, 210))
            c.rect(tl[0], tl[1], br[0] - tl[0], br[1] - tl[1], col, 2)
            # the coil-over tower: a beam from the body to the top mount
            c.line(to_px(0.05, cy + p.H), to_px(p.mount * p.L + 0.03, cy + p.H), col, 5)
            c.line(to_px(0.0, cy + 0.06), to_px(0.0, cy), col, 3)  # bushing bracket
            inner = car.unsprung.local_to_world(car.arm_inner)
            outer = car.unsprung.local_to_world(car.wheel_centre)
            mount = car.unsprung.local_to_world(car.arm_mount)
            c.line(to_px(inner.x, inner.y), to_px(outer.x, outer.y), col, 6 if solid else 2)
            top = to_px(p.mount * p.L, cy + p.H)
            bot = to_px(mount.x, mount.y)
            zig = [
                (top[0] + (7 if k % 2 else -7) * (0 < k < 11), top[1] + (bot[1] - top[1]) * k / 11)
                for k in range(12)
            ]
            c.lines(zig, col, 2)
            w = to_px(outer.x, outer.y)
            c.circle(w, r_px, col, 12 if solid else 2)  # the tyre, open so the coil shows
            if solid:
                c.circle(w, r_px * 0.5, (160, 160, 160), 4)
                c.circle(w, 5, col)
            # the bushing: outer sleeve on the chassis, inner sleeve offset by 10x the deflection
            b = to_px(0.0, cy)
            c.circle(b, 14, col, 3)
            dx, dy = inner.x, inner.y - cy
            c.circle((b[0] + 10 * scale * dx, b[1] - 10 * scale * dy), 5, col)
        # bushing forces on the arm as arrows (model red, reference blue), force_scale -> 60 px
        b = to_px(0.0, self.car.chassis.position.y)
        k = 60.0 / p.force_scale
        for fr, fa, col in (
            (
                info.get("force_radial_model_n", 0.0),
                info.get("force_axial_model_n", 0.0),
                (200, 40, 40),
            ),
            (
                info.get("force_radial_reference_n", 0.0),
                info.get("force_axial_reference_n", 0.0),
                (40, 70, 200),
            ),
        ):
            if math.isfinite(fr) and math.isfinite(fa):
                dx = max(-90.0, min(90.0, -k * fa))
                dy = max(-90.0, min(90.0, k * fr))
                c.arrow(b, (b[0] + dx, b[1] + dy), col, 3)
        c.text("model car (grey), reference car (blue)", (10, 48), small=True)
        fs = 5 * p.force_scale
        c.force_bar(330, 60, 250, 14, info.get("force_radial_model_n", 0.0), fs,
                    (200, 40, 40), f"radial F, model car (+-{fs / 1e3:.0f} kN)")  # fmt: skip
        c.force_bar(330, 95, 250, 14, info.get("force_radial_reference_n", 0.0), fs,
                    (40, 70, 200), "radial F, reference car")  # fmt: skip
        c.force_bar(330, 130, 250, 14, info.get("force_axial_model_n", 0.0), fs,
                    (200, 40, 40), "axial F, model car")  # fmt: skip
        c.force_bar(330, 165, 250, 14, info.get("force_axial_reference_n", 0.0), fs,
                    (40, 70, 200), "axial F, reference car")  # fmt: skip
        if self._trace is not None:
            plot_traces(
                c,
                (330, 215, 250, 150),
                self._trace,
                (p.max_road, fs, fs),
                ((90, 70, 40), (200, 40, 40), (40, 70, 200)),
                ("road", "F radial model", "reference"),
            )
        return c.frame()

    def close(self) -> None:
        if self._canvas is not None:
            self._canvas.close()
            self._canvas = None
