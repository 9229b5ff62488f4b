"""BushRigVectorEnv: N bushing test rigs stepped as arrays (``vector_entry_point`` of BushRig-v0).

The rig's displacement is prescribed (see ``BushRigEnv``), so a rig needs no pymunk body to
know its motion: N rigs are N columns of arrays, and the two models run through their batched
``step`` on (N,) arrays -- the same compiled kernels the single env calls with B = 1. Every
operation on a column is the single env's operation on its floats (IEEE double, same order:
action clean-up, x + a * step, clip, (x - x0) / dt, F / limit, the reward, and the episode's end
from ``divergence.force_termination``), so column i equals a ``BushRigEnv`` given the same
actions, bit for bit (tests/rigs/test_vector.py). An auto-reset column of a model returns to
``initial_state`` except rows shared by all columns (``common.shared_state_rows``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from bushenv.divergence import force_termination
from bushenv.rigs.actions import check_options, unit_actions
from bushenv.rigs.bushrig import ENV_ID, BushRigEnv, RigParameters, check_excitation
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

# info keys and their values at rest (the reset info of one rig)
REST_INFO = {
    "time_s": 0.0,
    "step": 0,
    "displacement_m": 0.0,
    "velocity_m_per_s": 0.0,
    "force_model_n": 0.0,
    "force_reference_n": 0.0,
    "error_n": 0.0,
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
        super().__init__(
            ENV_ID, num_envs, max_episode_steps, episode_steps, autoreset_mode, render_mode
        )
        n = self.num_envs
        p = RigParameters(spec_kwargs(ENV_ID, spec_overrides))
        self.params = p
        self.metadata = p.metadata(self.metadata)
        self._overrides = dict(spec_overrides)
        self.render_mode = render_mode
        self.model, self.reference = p.model, p.reference
        self._shared = (shared_state_rows(self.model), shared_state_rows(self.reference))
        self.single_action_space, self.single_observation_space = p.spaces()
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.reward_fn = check_hook("reward_fn", reward_fn) or ForceDeviationReward(
            p.force_scale, p.reward_cap
        )
        self.divergence_monitor = check_hook("divergence_monitor", divergence_monitor)
        self._obs = np.zeros((n, 3, p.history), dtype=np.float32)
        self._x = np.zeros(n)
        self._replay: np.ndarray | None = None
        self._columns = np.arange(n)
        self._render_env: BushRigEnv | None = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        p, n = self.params, self.num_envs
        self._replay = None
        self._end[:] = self.max_episode_steps
        options = check_options(ENV_ID, options)
        if options.get("excitation") is not None:
            x = check_excitation(options["excitation"], p.max_x, p.max_step)
            if x.ndim == 1:
                x = np.repeat(x[:, None], n, axis=1)
            if x.shape[1] != n:
                raise RigError(f"excitation has {x.shape[1]} columns, expected num_envs={n}")
            self._replay = np.ascontiguousarray(x)
            self._end[:] = x.shape[0]
        self.model.reset(n)
        self.reference.reset(n)
        call_reset(self.reward_fn)
        call_reset(self.divergence_monitor)
        self._obs[:] = 0.0
        self._x[:] = 0.0
        self._t[:] = 0
        self._prev_done[:] = False
        zeros, no = np.zeros(n), np.zeros(n, dtype=bool)
        reasons = np.full(n, "", dtype=object)
        info = self._info(zeros, zeros, zeros, zeros, ~no, no, no, no.copy(), reasons)
        return self._obs.reshape(n, -1).copy(), info

    def _model_forces(self, x: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, str, str]:
        """The model's (N,) forces, the reason if its batched step refused (a divergence), and
        the model's own error if it raised otherwise (``common.MODEL_ERRORS``). A refusal
        refuses the whole batch; the histories that caused it show non-finite forces in what
        the kernel wrote (``last_force_n``); all columns are judged if none do."""
        n = self.num_envs
        try:
            return np.array(self.model.step(x, v), dtype=np.float64), "", ""
        except MODEL_ERRORS as exc:
            f_m = np.array(self.model.last_force_n, np.float64)
            if f_m.shape != (n,) or np.isfinite(f_m).all():
                f_m = np.full(n, np.nan)
            return f_m, f"model raised {type(exc).__name__}: {exc}", ""
        except Exception as exc:  # the model's own bug: ends every episode, not a divergence
            return np.full(n, np.nan), "", model_error_text(exc)

    def step(self, actions):
        p, n = self.params, self.num_envs
        x0 = self._x
        if self._replay is None:
            x = x0 + unit_actions(actions, n, ENV_ID) * p.max_step
            np.clip(x, -p.max_x, p.max_x, out=x)
        else:
            x = self._replay[np.minimum(self._t, self._end - 1), self._columns]
        v = (x - x0) / p.dt
        self._x = x
        self._t += 1
        f_m, raised, model_error = self._model_forces(x, v)
        f_r = np.array(self.reference.step(x, v), dtype=np.float64)

        obs = self._obs
        obs[:, :, 1:] = obs[:, :, :-1]
        obs[:, 0, 0] = x / p.max_x
        obs[:, 1, 0] = force_observations(f_m, p.force_limit)
        obs[:, 2, 0] = force_observations(f_r, p.force_limit)

        non_finite, model_over, ref_over = force_termination(f_m, f_r, p.force_limit)
        terminated = non_finite | model_over
        truncated = ref_over & ~non_finite
        reasons = np.full(n, "", dtype=object)
        reasons[non_finite] = raised or "model force is not finite"
        for i in np.flatnonzero(model_over):
            reasons[i] = f"|F_model| = {abs(f_m[i]):.6g} N exceeds {p.force_limit:.6g} N"
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
        reset_columns(self.model, mask, self._shared[0])
        reset_columns(self.reference, mask, self._shared[1])
        self._obs[mask] = 0.0
        self._x[mask] = 0.0

    def _rest_info(self) -> dict[str, Any]:
        return REST_INFO

    def _info(self, x, v, f_m, f_r, finite, model_over, ref_over, monitor, reasons):
        info = {
            "time_s": self._t * self.params.dt,
            "step": self._t.copy(),
            "displacement_m": x.copy(),
            "velocity_m_per_s": v.copy(),
            "force_model_n": f_m,
            "force_reference_n": f_r,
            "error_n": f_m - f_r,
            "model_force_finite": finite.copy(),
            "model_over_force_limit": model_over.copy(),
            "reference_over_force_limit": ref_over.copy(),
            "monitor_verdict": monitor,
            "diverged": np.zeros(self.num_envs, dtype=bool),
            "machine_limit": ref_over.copy(),
            "divergence_reason": reasons,
            "model_error": np.full(self.num_envs, "", dtype=object),
        }
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
        env._last = (
            float(self._x[0]),
            float(self._obs[0, 1, 0]) * p.force_limit,
            float(self._obs[0, 2, 0]) * p.force_limit,
        )
        return (env.render(),)

    def close_extras(self, **kwargs: Any) -> None:
        if self._render_env is not None:
            self._render_env.close()
