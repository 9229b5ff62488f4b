"""What the array vector envs (``BushRigVectorEnv``, ``QuarterCarVectorEnv``) share: the episode
length, the autoreset of finished columns, the hooks' column resets and the info masks.

Autoreset follows Gymnasium's two modes (``autoreset_mode=``):

- ``NEXT_STEP`` (default, Gymnasium's default): the step after a column's episode ended returns
  its reset observation, reward 0, no termination, and ignores its action.
- ``SAME_STEP``: the step that ends a column's episode resets it at once; the returned
  observation and ``info`` are the new episode's, the last ones are in ``info["final_obs"]``
  (object array, None for running columns) and ``info["final_info"]`` (the step's info arrays),
  masked by ``info["_final_obs"]`` / ``info["_final_info"]``. SB3 needs this mode
  (``bushenv.rigs.sb3``).

The episode length is ``max_episode_steps`` (what ``gym.make_vec`` passes from the spec, like
Gymnasium's ``CartPoleVectorEnv``); ``episode_steps`` is the same number under its former name,
kept while callers move, and wins when both are given.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv

from bushenv.rigs.common import RigError, call_reset_columns, positive_int
from bushenv.rigs.specs import max_episode_steps as spec_episode_steps


def autoreset_mode_of(value: Any) -> AutoresetMode:
    """``AutoresetMode`` from the enum or its value (``"NextStep"``, ``"SameStep"``)."""
    modes = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP)
    for mode in modes:
        if value is mode or value == mode.value:
            return mode
    raise RigError(
        f"autoreset_mode must be one of {[m.value for m in modes]} (gymnasium.vector."
        f"AutoresetMode), got {value!r}"
    )


class ArrayVectorEnv(VectorEnv):
    """Base of the array vector envs. Subclasses call ``super().__init__`` first in their
    ``__init__``, write their step's arrays, call ``_end_step`` last, and implement
    ``_reset_columns(mask)`` (physics and models of the columns ``mask`` back to rest) and
    ``_rest_info()`` (one column's info at rest, plain values)."""

    metadata = {
        "render_modes": ["rgb_array"],
        "render_fps": 204.8,  # the papers' rate; each env sets 1 / its dt
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self, env_id, num_envs, max_episode_steps, episode_steps, autoreset_mode, render_mode=None
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise RigError(f"render_mode must be one of {self.metadata['render_modes']}")
        self.env_id = env_id
        self.num_envs = positive_int("num_envs", num_envs)
        if episode_steps is not None:  # the former name of max_episode_steps
            max_episode_steps = positive_int("episode_steps", episode_steps)
        self.max_episode_steps = spec_episode_steps(env_id, max_episode_steps)
        self.autoreset_mode = autoreset_mode_of(autoreset_mode)
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode}
        n = self.num_envs
        self._t = np.zeros(n, dtype=np.int64)
        self._end = np.full(n, self.max_episode_steps, dtype=np.int64)
        self._prev_done = np.zeros(n, dtype=bool)

    def _reset_columns(self, mask: np.ndarray) -> None:
        raise NotImplementedError

    def _rest_info(self) -> dict[str, Any]:
        raise NotImplementedError

    def _restart_columns(self, mask: np.ndarray, obs: np.ndarray, info: dict[str, Any]) -> None:
        """Columns ``mask`` to rest: physics, models, hooks, step counter; their observation
        rows (a view into the returned batch) and info entries take the rest values."""
        self._reset_columns(mask)
        call_reset_columns(self.reward_fn, mask)
        call_reset_columns(self.divergence_monitor, mask)
        self._t[mask] = 0
        obs[mask] = 0.0
        for key, value in self._rest_info().items():
            info[key][mask] = value

    def _end_step(self, obs, reward, terminated, truncated, info):
        """Time limit and autoreset; returns the step's five values."""
        truncated = truncated | (self._t >= self._end)
        if self.autoreset_mode is AutoresetMode.NEXT_STEP:
            done = self._prev_done
            if done.any():
                self._restart_columns(done, obs, info)
                reward[done] = 0.0
                terminated[done] = False
                truncated[done] = False
            self._prev_done = terminated | truncated
            return obs, reward, terminated, truncated, info
        done = terminated | truncated
        if done.any():
            final_obs = np.full(self.num_envs, None, dtype=object)
            for i in np.flatnonzero(done):
                final_obs[i] = obs[i].copy()
            final_info = {k: v.copy() for k, v in info.items()}
            info["final_obs"], info["_final_obs"] = final_obs, done.copy()
            info["final_info"], info["_final_info"] = final_info, done.copy()
            self._restart_columns(done, obs, info)
        return obs, reward, terminated, truncated, info

    def _masks(self, info: dict[str, Any]) -> dict[str, Any]:
        """``info`` with Gymnasium's ``_key`` masks (every column has every key)."""
        ones = np.ones(self.num_envs, dtype=bool)
        for key in list(info):
            info["_" + key] = ones.copy()
        return info
