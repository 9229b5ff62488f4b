"""BushRigVectorEnv: N bushing test rigs stepped as arrays (``vector_entry_point`` of BushRig-v0).

The rig's displacement is prescribed (see ``BushRigEnv``), so a rig needs no pymunk body to
know its motion: N rigs are N columns of arrays, and the two models run through their batched
``step`` on (N,) arrays -- the same compiled kernels the single env calls with B = 1. Every
operation on a column is the single env's operation on its floats (IEEE double, same order:
action clean-up, x + a * step, clip, (x - x0) / dt, F / limit, the reward), so column i of this
env equals a ``BushRigEnv`` given the same actions, bit for bit (tests/rigs/test_vector.py).

Autoreset is next-step (``metadata["autoreset_mode"]``): the step after a sub-environment's
episode ended returns its reset observation, reward 0 and no termination; its models' columns
are returned to rest with ``initial_state``, except rows shared by all columns (a ring-buffer
position the kernel reads from column 0; ``common.shared_state_rows``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from bushenv.rigs.bushrig import ENV_ID, BushRigEnv, RigParameters, check_excitation
from bushenv.rigs.common import (
    MODEL_ERRORS,
    ForceDeviationReward,
    RigError,
    call_reset,
    call_reset_columns,
    check_hook,
    check_options,
    force_observations,
    positive_int,
    reset_columns,
    shared_state_rows,
    spec_kwargs,
    unit_actions,
)

INFO_KEYS = (
    "time_s",
    "step",
    "displacement_m",
    "velocity_m_per_s",
    "force_model_n",
    "force_reference_n",
    "error_n",
    "model_force_finite",
    "model_over_force_limit",
    "reference_over_force_limit",
    "monitor_verdict",
    "diverged",
    "machine_limit",
    "divergence_reason",
)


class BushRigVectorEnv(VectorEnv):
    """N BushRig-v0 rigs as arrays. Arguments as ``BushRigEnv`` plus ``num_envs``; ``info``
    holds (N,) arrays under the single env's keys (and Gymnasium's ``_key`` masks).
    ``reset(options={"excitation": x})`` takes x of shape (T,) (every rig) or (T, N)."""

    metadata = {
        "render_modes": ["rgb_array"],
        "render_fps": 50,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 1,
        *,
        render_mode: str | None = None,
        reward_fn=None,
        divergence_monitor=None,
        **spec_overrides: Any,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise RigError(f"render_mode must be one of {self.metadata['render_modes']}")
        self.num_envs = n = positive_int("num_envs", num_envs)
        p = RigParameters(spec_kwargs(ENV_ID, spec_overrides))
        self.params = p
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
        self._t = np.zeros(n, dtype=np.int64)
        self._end = np.full(n, p.episode_steps, dtype=np.int64)
        self._replay: np.ndarray | None = None
        self._prev_done = np.zeros(n, dtype=bool)
        self._columns = np.arange(n)
        self._masks = {"_" + k: np.ones(n, dtype=bool) for k in INFO_KEYS}
        self._render_env: BushRigEnv | None = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        p, n = self.params, self.num_envs
        self._replay = None
        self._end[:] = p.episode_steps
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
        zeros = np.zeros(n)
        info = self._info(
            zeros, zeros, zeros, zeros, np.ones(n, bool), *(np.zeros(n, bool),) * 3, None
        )
        return self._obs.reshape(n, -1).copy(), info

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

        raised = ""
        try:
            f_m = np.array(self.model.step(x, v), dtype=np.float64)
        except MODEL_ERRORS as exc:
            # The batched step refused as a whole; the histories that caused it show non-finite
            # forces in the model's output buffer (all columns are judged if none do).
            raised = f"model raised {type(exc).__name__}: {exc}"
            buffer = getattr(self.model, "_f1", None)
            f_m = np.array(buffer[0] if buffer is not None else np.full(n, np.nan), np.float64)
            if f_m.shape != (n,) or np.isfinite(f_m).all():
                f_m = np.full(n, np.nan)
        f_r = np.array(self.reference.step(x, v), dtype=np.float64)

        obs = self._obs
        obs[:, :, 1:] = obs[:, :, :-1]
        obs[:, 0, 0] = x / p.max_x
        obs[:, 1, 0] = force_observations(f_m, p.force_limit)
        obs[:, 2, 0] = force_observations(f_r, p.force_limit)

        finite = np.isfinite(f_m)
        ref_over = ~(np.abs(f_r) <= p.force_limit)
        model_over = finite & (np.abs(np.where(finite, f_m, 0.0)) > p.force_limit) & ~ref_over
        terminated = ~finite | (model_over & ~ref_over)
        truncated = ref_over & finite
        reasons = np.full(n, "", dtype=object)
        reasons[~finite] = raised or "model force is not finite"
        for i in np.flatnonzero(model_over & finite):
            reasons[i] = f"|F_model| = {abs(f_m[i]):.6g} N exceeds {p.force_limit:.6g} N"
        monitor = np.zeros(n, dtype=bool)
        info = self._info(x, v, f_m, f_r, finite, model_over, ref_over, monitor, reasons)
        if self.divergence_monitor is not None:
            verdict = np.asarray(self.divergence_monitor(info), dtype=bool)
            verdict = np.broadcast_to(verdict, (n,)) & ~terminated
            monitor[:] = verdict
            reasons[verdict] = "divergence monitor"
            terminated = terminated | verdict
        info["diverged"] = terminated.copy()
        truncated = truncated | (self._t >= self._end)
        reward = np.asarray(self.reward_fn(info), dtype=np.float64).copy()

        done = self._prev_done
        if done.any():  # next-step autoreset of the rigs whose episode ended last step
            reset_columns(self.model, done, self._shared[0])
            reset_columns(self.reference, done, self._shared[1])
            call_reset_columns(self.reward_fn, done)
            call_reset_columns(self.divergence_monitor, done)
            obs[done] = 0.0
            self._x[done] = 0.0
            self._t[done] = 0
            reward[done] = 0.0
            terminated[done] = False
            truncated[done] = False
            for key in INFO_KEYS:
                arr = info[key]
                arr[done] = "" if key == "divergence_reason" else (key == "model_force_finite")
        self._prev_done = terminated | truncated
        return obs.reshape(n, -1).copy(), reward, terminated, truncated, info

    def _info(self, x, v, f_m, f_r, finite, model_over, ref_over, monitor, reasons):
        n = self.num_envs
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
            "diverged": np.zeros(n, dtype=bool),
            "machine_limit": ref_over.copy(),
            "divergence_reason": reasons if reasons is not None else np.full(n, "", object),
        }
        for k, m in self._masks.items():
            info[k] = m.copy()
        return info

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
