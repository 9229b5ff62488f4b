"""The quarter car's environment for RL agents: the road under the wheel, as arrays.

``road_agent_env`` builds what ``RLSearch`` acts in on the quarter car: ``QuarterCarBatch``
cars (the QuarterCar-v0 car as one compiled integrator), QuarterCar-v0's observations and a
gentler action than the env's (``ROAD_ACTION_SCALE``, ``ROAD_DEAD_ZONE``).
"""

from __future__ import annotations

import numpy as np

from bushenv.scales import FORCE_FLOOR_N
from bushenv.search.rl import DENSE_CAP, ROAD_ACTION_SCALE, ROAD_DEAD_ZONE, ROBUSTNESS_CLIP


def road_agent_env(evaluator, n_envs, episode_steps, on_episodes, actions=None):
    """SB3 ``VecEnv`` of ``n_envs`` quarter cars (``actions`` is the rig's notion; unused)."""
    return _road_vec_env(evaluator, n_envs, episode_steps, on_episodes)


def _road_vec_env(evaluator, n_envs, episode_steps, on_episodes):
    """SB3 ``VecEnv``: ``n_envs`` QuarterCar-v0 cars driven by the agent's road, as arrays.

    The car is ``QuarterCarBatch`` (the QuarterCar-v0 car as one compiled array integrator,
    agreement with the pymunk env tested in tests/rigs), the model under test on the attacked
    axis and a twin on the rubber. Observations follow QuarterCar-v0's docstring (12 scaled
    values); the action is the road height change per step as a fraction of
    ``ROAD_ACTION_SCALE * max_road_step_m``, ``|a| < ROAD_DEAD_ZONE`` holding the road. All
    cars run episodes of the same length and reset together; at the end the roads are judged
    by ``evaluator`` (the same batched quarter-car path as random search).
    """
    from gymnasium import spaces
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv

    from bushenv.search.roads import make_cars

    axis = evaluator.axis

    class RoadVecEnv(VecEnv):
        def __init__(self) -> None:
            self.car = make_cars(
                evaluator.model, evaluator.reference, n_envs, evaluator.dt, axis, episode_steps
            )
            self.p = self.car.params
            obs = spaces.Box(-1.0, 1.0, shape=(12,), dtype=np.float32)
            act = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
            super().__init__(n_envs, obs, act)
            self._actions = None
            self._restart()

        def _restart(self) -> None:
            self.car.reset()
            self.h = np.zeros(self.num_envs)
            self.roads: list[np.ndarray] = []
            self.peak = np.full(self.num_envs, FORCE_FLOOR_N)

        def reset(self):
            self._restart()
            return np.zeros((self.num_envs, 12), dtype=np.float32)

        def step_async(self, actions) -> None:
            self._actions = np.asarray(actions, dtype=np.float64).reshape(self.num_envs)

        def _observe(self, out) -> np.ndarray:
            p = self.p
            cols = [
                out["road_height_m"] / p.max_road,
                out["chassis_y_m"] / p.max_body,
                out["chassis_vy_m_per_s"] / p.v_scale,
                out["wheel_y_m"] / p.max_body,
                out["wheel_vy_m_per_s"] / p.v_scale,
                out["radial_deflection_m"] / p.max_deflection,
                out["axial_deflection_m"] / p.max_deflection,
                out["force_radial_model_n"] / p.force_limit,
                out["force_axial_model_n"] / p.force_limit,
                out["force_radial_reference_n"] / p.force_limit,
                out["force_axial_reference_n"] / p.force_limit,
                (out["chassis_y_m"] - out["reference_chassis_y_m"]) / p.max_body,
            ]
            obs = np.nan_to_num(np.stack(cols, axis=1), nan=0.0, posinf=1.0, neginf=-1.0)
            return np.clip(obs, -1.0, 1.0).astype(np.float32)

        def step_wait(self):
            p = self.p
            a = np.clip(np.nan_to_num(self._actions, nan=0.0), -1.0, 1.0)
            a = np.where(np.abs(a) < ROAD_DEAD_ZONE, 0.0, a)  # lets the agent hold the road
            step = ROAD_ACTION_SCALE * p.max_road_step
            self.h = np.clip(self.h + a * step, -p.max_road, p.max_road)
            out = self.car.step(self.h)
            self.roads.append(self.h.copy())
            obs = self._observe(out)
            fm = out[f"force_{axis}_model_n"]
            fr = out[f"force_{axis}_reference_n"]
            np.maximum(self.peak, np.abs(fr), out=self.peak)
            with np.errstate(invalid="ignore"):
                dense = np.abs(fm - fr) / self.peak
            dense = np.where(np.isfinite(dense), np.minimum(dense, DENSE_CAP), DENSE_CAP)
            reward = dense / episode_steps
            dones = np.zeros(self.num_envs, dtype=bool)
            infos = [{} for _ in range(self.num_envs)]
            if len(self.roads) >= episode_steps:
                road = np.stack(self.roads, axis=1)  # (n, T)
                batch = evaluator.evaluate(list(road))
                rob = np.clip(batch.verdict.robustness, -ROBUSTNESS_CLIP, ROBUSTNESS_CLIP)
                reward = reward - rob
                on_episodes(batch)
                dones[:] = True
                for i in range(self.num_envs):
                    infos[i]["terminal_observation"] = obs[i].copy()
                    infos[i]["TimeLimit.truncated"] = True
                obs = self.reset()
            return obs, reward.astype(np.float32), dones, infos

        def close(self) -> None:
            pass

        def seed(self, seed=None):
            return [seed] * self.num_envs

        def get_attr(self, attr_name, indices=None):
            return [getattr(self, attr_name, None)] * self.num_envs

        def set_attr(self, attr_name, value, indices=None) -> None:
            setattr(self, attr_name, value)

        def env_method(self, method_name, *args, indices=None, **kwargs):
            return [None] * self.num_envs

        def env_is_wrapped(self, wrapper_class, indices=None):
            return [False] * self.num_envs

    return RoadVecEnv()
