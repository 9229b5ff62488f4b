"""BushRig-v0: the one-axis bushing test rig (seed 001 §4, Fig. 11) as a Gymnasium env.

The actuator's motion is prescribed, so the rig is a function of the commanded displacement:
``BushRigEnv`` (here) and ``BushRigVectorEnv`` (``vector.py``) step the same models with the same
arithmetic and decide the episode's end with ``divergence.force_termination``, the function the
divergence judge calls.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pymunk
from gymnasium import spaces

from bushenv.divergence import force_termination
from bushenv.rigs.actions import check_options, check_profile, unit_action
from bushenv.rigs.common import (
    MODEL_ERRORS,
    ForceDeviationReward,
    RigError,
    ask_monitor,
    call_reset,
    check_hook,
    force_observation,
    model_error_text,
    model_label,
    per_axis,
    positive,
    positive_int,
    resolve_model,
    resolve_reference,
)
from bushenv.rigs.coupling import space_stepper, velocity_setter
from bushenv.rigs.drawing import Canvas, Trace
from bushenv.rigs.scenes import draw_bushrig
from bushenv.rigs.specs import spec_kwargs

ENV_ID = "BushRig-v0"
AXES = ("axial", "radial")
ACTUATOR_MASS_KG = 10.0  # piston and fixture; drawn only, the motion is prescribed
MAX_HISTORY = 10_000  # samples per channel in the observation (3 x 10 000 float32 = 120 kB)
# pymunk objects and chipmunk call handles: rebuilt on unpickling, not pickled (see __getstate__)
PHYSICS_ATTRS = ("space", "ground", "actuator", "groove", "_space_step", "_set_actuator_velocity")


def build_physics() -> tuple:
    """The rig's pymunk objects, in ``PHYSICS_ATTRS`` order: the space, its static body, the
    actuator, the groove, and the chipmunk calls that step the space and set the actuator's
    velocity."""
    space = pymunk.Space()
    ground = space.static_body
    # The actuator piston: a dynamic body in displacement control. Its velocity is set every
    # step so it arrives at the commanded x at the end of the step; the servo supplies the
    # force that takes, so the bushing's reaction never feeds back into the motion.
    actuator = pymunk.Body(ACTUATOR_MASS_KG, math.inf)
    actuator.position = (0.0, 0.0)
    space.add(actuator)
    # the groove: the translational joint of Fig. 11, the actuator slides along x
    groove = pymunk.GrooveJoint(ground, actuator, (-0.05, 0.0), (0.05, 0.0), (0.0, 0.0))
    space.add(groove)
    return space, ground, actuator, groove, space_stepper(space), velocity_setter(actuator)


def check_excitation(profile: Any, max_displacement_m: float, max_step_m: float) -> np.ndarray:
    """A replayable displacement profile: finite (T,) or (T, N), within the stroke, and each
    sample (the rig starting at rest at 0) at most ``max_step_m`` from the previous one."""
    return check_profile(
        "excitation",
        profile,
        "excitation",
        max_displacement_m,
        "|x| = {value:.6g} m exceeds the stroke limit " + f"{max_displacement_m:.6g} m",
        max_step_m,
        "a step of {value:.6g} m exceeds the velocity limit "
        + f"({max_step_m:.6g} m per step; the rig starts at rest at x = 0)",
    )


class RigParameters:
    """The spec's kwargs checked and converted; shared by ``BushRigEnv`` and the vector env."""

    def __init__(self, kwargs: dict[str, Any]) -> None:
        self.axis = kwargs["axis"]
        if self.axis not in AXES:
            raise RigError(f"{ENV_ID}: axis must be one of {AXES}, got {self.axis!r}")
        self.dt = positive("dt_s", kwargs["dt_s"])
        self.substeps = positive_int("physics_substeps", kwargs["physics_substeps"])
        self.history = positive_int("history", kwargs["history"])
        if self.history > MAX_HISTORY:
            raise RigError(
                f"history must be at most {MAX_HISTORY} samples, got {self.history} (the "
                f"observation holds 3 x history values)"
            )
        self.max_x = positive("max_displacement_m", kwargs["max_displacement_m"])
        self.max_v = positive("max_velocity_m_per_s", kwargs["max_velocity_m_per_s"])
        self.force_limit = positive("force_limit_n", kwargs["force_limit_n"])
        self.force_scale = per_axis("force_scale_n", kwargs["force_scale_n"], self.axis)
        self.reward_cap = positive("reward_cap", kwargs["reward_cap"])
        self.max_step = self.max_v * self.dt  # largest displacement change per step, m
        self.model = resolve_model(kwargs["model"], self.axis, self.dt)
        self.reference = resolve_reference(
            kwargs["reference"],
            self.axis,
            self.dt,
            trust_reference=bool(kwargs.get("trust_reference", False)),
        )
        self.judge = self.reference.judge
        self.model_name = model_label(self.model, kwargs["model"])
        self.reference_name = model_label(self.reference, kwargs["reference"])

    def spaces(self) -> tuple[spaces.Box, spaces.Box]:
        action = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        observation = spaces.Box(-1.0, 1.0, shape=(3 * self.history,), dtype=np.float32)
        return action, observation

    def metadata(self, metadata: dict[str, Any]) -> dict[str, Any]:
        """``metadata`` with ``render_fps`` = 1 / dt: one frame per step shows real time."""
        return {**metadata, "render_fps": 1.0 / self.dt}


