"""QuarterCarVectorEnv: N QuarterCar-v0 car pairs as arrays (``vector_entry_point``).

The cars are ``QuarterCarBatch`` (the QuarterCar-v0 car as one compiled array integrator, a
model car and its reference twin per column); actions, observations, rewards, hooks, info keys,
reset options and the episode's end (``car.car_verdict``) are ``QuarterCarEnv``'s, on (N,)
arrays. The integrator solves the three dampers together where pymunk solves them one by one,
so a column follows the pymunk env within 1 % of each signal's peak over an episode
(tests/rigs/test_quartercar_vector.py; docs/envs.md), not bit for bit. With ``arm_bushing``
(one planar model per car) info adds the pymunk env's planar keys as arrays (docs/planar.md
gives that agreement).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from bushenv.rigs.actions import check_options, unit_actions
from bushenv.rigs.car import Car, check_road
from bushenv.rigs.car_bushings import AXES
from bushenv.rigs.car_verdict import (
    beyond_bounds,
    car_verdict,
    force_reason,
    moment_reason,
    out_of_bounds,
    reference_range_reason,
)
from bushenv.rigs.common import ForceDeviationReward, RigError, call_reset, check_hook
from bushenv.rigs.quartercar import ENV_ID, OBS_SIZE, QuarterCarEnv, observation_values
from bushenv.rigs.quartercar_batch import ROTATION_KEYS, TH, X_U, Y_C, Y_U, QuarterCarBatch
from bushenv.rigs.vector_base import ArrayVectorEnv

TEXT_KEYS = ("model_out_of_bounds", "reference_out_of_bounds", "divergence_reason", "model_error")
FLAG_KEYS = ("monitor_verdict", "diverged", "physical_limit")
# the batch's outputs that are the env's info under the same key
BATCH_KEYS = (
    "road_height_m",
    "chassis_y_m",
    "chassis_vy_m_per_s",
    "wheel_y_m",
    "wheel_vy_m_per_s",
    "radial_deflection_m",
    "axial_deflection_m",
    "force_radial_model_n",
    "force_axial_model_n",
    "reference_chassis_y_m",
    "reference_chassis_vy_m_per_s",
    "reference_wheel_y_m",
    "reference_wheel_vy_m_per_s",
    "reference_radial_deflection_m",
    "reference_axial_deflection_m",
    "force_radial_reference_n",
    "force_axial_reference_n",
    "error_n",
)


class QuarterCarVectorEnv(ArrayVectorEnv):
    """N QuarterCar-v0 car pairs as arrays.

    Arguments as ``QuarterCarEnv`` plus ``num_envs``, ``max_episode_steps`` (default: the
    spec's 2048) and ``autoreset_mode`` (``NEXT_STEP`` by default, or ``SAME_STEP``; see
    ``vector_base``), the conventions of ``BushRigVectorEnv``. ``info`` holds (N,) arrays under
    ``QuarterCarEnv``'s keys; ``reset(options={"excitation": road})`` takes road heights of
    shape (T,) (every car) or (T, N). A model whose batched step raises ends every column.

    >>> import gymnasium as gym
    >>> import bushenv
    >>> venv = gym.make_vec("QuarterCar-v0", num_envs=4, vectorization_mode="vector_entry_point")
    >>> obs, info = venv.reset(seed=0)
    >>> obs.shape, info["chassis_y_m"].shape
    ((4, 12), (4,))
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
        self.batch = QuarterCarBatch(n, with_reference=True, **spec_overrides)
        self.params = p = self.batch.params
        self._batch_keys = BATCH_KEYS + (ROTATION_KEYS if p.planar else ())
        self._text_keys = TEXT_KEYS + (("reference_outside_range",) if p.planar else ())
        self.metadata = {**self.metadata, "render_fps": 1.0 / p.dt}
        self._overrides = dict(spec_overrides)
        self.render_mode = render_mode
        self.single_action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.single_observation_space = spaces.Box(-1.0, 1.0, (OBS_SIZE,), dtype=np.float32)
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.reward_fn = check_hook("reward_fn", reward_fn) or ForceDeviationReward(
            p.force_scale, p.reward_cap
        )
        self.divergence_monitor = check_hook("divergence_monitor", divergence_monitor)
        self._h = np.zeros(n)
        self._replay: np.ndarray | None = None
        self._columns = np.arange(n)
        self._render_env: QuarterCarEnv | None = None
        self._last_info: dict[str, Any] | None = None  # what render() shows

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        p, n = self.params, self.num_envs
        self._replay = None
        self._end[:] = self.max_episode_steps
        options = check_options(ENV_ID, options)
        if options.get("excitation") is not None:
            h = check_road(options["excitation"], p.max_road, p.max_road_step)
            if h.ndim == 1:
                h = np.repeat(h[:, None], n, axis=1)
            if h.shape[1] != n:
                raise RigError(f"road excitation has {h.shape[1]} columns, expected num_envs={n}")
            self._replay = np.ascontiguousarray(h)
            self._end[:] = h.shape[0]
        self.batch.reset()
        call_reset(self.reward_fn)
        call_reset(self.divergence_monitor)
        self._h[:] = 0.0
        self._t[:] = 0
        self._prev_done[:] = False
        info = {}
        for key, value in self._rest_info().items():
            info[key] = np.full(n, value, dtype=object if isinstance(value, str) else None)
        self._last_info = None
        return np.zeros((n, OBS_SIZE), dtype=np.float32), self._masks(info)

    def step(self, actions):
        p, n = self.params, self.num_envs
        if self._replay is None:
            h = self._h + unit_actions(actions, n, ENV_ID) * p.max_road_step
            np.clip(h, -p.max_road, p.max_road, out=h)
        else:
            h = self._replay[np.minimum(self._t, self._end - 1), self._columns]
        self._h = h
        self._t += 1
        out = self.batch.step(h)
        info = self._last_info = self._info(out)
        terminated, truncated = self._verdict(info)
        if self.divergence_monitor is not None:
            verdict = np.asarray(self.divergence_monitor(info), dtype=bool)
            verdict = np.broadcast_to(verdict, (n,)) & ~(terminated | truncated)
            info["monitor_verdict"][:] = verdict
            info["divergence_reason"][verdict] = "divergence monitor"
            terminated = terminated | verdict
        info["diverged"] = terminated.copy()
        reward = np.asarray(self.reward_fn(info), dtype=np.float64).copy()
        obs = np.stack(observation_values(p, info), axis=1)
        obs = np.clip(np.nan_to_num(obs, nan=0.0, posinf=1.0, neginf=-1.0), -1.0, 1.0)
        obs = obs.astype(np.float32)
        return self._end_step(obs, reward, terminated, truncated, self._masks(info))

    def _info(self, out: dict[str, np.ndarray]) -> dict[str, Any]:
        """The step's info arrays from the batch's outputs (verdict fields still at rest)."""
        p, n = self.params, self.num_envs
        info: dict[str, Any] = {"time_s": self._t * p.dt, "step": self._t.copy()}
        info.update({k: out[k] for k in self._batch_keys})
        for prefix in ("", "reference_"):
            yc, yw = info[prefix + "chassis_y_m"], info[prefix + "wheel_y_m"]
            info[prefix + "suspension_travel_m"] = yw - yc
            info[prefix + "tyre_force_n"] = np.maximum(
                p.k_t * (info["road_height_m"] - yw), -p.tyre_static_n
            )
        info["chassis_y_error_m"] = info["chassis_y_m"] - info["reference_chassis_y_m"]
        for key in self._text_keys:
            info[key] = np.full(n, "", dtype=object)
        for key in FLAG_KEYS:
            info[key] = np.zeros(n, dtype=bool)
        if p.planar:  # where the twin's bushing judges beyond its calibrated rotation
            reference = self.batch.references["arm"]
            theta = info["reference_arm_rotation_rad"]
            limit = getattr(reference, "calibrated_rotation_rad", None)
            for i in np.flatnonzero(np.abs(theta) > limit) if limit is not None else ():
                info["reference_outside_range"][i] = reference_range_reason(reference, theta[i])
        return info

    def _verdict(self, info: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
        """(terminated, truncated) of every column (``car.car_verdict``), with the reasons
        written into ``info`` for the columns whose cars left their bounds."""
        p = self.params
        sides = {}
        for side, prefix in (("model", ""), ("reference", "reference_")):
            forces = np.stack(
                [info[f"force_{axis}_{side}_n"] for axis in AXES]
                + ([info[f"moment_{side}_nm"]] if p.planar else [])
            )
            motion = [info[f"{prefix}{k}"] for k in ("chassis_y_m", "wheel_y_m")]
            motion += [info[f"{prefix}{axis}_deflection_m"] for axis in AXES]
            with np.errstate(invalid="ignore"):
                own = ~(np.abs(forces[:2]) <= p.force_limit).all(axis=0)
                if p.planar:
                    own |= ~(np.abs(forces[2]) <= p.moment_limit)
            sides[side] = (forces, motion, beyond_bounds(p, *motion))
            for i in np.flatnonzero(own | sides[side][2]):
                info[f"{side}_out_of_bounds"][i] = self._why(side, i, forces[:, i], motion)
        terminated, truncated = car_verdict(
            p, sides["model"][0], sides["reference"][0], sides["model"][2], sides["reference"][2]
        )
        info["physical_limit"][:] = truncated
        info["divergence_reason"][terminated] = info["model_out_of_bounds"][terminated]
        return terminated, truncated

    def _why(self, side: str, i: int, forces: np.ndarray, motion: list) -> str:
        """Why car ``side`` of column ``i`` is out, in ``QuarterCarEnv``'s words."""
        yc, yw, xr, xa = (float(m[i]) for m in motion)
        fr, fa = float(forces[0]), float(forces[1])
        p = self.params
        return (
            self.batch.raised[side]
            or force_reason(fr, fa, p.force_limit)
            or (moment_reason(float(forces[2]), p.moment_limit) if p.planar else "")
            or out_of_bounds(p, yc, yw, xr, xa, fr, fa)
        )

    def _reset_columns(self, mask: np.ndarray) -> None:
        self.batch.reset_columns(mask)
        self._h[mask] = 0.0

    def _rest_info(self) -> dict[str, Any]:
        rest: dict[str, Any] = {"time_s": 0.0, "step": 0}
        rest.update(dict.fromkeys(self._batch_keys, 0.0))
        for prefix in ("", "reference_"):
            rest[prefix + "suspension_travel_m"] = 0.0
            rest[prefix + "tyre_force_n"] = 0.0
        rest["chassis_y_error_m"] = 0.0
        rest.update(dict.fromkeys(self._text_keys, ""))
        rest.update(dict.fromkeys(FLAG_KEYS, False))
        return rest

    def render(self):
        """A frame of column 0: a ``QuarterCarEnv`` drawing with its bodies set from the batch."""
        if self.render_mode is None:
            return None
        if self._render_env is None:
            models = {"radial": "linear", "axial": "linear"}  # drawing only; labels below
            kwargs = {**self._overrides, "model": models, "reference": models, "arm_bushing": ""}
            self._render_env = QuarterCarEnv(render_mode="rgb_array", **kwargs)
            self._render_env.params.model_name = self.params.model_name
            self._render_env.params.reference_name = self.params.reference_name
        env, s, n = self._render_env, self.batch.state, self.num_envs
        for car, col in ((env.car, 0), (env.twin, n)):
            _place(car, s[:, col], float(self.batch.road[col]))
        env._t, env._road = int(self._t[0]), float(self._h[0])
        last = self._last_info or {}
        env._info_last = {k: float(last[k][0]) for k in self._batch_keys if k in last}
        return (env.render(),)

    def close_extras(self, **kwargs: Any) -> None:
        if self._render_env is not None:
            self._render_env.close()


def _place(car: Car, column: np.ndarray, road_m: float) -> None:
    """Set a pymunk car's bodies to the batch state ``column`` (only for drawing)."""
    car.chassis.position = (0.0, float(column[Y_C]))
    car.unsprung.position = (float(column[X_U]), float(column[Y_U]))
    car.unsprung.angle = float(column[TH])
    car.road.position = (car.p.L, road_m)
