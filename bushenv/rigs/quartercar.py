"""QuarterCar-v0: a planar quarter car whose control arm hangs on the bushing (Gymnasium env).

The car itself (parameters, pymunk bodies, bounds) is ``car.py``; this module steps a model car
and its reference twin, each in its own pymunk space, and turns them into observations, rewards
and the episode's end. ``quartercar_vector.py`` is the same env for N roads as arrays.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from bushenv.rigs.actions import check_options, unit_action
from bushenv.rigs.car import Car, CarPair, CarParameters, check_road
from bushenv.rigs.car_bushings import AXES, axis_label, axis_models
from bushenv.rigs.car_verdict import (
    MODEL_ERROR_PREFIX,
    beyond_bounds,
    car_verdict,
    out_of_bounds,
    reference_range_reason,
)
from bushenv.rigs.common import (
    ForceDeviationReward,
    RigError,
    ask_monitor,
    call_reset,
    check_hook,
)
from bushenv.rigs.drawing import Canvas, Trace
from bushenv.rigs.scenes import draw_quartercar
from bushenv.rigs.specs import spec_kwargs

ENV_ID = "QuarterCar-v0"
OBS_SIZE = 12
__all__ = ["AXES", "ENV_ID", "QuarterCarEnv", "axis_label", "axis_models", "check_road"]


def observation_values(p: CarParameters, info: dict[str, Any]) -> tuple:
    """The 12 observations before clipping, from a step's ``info`` (floats or (N,) arrays)."""
    return (
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
    pymunk space, so nothing the model car does reaches it. The force criteria are
    ``divergence.force_termination``'s (``car.car_verdict``). Truncation: the reference car
    itself leaving its bounds (``info["physical_limit"]``: the road is too harsh to judge
    anything), the end of a replayed road, and, through ``gym.make``, Gymnasium's ``TimeLimit``
    at the spec's ``max_episode_steps`` (2048 = 10 s; ``gym.make(..., max_episode_steps=N)``
    changes it, -1 removes it). Built directly, the env has no time limit of its own.

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
        env = gym.make("QuarterCar-v0", arm_bushing="planar.npz")  # one planar model

    ``arm_bushing`` (a ``MODELS`` name with a three-axis form, a three-axis ``.npz`` file or
    a three-axis model) replaces the two one-axis models by one three-axis bushing that also carries
    the arm's rotation (a moment, judged by ``arm_moment_limit_nm``; the twin's is
    ``arm_bushing_reference``, by default the torsion preset ``rubber-torsion``); info then
    adds ``arm_rotation_rad``, ``moment_model_nm``,
    ``moment_reference_nm``. docs/planar.md gives its coupling and range.
        obs, info = env.reset(options={"excitation": road})  # replay road heights exactly

    ## Vectorized environment

    ``gym.make_vec("QuarterCar-v0", num_envs=N, vectorization_mode="vector_entry_point")``
    gives ``QuarterCarVectorEnv``: N car pairs as arrays through ``QuarterCarBatch`` (the same
    car as one compiled integrator, within 1 % of each signal's peak of this env; ~40x cheaper
    per car-step; with ``arm_bushing`` too, within 0.1 % of the peaks, docs/planar.md).
    ``bushenv.rigs.sb3.make_sb3_vec_env("QuarterCar-v0", N)`` gives it to stable-baselines3.
    ``vectorization_mode="sync"`` runs N of these pymunk envs.

    ## Rendering

    ``render_fps`` = 1 / ``dt_s`` (204.8): one frame per step, so a video written at
    ``render_fps`` plays in real time.

    ## Example

    >>> import gymnasium as gym
    >>> import bushenv
    >>> env = gym.make("bushenv/QuarterCar-v0", model="linear")
    >>> env.spec.max_episode_steps, env.metadata["render_fps"]
    (2048, 204.8)
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape, float(abs(obs).max())
    ((12,), 0.0)
    >>> obs, reward, terminated, truncated, info = env.step(env.action_space.high)
    >>> info["road_height_m"], terminated, truncated
    (0.05, False, False)

    ## Version History

    - v0: the car of ``envs/QuarterCar-v0.toml`` (``arm_bushing`` added, default off: the
      car is unchanged). Since: the episode length is the spec's
      ``max_episode_steps`` (Gymnasium's ``TimeLimit``; the kwarg ``episode_steps`` is gone),
      ``render_fps`` is 1 / ``dt_s``, the env pickles and deep-copies, a vector entry point
      exists, and the id is also registered as ``bushenv/QuarterCar-v0``. The dynamics and
      every number an episode gives are unchanged. With ``arm_bushing`` set, the twin's
      default is the torsion preset ``rubber-torsion`` since 2026-11-29 (the arm turns its
      pivot's bush about the bush's axis; before: the tilt preset ``reference``).
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 204.8}

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
        self.metadata = {**type(self).metadata, "render_fps": 1.0 / p.dt}
        self.render_mode = render_mode
        self.models, self.references = p.models, p.references
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.observation_space = spaces.Box(-1.0, 1.0, shape=(OBS_SIZE,), dtype=np.float32)
        self.reward_fn = check_hook("reward_fn", reward_fn) or ForceDeviationReward(
            p.force_scale, p.reward_cap
        )
        self.divergence_monitor = check_hook("divergence_monitor", divergence_monitor)
        self.cars = CarPair(p)
        self._road = 0.0
        self._t = 0
        self._replay: np.ndarray | None = None
        self._end: int | None = None  # the replay's length; no limit of its own otherwise
        self._obs = np.zeros(OBS_SIZE, dtype=np.float32)
        self._canvas: Canvas | None = None
        self._trace = Trace(3) if render_mode else None
        self._info_last: dict[str, Any] = {}

    def __getstate__(self) -> dict[str, Any]:
        """Everything but the drawing window; the cars pickle their own state."""
        return {**self.__dict__, "_canvas": None}

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        p = self.params
        self._replay = None
        self._end = None
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
        self.cars = CarPair(p)  # fresh bodies: no warm-start impulses from the last episode
        self._road = 0.0
        self._t = 0
        self._obs[:] = 0.0
        if self._trace is not None:
            self._trace.clear()
        zero = (0.0,) * 4
        forces = (0.0,) * (3 if p.planar else 2)
        info = self._info(zero, forces, zero, zero, forces, zero, "", "", "")
        self._info_last = info
        if self.render_mode == "human":
            self.render()
        return self._obs.copy(), info

    @property
    def car(self) -> Car:
        """The model car (pymunk bodies)."""
        return self.cars.car

    @property
    def twin(self) -> Car:
        """The reference car (pymunk bodies)."""
        return self.cars.twin

    def _next_road(self, action) -> float:
        """This step's road height: the action's change, clipped, or the replayed sample."""
        if self._replay is not None:
            return float(self._replay[min(self._t, self._end - 1)])
        p = self.params
        h = self._road + unit_action(action, ENV_ID) * p.max_road_step
        return max(-p.max_road, min(p.max_road, h))

    def step(self, action):
        p = self.params
        h0 = self._road
        h = self._next_road(action)
        self._road = h
        self._t += 1
        # sample both bushings at t_k (the state the previous step left), then integrate
        motion_m, force_m, why_m = self.cars.sample(self.car, self.models)
        motion_r, force_r, why_r = self.cars.sample(self.twin, self.references)
        self.cars.integrate(h0, h)
        body_m, body_r = self.car.body_state(), self.twin.body_state()
        bounds = [
            beyond_bounds(p, body[0], body[2], motion[0], motion[2])
            for body, motion in ((body_m, motion_m), (body_r, motion_r))
        ]
        terminated, truncated = car_verdict(p, np.array(force_m), np.array(force_r), *bounds)
        terminated, truncated = bool(terminated), bool(truncated)
        why_m = why_m or out_of_bounds(
            p, body_m[0], body_m[2], motion_m[0], motion_m[2], *force_m[:2]
        )
        why_r = why_r or out_of_bounds(
            p, body_r[0], body_r[2], motion_r[0], motion_r[2], *force_r[:2]
        )
        info = self._info(
            motion_m, force_m, body_m, motion_r, force_r, body_r, why_m, why_r,
            why_m if terminated else "",
        )  # fmt: skip
        if self.divergence_monitor is not None and not (terminated or truncated):
            terminated = ask_monitor(self.divergence_monitor, info)
        model_error = (
            why_m[len(MODEL_ERROR_PREFIX) :] if why_m.startswith(MODEL_ERROR_PREFIX) else ""
        )
        info["diverged"] = terminated and not model_error
        info["model_error"] = model_error
        terminated = terminated or bool(model_error)
        if self._end is not None and self._t >= self._end:
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
        o = self._obs
        for i, v in enumerate(observation_values(self.params, info)):
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
            "model_error": "",
            **(self._planar_info(force_m, force_r) if p.planar else {}),
        }

    def _planar_info(self, force_m, force_r) -> dict[str, Any]:
        """The arm's rotation and the planar bushing's moments (``arm_bushing`` set), and why
        the twin's bushing judges outside the range its law is calibrated for ("" if not)."""
        theta_r = self.twin.bushing_rotation()[0]
        return {
            "arm_rotation_rad": self.car.bushing_rotation()[0],
            "reference_arm_rotation_rad": theta_r,
            "reference_outside_range": reference_range_reason(self.references["arm"], theta_r),
            "moment_model_nm": force_m[2],
            "moment_reference_nm": force_r[2],
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
        state = {
            "t_s": self._t * self.params.dt,
            "road_m": self._road,
            "info": self._info_last,
            "trace": self._trace,
            "car": self.car,
            "twin": self.twin,
        }
        draw_quartercar(self._canvas, self.params, ENV_ID, state)
        return self._canvas.frame()

    def close(self) -> None:
        if self._canvas is not None:
            self._canvas.close()
            self._canvas = None