class BushRigEnv(gym.Env):
    """
    ## Description

    The bushing test rig of seed 001 §4 (Fig. 11, built there in ADAMS): an actuator body
    slides on a groove (translational) joint to ground and drives one end of the bushing; the
    other end sits on the ground through a load cell. The model under test (``model``) and the
    reference rubber bushing (``reference``, the "real" specimen) are driven by the same
    motion side by side, and the agent looks for motions that make them disagree or make the
    model diverge. One step is one sample of the bushing model (``dt_s``, 204.8 Hz).

    The actuator is in displacement control: its motion is *prescribed* (as the papers imposed
    the random input on the translational joint), its velocity set each step so it reaches the
    commanded x at the end of the step. So the bushing deflection is the commanded displacement
    itself and no bushing force feeds back into the motion: this rig needs no coupling
    stabilisation (the trap of DESIGN-NOTES cannot arise), and the bushing force only goes to
    the load cell. The models are fed the commanded x (not pymunk's read-back) and the
    velocity (x_k - x_{k-1}) / dt of the actuator over the step.

    ## Action Space

    ``Box(-1, 1, (1,), float32)``: the change of the actuator's commanded displacement this
    step, as a fraction of the largest change the machine allows (seed 002 Table 1)::

        x_k = clip(x_{k-1} + a * v_max * dt, -x_max, x_max)     v_max = 1.2566 m/s, x_max = 12.5 mm

    so |a| = 1 is the velocity limit (6.14 mm per step at 204.8 Hz). NaN counts as 0, values
    beyond +-1 (also +-inf) as +-1: no number raises. An action that is not one real number
    (text, None, complex, an array of another shape) is refused with a ``RigError`` naming
    the action space and the expected shape (1,).

    ## Observation Space

    ``Box(-1, 1, (3 H,), float32)``, H = ``history`` (4 by default), newest sample first:

    | index          | observation                                   | min | max |
    |----------------|-----------------------------------------------|-----|-----|
    | 0 .. H-1       | displacement x_{k-i} / x_max                  | -1  | 1   |
    | H .. 2H-1      | model force F_model,k-i / force_limit_n       | -1  | 1   |
    | 2H .. 3H-1     | reference force F_ref,k-i / force_limit_n     | -1  | 1   |

    Forces are clipped to [-1, 1] (beyond is a divergence or a machine-limit end anyway); a
    NaN force shows as 0.

    ## Rewards

    ``ForceDeviationReward``: r = min(|F_model - F_ref| / force_scale_n, reward_cap), and
    reward_cap when that is not finite. ``force_scale_n`` is the Table-1 stiffness times the
    stroke for the axis (4.7 kN axial, 19 kN radial). Replace it with ``reward_fn(info)`` (e.g.
    an STL robustness from ``bushenv.search``).

    ## Starting State

    At rest: x = 0, both models reset (zero deflection, zero force), observation all zeros.
    Nothing is random, so every seed gives the same episode for the same actions.

    ## Episode End

    Termination (the model's verdict, ``info["diverged"]``): the model's force is not finite or
    the model raised an error (a ``ValueError`` such as ``ModelError``, or an
    ``ArithmeticError``: ``ZeroDivisionError``, ``FloatingPointError``, ``OverflowError``);
    |F_model| > ``force_limit_n`` (25 kN, the machine's dynamic force) while the reference
    stays within it; or ``divergence_monitor(info)`` is truthy.
    Truncation: the reference itself needs more than the machine's 25 kN
    (``info["machine_limit"]``: the motion cannot be run on the real rig, so it judges
    nothing); the end of a replayed excitation; and, through ``gym.make``, Gymnasium's
    ``TimeLimit`` at the spec's ``max_episode_steps`` (2048 steps = 10 s;
    ``gym.make(..., max_episode_steps=N)`` changes it, -1 removes it, e.g. to replay a longer
    profile). The env built directly (``BushRigEnv()``) has no time limit of its own, like
    Gymnasium's ``CartPoleEnv``.

    ## Info

    ``time_s``, ``step``, ``displacement_m``, ``velocity_m_per_s``, ``force_model_n``,
    ``force_reference_n``, ``error_n`` (model minus reference), ``model_force_finite``,
    ``model_over_force_limit``, ``reference_over_force_limit``, ``monitor_verdict``,
    ``diverged``, ``machine_limit``, ``divergence_reason`` ("" if none). Plain Python values.

    ## Arguments

    Every key of ``envs/BushRig-v0.toml`` ``[kwargs]`` (``model``, ``axis``, ``reference``,
    ``dt_s``, ``physics_substeps``, ``history``, ``max_displacement_m``,
    ``max_velocity_m_per_s``, ``force_limit_n``, ``reward_cap``, ``force_scale_n``) plus
    ``reward_fn``, ``divergence_monitor`` (see ``bushenv.rigs.common``) and ``render_mode``::

        env = gym.make("BushRig-v0", model="nn", axis="radial")
        env = gym.make("BushRig-v0", model="fits/axial_nn.npz")
        obs, info = env.reset(options={"excitation": x})  # replay x exactly; actions ignored

    ## Vectorized environment

    ``gym.make_vec("BushRig-v0", num_envs=N, vectorization_mode="vector_entry_point")`` gives
    ``BushRigVectorEnv``: N rigs as arrays through the models' batched step, the same kernels
    and arithmetic, bit for bit equal to N single envs (next-step autoreset).
    ``bushenv.rigs.sb3.make_sb3_vec_env("BushRig-v0", N)`` gives it to stable-baselines3.

    ## Rendering

    ``render_fps`` = 1 / ``dt_s`` (204.8): one frame per step, so a video written at
    ``render_fps`` (``gymnasium.wrappers.RecordVideo``) plays in real time, and ``"human"``
    paces its window to the simulated time.

    ## Example

    >>> import gymnasium as gym
    >>> import numpy as np
    >>> import bushenv
    >>> env = gym.make("bushenv/BushRig-v0", model="linear", axis="axial")
    >>> env.spec.max_episode_steps, env.metadata["render_fps"]
    (2048, 204.8)
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape, obs.dtype, float(abs(obs).max())
    ((12,), dtype('float32'), 0.0)
    >>> obs, reward, terminated, truncated, info = env.step(np.array([0.5], np.float32))
    >>> round(info["displacement_m"] * 1e3, 3), terminated, truncated
    (3.068, False, False)

    ## Version History

    - v0: as in seed 001 §4. Since: the episode length is the spec's ``max_episode_steps``
      (Gymnasium's ``TimeLimit``; the kwarg ``episode_steps`` is gone), ``render_fps`` is
      1 / ``dt_s``, the env pickles and deep-copies, and the id is also registered as
      ``bushenv/BushRig-v0``. The dynamics and every number an episode gives are unchanged.
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
        p = RigParameters(spec_kwargs(ENV_ID, spec_overrides))
        self.params = p
        self.metadata = p.metadata(type(self).metadata)
        self.render_mode = render_mode
        self.model, self.reference = p.model, p.reference
        self.action_space, self.observation_space = p.spaces()
        self.reward_fn = check_hook("reward_fn", reward_fn) or ForceDeviationReward(
            p.force_scale, p.reward_cap
        )
        self.divergence_monitor = check_hook("divergence_monitor", divergence_monitor)
        self._dt, self._h = p.dt, p.dt / p.substeps
        self._obs = np.zeros((3, p.history), dtype=np.float32)
        self._x = 0.0
        self._t = 0
        self._replay: np.ndarray | None = None
        self._end: int | None = None  # the replay's length; no limit of its own otherwise
        (
            self.space,
            self.ground,
            self.actuator,
            self.groove,
            self._space_step,
            self._set_actuator_velocity,
        ) = build_physics()
        self._canvas: Canvas | None = None
        self._trace = Trace(3) if render_mode else None
        self._last = (0.0, 0.0, 0.0)

    def __getstate__(self) -> dict[str, Any]:
        """Everything but the pymunk space and the chipmunk call handles (which cannot be
        pickled); the actuator's position and velocity stand in for them."""
        state = {k: v for k, v in self.__dict__.items() if k not in PHYSICS_ATTRS}
        state["_canvas"] = None
        a = self.actuator
        state["_actuator_state"] = (tuple(a.position), tuple(a.velocity))
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        position, velocity = state.pop("_actuator_state")
        self.__dict__.update(state)
        (
            self.space,
            self.ground,
            self.actuator,
            self.groove,
            self._space_step,
            self._set_actuator_velocity,
        ) = build_physics()
        self.actuator.position = position
        self.actuator.velocity = velocity

    # ----- gymnasium -----------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        p = self.params
        self._replay = None
        self._end = None
        options = check_options(ENV_ID, options)
        if options.get("excitation") is not None:
            x = check_excitation(options["excitation"], p.max_x, p.max_step)
            if x.ndim != 1:
                raise RigError(f"excitation for one rig must be (T,), got {x.shape}")
            self._replay = x
            self._end = x.shape[0]
        self.model.reset(1)
        self.reference.reset(1)
        call_reset(self.reward_fn)
        call_reset(self.divergence_monitor)
        self._obs[:] = 0.0
        self._x = 0.0
        self._t = 0
        self.actuator.position = (0.0, 0.0)
        self.actuator.velocity = (0.0, 0.0)
        self._last = (0.0, 0.0, 0.0)
        if self._trace is not None:
            self._trace.clear()
        info = self._info(0.0, 0.0, 0.0, 0.0, True, False, False, False, "")
        if self.render_mode == "human":
            self.render()
        return self._obs.ravel().copy(), info

    def _next_displacement(self, action) -> float:
        """The commanded x of this step: the action's change, clipped to the stroke, or the
        replayed sample."""
        if self._replay is not None:
            return float(self._replay[min(self._t, self._end - 1)])
        p = self.params
        x = self._x + unit_action(action, ENV_ID) * p.max_step
        if x > p.max_x:
            return p.max_x
        if x < -p.max_x:
            return -p.max_x
        return x

    def step(self, action):
        p = self.params
        x0 = self._x
        x = self._next_displacement(action)
        v = (x - x0) / self._dt
        self._x = x
        self._t += 1

        reason = model_error = ""
        try:
            f_m = self.model.step(x, v)
        except MODEL_ERRORS as exc:  # a model refusing to go on (Bouc-Wen's guard), 1/0, ...
            f_m = math.nan
            reason = f"model raised {type(exc).__name__}: {exc}"
        except Exception as exc:  # the model's own bug: ends the episode, not a divergence
            f_m = math.nan
            model_error = model_error_text(exc)
        f_r = self.reference.step(x, v)

        self._set_actuator_velocity(v, 0.0)
        for _ in range(p.substeps):
            self._space_step(self._h)

        obs = self._obs
        obs[:, 1:] = obs[:, :-1]
        obs[0, 0] = x / p.max_x
        obs[1, 0] = force_observation(f_m, p.force_limit)
        obs[2, 0] = force_observation(f_r, p.force_limit)

        if abs(f_m) <= p.force_limit and abs(f_r) <= p.force_limit:
            # both finite and within the limit: force_termination cannot fire (tested); not
            # calling it saves its ~3 us of numpy scalar calls, a fifth of the step
            non_finite = model_over = ref_over = False
        else:
            verdict = force_termination(f_m, f_r, p.force_limit)
            non_finite, model_over, ref_over = (bool(v) for v in verdict)
        finite = not non_finite
        terminated = non_finite or model_over
        truncated = ref_over and finite
        if non_finite:
            reason = reason or "model force is not finite"
        elif model_over:
            reason = f"|F_model| = {abs(f_m):.6g} N exceeds {p.force_limit:.6g} N"
        if model_error:
            reason = ""
        info = self._info(x, v, f_m, f_r, finite, model_over, ref_over, False, reason)
        if self.divergence_monitor is not None and not terminated:
            terminated = ask_monitor(self.divergence_monitor, info)
        info["diverged"] = terminated and not model_error
        info["model_error"] = model_error
        terminated = terminated or bool(model_error)
        if self._end is not None and self._t >= self._end:
            truncated = True
        reward = float(self.reward_fn(info))
        self._last = (x, f_m, f_r)
        if self._trace is not None:
            self._trace.push(x, f_m, f_r)
        if self.render_mode == "human":
            self.render()
        return obs.ravel().copy(), reward, terminated, truncated, info

    def _info(self, x, v, f_m, f_r, finite, model_over, ref_over, monitor, reason):
        return {
            "time_s": self._t * self._dt,
            "step": self._t,
            "displacement_m": x,
            "velocity_m_per_s": v,
            "force_model_n": f_m,
            "force_reference_n": f_r,
            "error_n": f_m - f_r,
            "model_force_finite": finite,
            "model_over_force_limit": model_over,
            "reference_over_force_limit": ref_over,
            "monitor_verdict": monitor,
            "diverged": False,  # set by step once the monitor has spoken
            "machine_limit": ref_over,
            "divergence_reason": reason,
            "model_error": "",  # the model's own exception, when it raised (not a divergence)
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
        t_s = self._t * self._dt
        draw_bushrig(self._canvas, self.params, ENV_ID, t_s, self._last, self._trace)
        return self._canvas.frame()

    def close(self) -> None:
        if self._canvas is not None:
            self._canvas.close()
            self._canvas = None
