"""stable-baselines3's ``VecEnv`` over the array vector envs, so an agent trains on N rigs at once.

    from stable_baselines3 import PPO
    from bushenv.rigs.sb3 import make_sb3_vec_env

    venv = make_sb3_vec_env("BushRig-v0", num_envs=32, model="nn")
    PPO("MlpPolicy", venv, n_steps=64).learn(10_000)

``SB3VecEnv`` adapts a Gymnasium vector env of this package (``BushRigVectorEnv``,
``QuarterCarVectorEnv``; N columns in one object, ~40 us per rig-step instead of ~600 us for N
wrapped single envs in ``DummyVecEnv``) to SB3's conventions, as SB3's ``DummyVecEnv`` does for
single envs: ``done = terminated | truncated``; on ``done`` the returned observation already
starts the next episode, and ``infos[i]["terminal_observation"]`` holds the last one;
``infos[i]["TimeLimit.truncated"]`` says the episode was cut, not ended; ``seed(s)`` takes effect
at the next ``reset()`` (the vector env gets ``s``; SB3 numbers sub-envs ``s + i``, but one
vector env takes one seed; both bushenv envs draw nothing at random) and ``set_options`` too.

Autoreset: over a ``SAME_STEP`` vector env (what ``make_sb3_vec_env`` builds) this is exact.
Over a ``NEXT_STEP`` one (Gymnasium's default) the adapter returns the column's reset observation
(from the last ``reset()``; both envs start every episode at rest, all zeros) when it is done,
and SB3 then sees the vector env's autoreset step as one more transition of the new episode: the
action is ignored, reward 0, the observation still the rest one. Kept for callers that need the
rollouts they had.

One vector env is one object: ``get_attr``/``set_attr``/``env_method`` reach that object and
answer once per index.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices

from bushenv.rigs.common import RigError


class SB3VecEnv(VecEnv):
    """SB3 ``VecEnv`` over ``venv``, a Gymnasium vector env with ``autoreset_mode`` NEXT_STEP or
    SAME_STEP in its metadata. ``info_keys``: keys of the vector env's (N,) info arrays copied
    into each sub-env's info dict as plain values (none by default: SB3 needs none, and each
    costs a Python loop over the N envs per step)."""

    def __init__(self, venv: VectorEnv, info_keys: Sequence[str] = ()) -> None:
        mode = venv.metadata.get("autoreset_mode", AutoresetMode.NEXT_STEP)
        if mode not in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP):
            raise RigError(f"SB3VecEnv needs a NextStep or SameStep autoreset, got {mode!r}")
        self.venv = venv
        self.same_step = mode is AutoresetMode.SAME_STEP
        self.info_keys = tuple(info_keys)
        self._actions: np.ndarray | None = None
        self._rest_obs: np.ndarray | None = None
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)

    # ----- the VecEnv protocol ------------------------------------------------------------------
    def reset(self) -> np.ndarray:
        obs, info = self.venv.reset(seed=self._seeds[0], options=self._one_options())
        self._rest_obs = obs.copy()
        # the list SB3's VecEnv.__init__ made, refilled
        self.reset_infos[:] = self._per_env(info, np.zeros(self.num_envs, dtype=bool))
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=np.float32).reshape(self.num_envs, -1)

    def step_wait(self):
        obs, reward, terminated, truncated, info = self.venv.step(self._actions)
        done = terminated | truncated
        infos = self._per_env(info, done)
        for i, inf in enumerate(infos):
            inf["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        for i in np.flatnonzero(done):
            if self.same_step:
                infos[i]["terminal_observation"] = info["final_obs"][i]
                self.reset_infos[i] = {}
            else:
                infos[i]["terminal_observation"] = obs[i].copy()
                obs[i] = self._rest_obs[i]  # what the vector env returns on its autoreset step
        return obs, reward.astype(np.float32), done, infos

    def close(self) -> None:
        self.venv.close()

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        value = getattr(self.venv, attr_name)  # AttributeError if absent, as SB3 expects
        return [value] * len(list(self._get_indices(indices)))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Set ``attr_name`` on the vector env: shared by every sub-env, whatever ``indices``."""
        setattr(self.venv, attr_name, value)

    def env_method(
        self, method_name: str, *method_args, indices: VecEnvIndices = None, **method_kwargs
    ) -> list[Any]:
        """Call the vector env's ``method_name`` once; its result stands for every index."""
        result = getattr(self.venv, method_name)(*method_args, **method_kwargs)
        return [result] * len(list(self._get_indices(indices)))

    def env_is_wrapped(
        self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None
    ) -> list[bool]:
        return [False] * len(list(self._get_indices(indices)))

    def get_images(self) -> Sequence[np.ndarray | None]:
        frames = self.venv.render()
        return list(frames) if frames is not None else [None] * self.num_envs

    # ----- helpers --------------------------------------------------------------------------
    def _one_options(self) -> dict[str, Any] | None:
        """SB3 keeps options per sub-env; a vector env takes one dict for all of them."""
        first = self._options[0]
        for other in self._options[1:]:
            if other.keys() != first.keys() or any(
                not np.array_equal(np.asarray(other[k]), np.asarray(first[k])) for k in first
            ):
                raise RigError(
                    "set_options gave the sub-envs different options; a vector env takes one "
                    "dict for all, e.g. set_options({'excitation': profiles}) with profiles "
                    "of shape (T, num_envs)"
                )
        return dict(first) or None

    def _per_env(self, info: dict[str, Any], done: np.ndarray) -> list[dict[str, Any]]:
        """One info dict per sub-env holding ``info_keys`` (for a column that was reset in this
        step: the values its episode ended with)."""
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        final = info.get("final_info", {})
        for key in self.info_keys:
            values, last = info[key], final.get(key)
            for i, inf in enumerate(infos):
                v = last[i] if last is not None and done[i] else values[i]
                inf[key] = v.item() if isinstance(v, np.generic) else v
        return infos


def make_sb3_vec_env(env_id: str, num_envs: int, info_keys: Sequence[str] = (), **kwargs: Any):
    """``SB3VecEnv`` over ``gym.make_vec(env_id, num_envs, vector_entry_point, SAME_STEP)``;
    ``kwargs`` go to the vector env (spec overrides, ``max_episode_steps``, hooks).

    >>> from bushenv.rigs.sb3 import make_sb3_vec_env
    >>> venv = make_sb3_vec_env("BushRig-v0", num_envs=4, model="linear")
    >>> venv.seed(0)
    [0, 1, 2, 3]
    >>> venv.reset().shape
    (4, 12)
    """
    import bushenv  # noqa: F401  (registers the envs)

    venv = gym.make_vec(
        env_id,
        num_envs=num_envs,
        vectorization_mode="vector_entry_point",
        autoreset_mode=AutoresetMode.SAME_STEP,
        **kwargs,
    )
    return SB3VecEnv(venv, info_keys=info_keys)
