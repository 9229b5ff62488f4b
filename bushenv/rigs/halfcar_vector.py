"""HalfCarVectorEnv: N HalfCar-v0 envs stepped in turn behind Gymnasium's vector API.

No array integrator yet: each column is a ``HalfCarEnv`` (bit-equal to one made alone), so a
car-step costs what the scalar env's does; a batched form (the quarter car's
``QuarterCarBatch`` for this car: ~7 bodies, 4 three-axis bushings per car) is what would make
it cheaper. The autoreset modes, ``max_episode_steps`` and ``info`` arrays with ``_key`` masks
are ``vector_base.ArrayVectorEnv``'s.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from bushenv.rigs.actions import check_options
from bushenv.rigs.common import RigError
from bushenv.rigs.halfcar import OBS_SIZE, HalfCarEnv
from bushenv.rigs.halfcar_params import ENV_ID
from bushenv.rigs.vector_base import ArrayVectorEnv


class HalfCarVectorEnv(ArrayVectorEnv):
    """N half cars (``HalfCarEnv``) with the scalar env's actions, observations, rewards and
    info keys as (N,) arrays (strings as object arrays). ``reset(options=...)`` takes the
    scalar env's options, each (T,) (every column replays it) or (T, N) (one column each).
    Unlike the array vector envs, the hooks (``reward_fn``, ``divergence_monitor``) are called
    by each column with its own plain-value info, and a column's autoreset returns it to agent
    control (its replay is not restarted).

    >>> import gymnasium as gym
    >>> import numpy as np
    >>> import bushenv
    >>> venv = gym.make_vec("HalfCar-v0", num_envs=2, vectorization_mode="vector_entry_point")
    >>> obs, info = venv.reset(seed=0)
    >>> obs.shape, info["roll_rad"].shape
    ((2, 16), (2,))
    """

    def __init__(
        self,
        num_envs: int = 1,
        *,
        max_episode_steps: int | None = None,
        episode_steps: int | None = None,
        autoreset_mode: Any = "NextStep",
        render_mode: str | None = None,
        reward_fn=None,
        divergence_monitor=None,
        **overrides: Any,
    ) -> None:
        super().__init__(
            ENV_ID, num_envs, max_episode_steps, episode_steps, autoreset_mode, render_mode
        )
        self.render_mode = render_mode
        self.envs = [
            HalfCarEnv(reward_fn=reward_fn, divergence_monitor=divergence_monitor, **overrides)
            for _ in range(self.num_envs)
        ]
        self.reward_fn, self.divergence_monitor = None, None  # the columns call the hooks
        self.metadata = {**self.metadata, "render_fps": self.envs[0].metadata["render_fps"]}
        self.single_action_space = self.envs[0].action_space
        self.single_observation_space = self.envs[0].observation_space
        n = self.num_envs
        self.action_space = spaces.Box(-1.0, 1.0, shape=(n, 3), dtype=np.float32)
        self.observation_space = spaces.Box(-1.0, 1.0, shape=(n, OBS_SIZE), dtype=np.float32)
        self._rest = self.envs[0]._info_last or None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        options = check_options(ENV_ID, options)
        self._t[:] = 0
        self._prev_done[:] = False
        obs, infos = [], []
        for i, env in enumerate(self.envs):
            o, info = env.reset(seed=None if seed is None else seed + i,
                                options=_column(options, i, self.num_envs))  # fmt: skip
            obs.append(o)
            infos.append(info)
        self._rest = infos[0]
        n = min((len(e._replay) for e in self.envs if e._replay is not None), default=None)
        self._end[:] = self.max_episode_steps if n is None else min(n, self.max_episode_steps)
        return np.stack(obs), self._masks(_stack(infos))

    def step(self, actions):
        a = np.asarray(actions, dtype=np.float32)
        if a.shape != (self.num_envs, 3):
            raise RigError(f"{ENV_ID}: actions must have shape ({self.num_envs}, 3), got {a.shape}")
        results = [env.step(a[i]) for i, env in enumerate(self.envs)]
        self._t += 1
        obs = np.stack([r[0] for r in results])
        reward = np.array([r[1] for r in results])
        terminated = np.array([r[2] for r in results])
        truncated = np.array([r[3] for r in results])
        info = _stack([r[4] for r in results])
        return self._end_step(obs, reward, terminated, truncated, self._masks(info))

    def _reset_columns(self, mask: np.ndarray) -> None:
        for i in np.flatnonzero(mask):
            self.envs[i].reset()

    def _rest_info(self) -> dict[str, Any]:
        return {k: v for k, v in self._rest.items() if not k.startswith("_")}

    def render(self):
        return None if self.render_mode is None else self.envs[0].render()

    def close_extras(self, **kwargs: Any) -> None:
        for env in self.envs:
            env.close()


def _column(options: dict[str, Any], i: int, n: int) -> dict[str, Any]:
    out = {}
    for k, v in options.items():
        a = np.asarray(v) if v is not None else None
        out[k] = a[:, i] if a is not None and a.ndim == 2 and a.shape[1] == n else v
    return out


def _stack(infos: list[dict[str, Any]]) -> dict[str, Any]:
    out = {}
    for k in infos[0]:
        values = [d[k] for d in infos]
        out[k] = np.array(values, dtype=object if isinstance(values[0], str) else None)
    return out
