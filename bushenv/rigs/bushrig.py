"""BushRig-v0 and BushRig3-v0: the bushing test rig over C coordinates as a Gymnasium env.

The actuator's motion is prescribed, so the rig is a function of the commanded position of each
coordinate: ``BushRigEnv`` (here) and ``BushRigVectorEnv`` (``vector.py``) step the same models
with the same arithmetic, whatever C (read from the spec's limits, ``bushrig_params``), and
decide the episode's end with ``divergence.force_termination``, the function the divergence
judge calls.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pymunk

from bushenv.divergence import force_termination
from bushenv.rigs.actions import check_options, unit_vector
from bushenv.rigs.bushrig_params import ENV_ID, RigParameters, spec_id
from bushenv.rigs.common import (
    MODEL_ERRORS,
    ForceDeviationReward,
    RigError,
    ask_monitor,
    call_reset,
    check_hook,
    force_observation,
    model_error_text,
)
from bushenv.rigs.coupling import space_stepper, velocity_setter
from bushenv.rigs.drawing import Canvas, Trace
from bushenv.rigs.scenes import draw_bushrig
from bushenv.rigs.specs import spec_kwargs

ACTUATOR_MASS_KG = 10.0  # piston and fixture; drawn only, the motion is prescribed
# pymunk objects and chipmunk call handles: rebuilt on unpickling, not pickled (see __getstate__)
PHYSICS_ATTRS = ("space", "ground", "actuator", "groove", "_space_step", "_set_actuator_velocity")


def build_physics() -> tuple:
    """The rig's pymunk objects, in ``PHYSICS_ATTRS`` order: the space, its static body, the
    actuator, the groove, and the chipmunk calls that step the space and set the actuator's
    velocity (the first coordinate's: the drawing's)."""
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


def model_forces(model, x: list[float], v: list[float]) -> list[float]:
    """The model's force per coordinate at (x, v): one coordinate as floats (the models' fast
    path), several as a (C,) step."""
    if len(x) == 1:
        return [model.step(x[0], v[0])]
    return model.step(np.array(x), np.array(v)).tolist()


def over_reason(p: RigParameters, force: float, i: int) -> str:
    """Why the model's force of coordinate ``i`` ends the episode: beyond its limit."""
    label = "F_model" if p.n_coords == 1 else f"F_model {p.coords[i]}"
    unit = p.model.force_units[i]
    return f"|{label}| = {abs(force):.6g} {unit} exceeds {p.force_limit[i]:.6g} {unit}"


