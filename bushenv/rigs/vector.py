"""BushRigVectorEnv: N bushing test rigs stepped as arrays (``vector_entry_point`` of BushRig-v0
and BushRig3-v0).

The rig's motion is prescribed (see ``BushRigEnv``), so a rig needs no pymunk body to know its
motion: N rigs of C coordinates are (N, C) arrays, and the two models run through their
batched ``step`` -- the same compiled kernels the single env calls with B = 1. Every operation
on a column is the single env's operation on its floats (IEEE double, same order: action
clean-up, x + a * step, clip, (x - x0) / dt, F / limit, the reward, and the episode's end from
``divergence.force_termination``), so column i equals a ``BushRigEnv`` given the same actions,
bit for bit (tests/rigs/test_vector.py). An auto-reset column of a model returns to
``initial_state`` except rows shared by all columns (``common.shared_state_rows``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from bushenv.divergence import force_termination
from bushenv.rigs.actions import check_options, unit_actions
from bushenv.rigs.bushrig import BushRigEnv, over_reason
from bushenv.rigs.bushrig_params import RigParameters, spec_id
from bushenv.rigs.common import (
    MODEL_ERRORS,
    ForceDeviationReward,
    RigError,
    call_reset,
    check_hook,
    force_observations,
    model_error_text,
    reset_columns,
    shared_state_rows,
)
from bushenv.rigs.specs import spec_kwargs
from bushenv.rigs.vector_base import ArrayVectorEnv

# info keys beside the per-coordinate ones, and their values at rest
REST_FLAGS = {
    "model_force_finite": True,
    "model_over_force_limit": False,
    "reference_over_force_limit": False,
    "monitor_verdict": False,
    "diverged": False,
    "machine_limit": False,
    "divergence_reason": "",
    "model_error": "",
}


class BushRigVectorEnv(ArrayVectorEnv):
    """N BushRig-v0 rigs as arrays.

    Arguments as ``BushRigEnv`` plus ``num_envs``, ``max_episode_steps`` (default: the spec's
    2048) and ``autoreset_mode`` (``NEXT_STEP`` by default, or ``SAME_STEP``; see
    ``vector_base``). ``info`` holds (N,) arrays under the single env's keys (and Gymnasium's
    ``_key`` masks); hooks get those arrays and return (N,) arrays.
    ``reset(options={"excitation": x})`` takes x of shape (T,) (every rig) or (T, N).

    >>> import gymnasium as gym
    >>> import bushenv
    >>> venv = gym.make_vec("BushRig-v0", num_envs=3, vectorization_mode="vector_entry_point")
    >>> obs, info = venv.reset(seed=0)
    >>> obs.shape, info["force_model_n"].shape, venv.unwrapped.max_episode_steps
    ((3, 12), (3,), 2048)
    """

    def __init__(
        self,
        num_envs: int = 1,
        *,
        max_episode_steps: int | None = None,
        episode_steps: int | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        render_mode: str | None = None,
        reward_fn=None,
        divergence_monitor=None,
        **spec_overrides: Any,
    ) -> None:
        env_id = spec_id(spec_overrides)
        super().__init__(
            env_id, num_envs, max_episode_steps, episode_steps, autoreset_mode, render_mode
        )
        n = self.num_envs
        p = RigParameters(spec_kwargs(env_id, spec_overrides), env_id)
        self.params = p
        self.metadata = p.metadata(self.metadata)
        self._overrides = dict(spec_overrides)
        self.render_mode = render_mode
        self.model, self.reference = p.model, p.reference
        self._shared = tuple(
            shared_state_rows(m) for m in (self.model, self.reference) if m is not None
        )
        self.single_action_space, self.single_observation_space = p.spaces()
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.keys = p.info_keys()
        self.reward_fn = check_hook("reward_fn", reward_fn) or ForceDeviationReward(
            p.force_scale, p.reward_cap, self.keys["error"]
        )
        self.divergence_monitor = check_hook("divergence_monitor", divergence_monitor)
        c = p.n_coords
        self._obs = np.zeros((n, 3, c, p.history), dtype=np.float32)
        self._x = np.zeros((n, c))
        self._rest = np.zeros((n, c))  # the reference's forces when there is none
        self._replay: np.ndarray | None = None  # (T, N, C)
        self._columns = np.arange(n)
        self._render_env: BushRigEnv | None = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        p, n, c = self.params, self.num_envs, self.params.n_coords
        self._replay = None
        self._end[:] = self.max_episode_steps
        options = check_options(self.env_id, options)
        if options.get("excitation") is not None:
            x = p.check_excitation(options["excitation"], vector=True)
            every = x.ndim == (1 if c == 1 else 2)  # one profile for every rig
            x = x.reshape(x.shape[0], -1, c)
            if every:
                x = np.repeat(x, n, axis=1)
            if x.shape[1] != n:
                raise RigError(f"excitation has {x.shape[1]} columns, expected num_envs={n}")
            self._replay = np.ascontiguousarray(x)
            self._end[:] = x.shape[0]
        for m in (self.model, self.reference):
            if m is not None:
                m.reset(n)
        call_reset(self.reward_fn)
        call_reset(self.divergence_monitor)
        self._obs[:] = 0.0
        self._x[:] = 0.0
        self._t[:] = 0
        self._prev_done[:] = False
        zeros, no = np.zeros((n, c)), np.zeros(n, dtype=bool)
        reasons = np.full(n, "", dtype=object)
        info = self._info(zeros, zeros, zeros, zeros, ~no, no, no, no.copy(), reasons)
        return self._obs.reshape(n, -1).copy(), info

    def _forces(self, model, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(N, C) forces of ``model`` at (N, C) ``x``, ``v``: one coordinate as (N,) steps."""
        n, c = x.shape
        if c == 1:
            return np.array(model.step(x[:, 0], v[:, 0]), dtype=np.float64).reshape(n, 1)
        return np.array(model.step(x, v), dtype=np.float64)

    def _model_forces(self, x: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, str, str]:
        """The model's (N, C) forces, the reason if its batched step refused (a divergence),
        and the model's own error if it raised otherwise (``common.MODEL_ERRORS``). A refusal
        refuses the whole batch; the histories that caused it show non-finite forces in what
        the kernel wrote (``last_force_n``); all columns are judged if none do."""
        n, c = x.shape
        try:
            return self._forces(self.model, x, v), "", ""
        except MODEL_ERRORS as exc:
            f_m = np.array(self.model.last_force_n, np.float64)
            if f_m.size != n * c or np.isfinite(f_m).all():
                f_m = np.full(n * c, np.nan)
            return f_m.reshape(n, c), f"model raised {type(exc).__name__}: {exc}", ""
        except Exception as exc:  # the model's own bug: ends every episode, not a divergence
            return np.full((n, c), np.nan), "", model_error_text(exc)

    def step(self, actions):
        p, n = self.params, self.num_envs
        x0 = self._x
        if self._replay is None:
            a = unit_actions(actions, n, self.env_id, p.n_coords).reshape(n, p.n_coords)
            x = x0 + a * p.max_step
            np.clip(x, -p.max_x, p.max_x, out=x)
        else:
            x = self._replay[np.minimum(self._t, self._end - 1), self._columns]
        v = (x - x0) / p.dt
        self._x = x
        self._t += 1
        f_m, raised, model_error = self._model_forces(x, v)
        f_r = self._rest if self.reference is None else self._forces(self.reference, x, v)

        obs = self._obs
        obs[..., 1:] = obs[..., :-1]
        obs[:, 0, :, 0] = x / p.max_x
        obs[:, 1, :, 0] = force_observations(f_m, p.force_limit)
        obs[:, 2, :, 0] = force_observations(f_r, p.force_limit)

        nf, mo, ro = force_termination(f_m, f_r, p.force_limit)
        non_finite, ref_over = nf.any(axis=1), ro.any(axis=1)
        model_over = mo.any(axis=1) & ~ref_over  # a reference beyond a limit: no verdict
        terminated = non_finite | model_over
        truncated = ref_over & ~non_finite
        reasons = np.full(n, "", dtype=object)
        reasons[non_finite] = raised or "model force is not finite"
        for i in np.flatnonzero(model_over):
            j = int(np.argmax(mo[i]))
            reasons[i] = over_reason(p, f_m[i, j], j)
        monitor = np.zeros(n, dtype=bool)
        info = self._info(x, v, f_m, f_r, ~non_finite, model_over, ref_over, monitor, reasons)
        if self.divergence_monitor is not None:
            verdict = np.asarray(self.divergence_monitor(info), dtype=bool)
            verdict = np.broadcast_to(verdict, (n,)) & ~terminated
            monitor[:] = verdict
            reasons[verdict] = "divergence monitor"
            terminated = terminated | verdict
        info["diverged"] = terminated.copy()
        if model_error:
            info["diverged"][:] = False
            reasons[:] = ""
            info["model_error"] = np.full(n, model_error, dtype=object)
            terminated = np.ones(n, dtype=bool)
        reward = np.asarray(self.reward_fn(info), dtype=np.float64).copy()
        return self._end_step(obs.reshape(n, -1).copy(), reward, terminated, truncated, info)

    def _reset_columns(self, mask: np.ndarray) -> None:
        models = [m for m in (self.model, self.reference) if m is not None]
        for m, shared in zip(models, self._shared, strict=True):
            reset_columns(m, mask, shared)
        self._obs[mask] = 0.0
        self._x[mask] = 0.0

    def _rest_info(self) -> dict[str, Any]:
        rest: dict[str, Any] = {"time_s": 0.0, "step": 0}
        for kind, names in self.keys.items():
            if kind != "f_r" or self.reference is not None:
                rest.update(dict.fromkeys(names, 0.0))
        return {**rest, **REST_FLAGS}

    def _info(self, x, v, f_m, f_r, finite, model_over, ref_over, monitor, reasons):
        k, n = self.keys, self.num_envs
        info: dict[str, Any] = {"time_s": self._t * self.params.dt, "step": self._t.copy()}
        for i, name in enumerate(k["q"]):
            info[name] = x[:, i].copy()
        for i, name in enumerate(k["v"]):
            info[name] = v[:, i].copy()
        for i, name in enumerate(k["f_m"]):
            info[name] = f_m[:, i]
        if self.reference is not None:
            for i, name in enumerate(k["f_r"]):
                info[name] = f_r[:, i]
        for i, name in enumerate(k["error"]):
            info[name] = f_m[:, i] - f_r[:, i]
        info.update(
            {
                "model_force_finite": finite.copy(),
                "model_over_force_limit": model_over.copy(),
                "reference_over_force_limit": ref_over.copy(),
                "monitor_verdict": monitor,
                "diverged": np.zeros(n, dtype=bool),
                "machine_limit": ref_over.copy(),
                "divergence_reason": reasons,
                "model_error": np.full(n, "", dtype=object),
            }
        )
        return self._masks(info)

    def render(self):
        """A frame of rig 0 (drawn by a ``BushRigEnv`` set to its state)."""
        if self.render_mode is None:
            return None
        if self._render_env is None:
            kwargs = {**self._overrides, "model": self.model.copy()}
            self._render_env = BushRigEnv(render_mode="rgb_array", **kwargs)
        env = self._render_env
        env._t = int(self._t[0])
        p = self.params
        env._last = (  # the first coordinate: the drawing's
            float(self._x[0, 0]),
            float(self._obs[0, 1, 0, 0]) * float(p.force_limit[0]),
            float(self._obs[0, 2, 0, 0]) * float(p.force_limit[0]),
        )
        return (env.render(),)

    def close_extras(self, **kwargs: Any) -> None:
        if self._render_env is not None:
            self._render_env.close()
