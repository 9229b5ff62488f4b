"""The quarter car's environment for RL agents: QuarterCar-v0's vector env, road by road.

``road_agent_env`` builds what ``RLSearch`` acts in on the quarter car: ``n_envs`` cars of
QuarterCar-v0's vector entry point (``QuarterCarBatch``, within 1 % of the pymunk env), the model
under test on the attacked axis and a twin on the reference, adapted to SB3 by the public
``SB3VecEnv``. The agent's action is gentler than the env's (``ROAD_ACTION_SCALE``; below
``ROAD_DEAD_ZONE`` it holds the road, where the free response is judged). Each car's road is
judged by the evaluator when its episode ends -- at the episode's length, or earlier when either
car leaves its bounds -- like any other road profile.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import VecEnvWrapper

from bushenv.models import get_reference
from bushenv.rigs.sb3 import SB3VecEnv
from bushenv.search.rl import DENSE_CAP, ROAD_ACTION_SCALE, ROAD_DEAD_ZONE, ROBUSTNESS_CLIP


class RoadReward:
    """``reward_fn`` hook: dense force deviation on the attacked axis, and when a car's episode
    ends, ``-robustness`` of its road from the evaluator (ended roads judged in one batch)."""

    def __init__(self, n_envs: int, episode_steps: int, evaluator, on_episodes) -> None:
        self.n, self.episode_steps = n_envs, episode_steps
        self.evaluator, self.on_episodes = evaluator, on_episodes
        self.axis = evaluator.axis
        self.floor = evaluator.scales.force_floor_n
        self.roads: list[list[float]] = [[] for _ in range(self.n)]
        self.peak = np.full(self.n, self.floor)

    def reset(self) -> None:
        self.reset_columns(np.ones(self.n, dtype=bool))

    def reset_columns(self, mask) -> None:
        for i in np.flatnonzero(mask):
            self.roads[i] = []
            self.peak[i] = self.floor

    def __call__(self, info) -> np.ndarray:
        fm = np.asarray(info[f"force_{self.axis}_model_n"], dtype=np.float64)
        fr = np.asarray(info[f"force_{self.axis}_reference_n"], dtype=np.float64)
        for i, h in enumerate(np.asarray(info["road_height_m"], dtype=np.float64)):
            self.roads[i].append(float(h))
        np.maximum(self.peak, np.abs(fr), out=self.peak)
        with np.errstate(invalid="ignore"):
            dense = np.abs(fm - fr) / self.peak
        dense = np.where(np.isfinite(dense), np.minimum(dense, DENSE_CAP), DENSE_CAP)
        reward = dense / self.episode_steps
        ended = (
            np.asarray(info["diverged"], dtype=bool)
            | np.asarray(info["physical_limit"], dtype=bool)
            | (np.asarray(info["step"]) >= self.episode_steps)
        )
        idx = np.flatnonzero(ended)
        if idx.size:
            batch = self.evaluator.evaluate([np.array(self.roads[i]) for i in idx])
            rob = np.clip(batch.verdict.robustness, -ROBUSTNESS_CLIP, ROBUSTNESS_CLIP)
            reward[idx] -= rob
            self.on_episodes(batch)
        return reward


class RoadActions(VecEnvWrapper):
    """The agent's gentler road action: |a| < ``ROAD_DEAD_ZONE`` holds the road, the rest is
    scaled by ``ROAD_ACTION_SCALE`` (QuarterCar-v0's full action throws the twin car against its
    bump stops within 0.1-0.3 s on a random policy, after which nothing can be judged)."""

    def reset(self):
        return self.venv.reset()

    def step_async(self, actions) -> None:
        a = np.clip(np.nan_to_num(np.asarray(actions, np.float64), nan=0.0), -1.0, 1.0)
        a = np.where(np.abs(a) < ROAD_DEAD_ZONE, 0.0, a) * ROAD_ACTION_SCALE
        self.venv.step_async(a.astype(np.float32))

    def step_wait(self):
        return self.venv.step_wait()


def road_agent_env(evaluator, n_envs, episode_steps, on_episodes, actions=None):
    """SB3 ``VecEnv`` of ``n_envs`` quarter cars (``actions`` is the rig's notion; unused)."""
    axis = evaluator.axis
    other = "axial" if axis == "radial" else "radial"
    other_ref = get_reference("rubber", axis=other, dt=evaluator.dt)
    venv = gym.make_vec(
        "QuarterCar-v0",
        num_envs=n_envs,
        vectorization_mode="vector_entry_point",
        model={axis: evaluator.model.copy(), other: other_ref.copy()},
        reference={axis: evaluator.reference.copy(), other: other_ref.copy()},
        dt_s=evaluator.dt,
        max_episode_steps=episode_steps,
        autoreset_mode="SameStep",
        reward_fn=RoadReward(n_envs, episode_steps, evaluator, on_episodes),
        trust_reference=True,  # the evaluator's judge vetted it already
    )
    return RoadActions(SB3VecEnv(venv))