class BushRigEnv(gym.Env):
    """
    ## Description

    The bushing test rig of seed 001 §4 (Fig. 11, built there in ADAMS) over C coordinates of
    the bushing: BushRig-v0 drives one (``axis``: axial or radial), BushRig3-v0 the 3-axis
    elastomer tester's three in the bushing's plane (seed 000 §4.1, Fig. 8; seed 002 Table 1:
    axial and radial translation, m, and the in-plane rotation, rad) at once. An actuator body
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

    ``Box(-1, 1, (C,), float32)``: per coordinate the change of the commanded position this
    step, as a fraction of the largest change the machine allows (seed 002 Table 1)::

        x_k = clip(x_{k-1} + a * v_max * dt, -x_max, x_max)     v_max = 1.2566 m/s, x_max = 12.5 mm

    so |a| = 1 is the velocity limit (6.14 mm per step at 204.8 Hz; BushRig3-v0's rotation
    15.08 rad/s within +-0.15 rad, the same rule). NaN counts as 0, values beyond +-1 (also
    +-inf) as +-1: no number raises. An action that is not C real numbers (text, None,
    complex, an array of another shape) is refused with a ``RigError`` naming the action
    space and the expected shape (C,).

    ## Observation Space

    ``Box(-1, 1, (3 C H,), float32)``, H = ``history`` (4 by default), newest sample first,
    each block of H per coordinate c in order:

    | index              | observation                                   | min | max |
    |--------------------|-----------------------------------------------|-----|-----|
    | c H .. (c+1) H - 1 | position x_c,k-i / x_max,c                    | -1  | 1   |
    | (C + c) H ..       | model force F_model,c,k-i / force_limit_c     | -1  | 1   |
    | (2 C + c) H ..     | reference force F_ref,c,k-i / force_limit_c   | -1  | 1   |

    Forces are clipped to [-1, 1] (beyond is a divergence or a machine-limit end anyway); a
    NaN force shows as 0; without a reference its block stays 0.

    ## Rewards

    ``ForceDeviationReward``: r = min(sum_c |F_model,c - F_ref,c| / force_scale_c, reward_cap),
    and reward_cap when that is not finite. ``force_scale`` is the Table-1 stiffness times the
    stroke per coordinate (4.7 kN axial, 19 kN radial, 450 N m rotation; with a user's
    reference over several coordinates left at the spec's: that bushing's static stiffness
    times the stroke). Without a reference F_ref is 0 (the model's own force: the search then
    looks for the verdicts that need no reference). Replace it with ``reward_fn(info)`` (e.g.
    an STL robustness from ``bushenv.search``).

    ## Starting State

    At rest: x = 0, both models reset (zero deflection, zero force), observation all zeros.
    Nothing is random, so every seed gives the same episode for the same actions.

    ## Episode End

    Termination (the model's verdict, ``info["diverged"]``): a force of the model is not finite
    or the model refused to go on (``ModelRefused``, an ``ArithmeticError``:
    ``ZeroDivisionError``, ``FloatingPointError``, ``OverflowError``); |F_model,c| >
    ``force_limit`` (25 kN, the machine's dynamic force; 2.5 kN m for a rotation) while the
    reference stays within every limit; or ``divergence_monitor(info)`` is truthy. A bug of
    the model's own ends the episode as ``info["model_error"]``, never a divergence.
    Truncation: the reference itself needs more than the machine's limits
    (``info["machine_limit"]``: the motion cannot be run on the real rig, so it judges
    nothing); the end of a replayed excitation; and, through ``gym.make``, Gymnasium's
    ``TimeLimit`` at the spec's ``max_episode_steps`` (2048 steps = 10 s;
    ``gym.make(..., max_episode_steps=N)`` changes it, -1 removes it, e.g. to replay a longer
    profile). The env built directly (``BushRigEnv()``) has no time limit of its own, like
    Gymnasium's ``CartPoleEnv``.

    ## Info

    ``time_s``, ``step``, per coordinate the position, its rate, both forces and the error
    (model minus reference) -- one coordinate: ``displacement_m``, ``velocity_m_per_s``,
    ``force_model_n``, ``force_reference_n``, ``error_n``; several: ``q_<c>``,
    ``velocity_<c>``, ``force_model_<c>``, ``force_reference_<c>`` (not without a reference),
    ``error_<c>`` in the coordinate's units -- then ``model_force_finite``,
    ``model_over_force_limit``, ``reference_over_force_limit``, ``monitor_verdict``,
    ``diverged``, ``machine_limit``, ``divergence_reason`` ("" if none), ``model_error``.
    Plain Python values.

    ## Arguments

    Every key of the spec's ``[kwargs]`` plus ``reward_fn``, ``divergence_monitor`` (see
    ``bushenv.rigs.common``) and ``render_mode``. ``envs/BushRig-v0.toml``: ``model``,
    ``axis``, ``reference`` (vetted before it judges), ``trust_reference``, ``dt_s``,
    ``physics_substeps``, ``history``, ``max_displacement_m``, ``max_velocity_m_per_s``,
    ``force_limit_n``, ``reward_cap``, ``force_scale_n``. ``envs/BushRig3-v0.toml``: ``model``
    (a name in ``bushenv.models.MODELS`` whose three-axis form has a preset, a three-axis
    ``.npz`` file, or a model), ``reference`` (the same, ``"none"``, or ``"default"``: the
    built-in coupled rubber beside a registered model, none beside a user's model, with a
    warning saying so), ``dt_s``, ``history``, ``reward_cap`` and the tables ``stroke``,
    ``rate``, ``force_limit``, ``force_scale`` by coordinate (``bushrig_params``)::

        env = gym.make("BushRig-v0", model="nn", axis="radial")
        env = gym.make("BushRig-v0", model="fits/axial_nn.npz")
        env = gym.make("BushRig3-v0", model="fits/nn3.npz", reference="fits/hbw3.npz")
        obs, info = env.reset(options={"excitation": x})  # replay x exactly; actions ignored

    ## Vectorized environment

    ``gym.make_vec("BushRig-v0", num_envs=N, vectorization_mode="vector_entry_point")`` gives
    ``BushRigVectorEnv``: N rigs as arrays through the models' batched step, the same kernels
    and arithmetic, bit for bit equal to N single envs (next-step autoreset).
    ``bushenv.rigs.sb3.make_sb3_vec_env("BushRig-v0", N)`` gives it to stable-baselines3.

    ## Rendering

    ``render_fps`` = 1 / ``dt_s`` (204.8): one frame per step, so a video written at
    ``render_fps`` (``gymnasium.wrappers.RecordVideo``) plays in real time, and ``"human"``
    paces its window to the simulated time. The drawing shows the first coordinate.

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
    >>> env = gym.make("BushRig3-v0", model="linear")
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape
    (36,)
    >>> obs, reward, terminated, truncated, info = env.step(np.array([1, 0, -1], np.float32))
    >>> round(info["q_axial"] * 1e3, 3), round(info["q_rotation"], 4)
    (6.136, -0.0736)

    ## Version History

    - v0: as in seed 001 §4. Since: the episode length is the spec's ``max_episode_steps``
      (Gymnasium's ``TimeLimit``; the kwarg ``episode_steps`` is gone), ``render_fps`` is
      1 / ``dt_s``, the env pickles and deep-copies, and the id is also registered as
      ``bushenv/BushRig-v0``. The dynamics and every number an episode gives are unchanged.
    - BushRig3-v0 v0: first version, its own env class. Since: the same class as BushRig-v0
      over three coordinates (replayed excitations, the hooks, ``model_error``, the info's
      verdict keys and rendering came with it); the reference ``"default"`` (none beside a
      user's model file, said) and ``"none"``, and the force scale of a user's reference,
      came without a new id: with the built-in models every number is unchanged.
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
        self.env_id = spec_id(spec_overrides)
        p = RigParameters(spec_kwargs(self.env_id, spec_overrides), self.env_id)
        self.params = p
        self.metadata = p.metadata(type(self).metadata)
        self.render_mode = render_mode
        self.model, self.reference = p.model, p.reference
        self.action_space, self.observation_space = p.spaces()
        self.keys = p.info_keys()
        self.reward_fn = check_hook("reward_fn", reward_fn) or ForceDeviationReward(
            p.force_scale, p.reward_cap, self.keys["error"]
        )
        self.divergence_monitor = check_hook("divergence_monitor", divergence_monitor)
        c = p.n_coords
        self._dt, self._h = p.dt, p.dt / p.substeps
        # per coordinate as floats: the step's arithmetic is the vector env's, one column
        self._max_x, self._max_step = p.max_x.tolist(), p.max_step.tolist()
        self._limit = p.force_limit.tolist()
        self._rest = [0.0] * c
        # the observation's (3, C, H) blocks as rows kind * C + coordinate, newest sample first
        self._obs = np.zeros((3 * c, p.history), dtype=np.float32)
        self._names = self.keys["q"] + self.keys["v"] + self.keys["f_m"] + self.keys["error"]
        if self.reference is not None:
            self._names += self.keys["f_r"]
        self._x = list(self._rest)
        self._t = 0
        self._replay: np.ndarray | None = None  # (T, C)
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
        options = check_options(self.env_id, options)
        if options.get("excitation") is not None:
            x = p.check_excitation(options["excitation"], vector=False)
            if p.n_coords == 1 and x.ndim != 1:
                raise RigError(f"excitation for one rig must be (T,), got {x.shape}")
            self._replay = x.reshape(x.shape[0], p.n_coords)
            self._end = x.shape[0]
        self.model.reset(1)
        if self.reference is not None:
            self.reference.reset(1)
        call_reset(self.reward_fn)
        call_reset(self.divergence_monitor)
        self._obs[:] = 0.0
        self._x = list(self._rest)
        self._t = 0
        self.actuator.position = (0.0, 0.0)
        self.actuator.velocity = (0.0, 0.0)
        self._last = (0.0, 0.0, 0.0)
        if self._trace is not None:
            self._trace.clear()
        rest = self._rest
        info = self._info(rest, rest, rest, rest, True, False, False, "")
        if self.render_mode == "human":
            self.render()
        return self._obs.ravel().copy(), info

    def _next_position(self, action) -> list[float]:
        """The commanded position of this step per coordinate: the action's change, clipped to
        the stroke, or the replayed sample."""
        if self._replay is not None:
            return self._replay[min(self._t, self._end - 1)].tolist()
        a = unit_vector(action, len(self._x), self.env_id)
        out = []
        for i, x0 in enumerate(self._x):
            x, limit = x0 + a[i] * self._max_step[i], self._max_x[i]
            out.append(limit if x > limit else (-limit if x < -limit else x))
        return out

    def step(self, action):
        p = self.params
        x0 = self._x
        x = self._next_position(action)
        dt = self._dt
        v = [(x[i] - x0[i]) / dt for i in range(len(x))]
        self._x = x
        self._t += 1

        reason = model_error = ""
        try:
            f_m = model_forces(self.model, x, v)
        except MODEL_ERRORS as exc:  # a model refusing to go on (Bouc-Wen's guard), 1/0, ...
            f_m = [math.nan] * len(x)
            reason = f"model raised {type(exc).__name__}: {exc}"
        except Exception as exc:  # the model's own bug: ends the episode, not a divergence
            f_m = [math.nan] * len(x)
            model_error = model_error_text(exc)
        f_r = self._rest if self.reference is None else model_forces(self.reference, x, v)

        self._set_actuator_velocity(v[0], 0.0)
        for _ in range(p.substeps):
            self._space_step(self._h)

        obs = self._obs
        obs[:, 1:] = obs[:, :-1]
        calm = True
        c = len(x)
        for i, limit in enumerate(self._limit):
            obs[i, 0] = x[i] / self._max_x[i]
            obs[c + i, 0] = force_observation(f_m[i], limit)
            obs[2 * c + i, 0] = force_observation(f_r[i], limit)
            calm = calm and abs(f_m[i]) <= limit and abs(f_r[i]) <= limit

        if calm:
            # every force finite and within its limit: force_termination cannot fire (tested);
            # not calling it saves its ~3 us of numpy calls, a fifth of the step
            non_finite = model_over = ref_over = False
        else:
            nf, mo, ro = force_termination(np.array(f_m), np.array(f_r), p.force_limit)
            non_finite, ref_over = bool(nf.any()), bool(ro.any())
            model_over = bool(mo.any()) and not ref_over  # a reference beyond a limit: no verdict
        finite = not non_finite
        terminated = non_finite or model_over
        truncated = ref_over and finite
        if non_finite:
            reason = reason or "model force is not finite"
        elif model_over:
            i = int(np.argmax(mo))
            reason = over_reason(p, f_m[i], i)
        if model_error:
            reason = ""
        info = self._info(x, v, f_m, f_r, finite, model_over, ref_over, reason)
        if self.divergence_monitor is not None and not terminated:
            terminated = ask_monitor(self.divergence_monitor, info)
        info["diverged"] = terminated and not model_error
        info["model_error"] = model_error
        terminated = terminated or bool(model_error)
        if self._end is not None and self._t >= self._end:
            truncated = True
        reward = float(self.reward_fn(info))
        self._last = (x[0], f_m[0], f_r[0])
        if self._trace is not None:
            self._trace.push(x[0], f_m[0], f_r[0])
        if self.render_mode == "human":
            self.render()
        return obs.ravel().copy(), reward, terminated, truncated, info

    def _info(self, x, v, f_m, f_r, finite, model_over, ref_over, reason):
        info: dict[str, Any] = {"time_s": self._t * self._dt, "step": self._t}
        errors = [f_m[i] - f_r[i] for i in range(len(x))]
        values = x + v + f_m + errors + (f_r if self.reference is not None else [])
        info.update(zip(self._names, values, strict=True))
        info.update(
            {
                "model_force_finite": finite,
                "model_over_force_limit": model_over,
                "reference_over_force_limit": ref_over,
                "monitor_verdict": False,
                "diverged": False,  # set by step once the monitor has spoken
                "machine_limit": ref_over,
                "divergence_reason": reason,
                "model_error": "",  # the model's own exception, when it raised (not a divergence)
            }
        )
        return info

    # ----- drawing ---------------------------------------------------------------------------
    def render(self):
        if self.render_mode is None:
            gym.logger.warn(
                "render() without a render_mode; pass render_mode='rgb_array' to gym.make"
            )
            return None
        if self._canvas is None:
            fps = self.metadata["render_fps"]
            self._canvas = Canvas(600, 400, self.render_mode, fps, self.env_id)
        t_s = self._t * self._dt
        draw_bushrig(self._canvas, self.params, self.env_id, t_s, self._last, self._trace)
        return self._canvas.frame()

    def close(self) -> None:
        if self._canvas is not None:
            self._canvas.close()
            self._canvas = None


__all__ = ["ENV_ID", "BushRigEnv", "build_physics"]
