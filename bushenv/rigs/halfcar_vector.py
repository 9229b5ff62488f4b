"""HalfCarVectorEnv: N HalfCar-v0 car pairs as arrays (``vector_entry_point``).

The cars are ``HalfCarBatch`` (the HalfCar-v0 car as one compiled array integrator, a model car
and its reference twin per column); actions, observations, rewards, hooks, info keys, reset
options and the episode's end are ``HalfCarEnv``'s, on (N,) arrays. The integrator makes every
damper implicit Euler at the current configuration where the pymunk car refreshes its
coefficients every 0.02 rad, so a column follows the pymunk env within 1 % of each output's
peak (tests/rigs/test_halfcar_vector.py, docs/envs.md), not bit for bit. The autoreset modes,
``max_episode_steps`` and the ``_key`` masks are ``vector_base.ArrayVectorEnv``'s.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from bushenv.rigs.actions import check_options
from bushenv.rigs.car_verdict import reference_range_reason
from bushenv.rigs.common import ForceDeviationReward, RigError, call_reset, check_hook
from bushenv.rigs.halfcar import OBS_SIZE, HalfCarEnv
from bushenv.rigs.halfcar_batch import HalfCarBatch
from bushenv.rigs.halfcar_batch_kernels import ANG, PX, PY
from bushenv.rigs.halfcar_batch_layout import BODIES
from bushenv.rigs.halfcar_batch_outputs import RESULT_KEYS
from bushenv.rigs.halfcar_inputs import REPLAY_KEYS, replay_inputs
from bushenv.rigs.halfcar_outputs import (
    PIVOT_KEYS,
    force_reason,
    observation_values,
    out_of_bounds,
)
from bushenv.rigs.halfcar_params import ENV_ID, POSITIONS
from bushenv.rigs.vector_base import ArrayVectorEnv

TEXT_KEYS = ("model_out_of_bounds", "reference_out_of_bounds", "divergence_reason", "model_error",
             "reference_outside_range")  # fmt: skip
FLAG_KEYS = ("monitor_verdict", "diverged", "physical_limit")
INFO_KEYS = tuple(k for k in RESULT_KEYS if k not in (*FLAG_KEYS, "reference_outside_range"))


class HalfCarVectorEnv(ArrayVectorEnv):
    """N HalfCar-v0 car pairs as arrays.

    Arguments as ``HalfCarEnv`` plus ``num_envs``, ``max_episode_steps`` (default: the spec's
    2048), ``autoreset_mode`` (``NEXT_STEP`` by default, or ``SAME_STEP``) and ``threads``
    (``HalfCarBatch``'s). ``info`` holds (N,) arrays under ``HalfCarEnv``'s keys (strings as
    object arrays); ``reset(options=...)`` takes the scalar env's options, each (T,) (every
    column) or (T, N). The hooks get the info arrays and return (N,) arrays. A model whose
    batched step raises a bug of its own (``ModelRaised``) ends every column: it propagates.

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
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        render_mode: str | None = None,
        reward_fn=None,
        divergence_monitor=None,
        threads: int = 1,
        **overrides: Any,
    ) -> None:
        super().__init__(
            ENV_ID, num_envs, max_episode_steps, episode_steps, autoreset_mode, render_mode
        )
        n = self.num_envs
        self.batch = HalfCarBatch(n, threads=threads, **overrides)
        self.params = p = self.batch.params
        self._overrides = dict(overrides)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": 1.0 / p.dt}
        self.single_action_space = spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        self.single_observation_space = spaces.Box(-1.0, 1.0, (OBS_SIZE,), dtype=np.float32)
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.reward_fn = check_hook("reward_fn", reward_fn) or ForceDeviationReward(
            p.force_scale, p.reward_cap
        )
        self.divergence_monitor = check_hook("divergence_monitor", divergence_monitor)
        self._inputs = np.zeros((3, n))
        self._replay: np.ndarray | None = None  # (T, 3, N)
        self._columns = np.arange(n)
        self._render_env: HalfCarEnv | None = None
        self._last_info: dict[str, Any] | None = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        n = self.num_envs
        self._replay = _replay(self.params, check_options(ENV_ID, options), n)
        self._end[:] = self.max_episode_steps
        if self._replay is not None:
            self._end[:] = min(self._replay.shape[0], self.max_episode_steps)
        self.batch.reset()
        call_reset(self.reward_fn)
        call_reset(self.divergence_monitor)
        self._inputs[:] = 0.0
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
            a = np.asarray(actions, dtype=np.float64)
            if a.shape != (n, 3):
                raise RigError(f"{ENV_ID}: actions must have shape ({n}, 3), got {a.shape}")
            a = np.clip(np.nan_to_num(a, nan=0.0), -1.0, 1.0).T
            step = np.array([p.max_road_step, p.max_road_step, p.max_ay_step])[:, None]
            limit = np.array([p.max_road, p.max_road, p.max_ay])[:, None]
            now = np.clip(self._inputs + a * step, -limit, limit)
        else:
            now = self._replay[np.minimum(self._t, self._end - 1), :, self._columns].T
        self._inputs = now
        self._t += 1
        out = self.batch.step(now[0], now[1], now[2])
        info = self._last_info = self._info(out)
        terminated, truncated = out["diverged"], out["physical_limit"]
        for side, bad in (("model", terminated), ("reference", truncated)):
            for i in np.flatnonzero(bad):
                info[f"{side}_out_of_bounds"][i] = self._why(side, info, i)
        info["divergence_reason"][terminated] = info["model_out_of_bounds"][terminated]
        info["physical_limit"][:] = truncated
        if self.divergence_monitor is not None:
            verdict = np.asarray(self.divergence_monitor(info), dtype=bool)
            verdict = np.broadcast_to(verdict, (n,)) & ~(terminated | truncated)
            info["monitor_verdict"][:] = verdict
            info["divergence_reason"][verdict] = "divergence monitor"
            terminated = terminated | verdict
        info["diverged"] = terminated.copy()
        reward = np.asarray(self.reward_fn(info), dtype=np.float64).copy()
        obs = observations(p, info)
        return self._end_step(obs, reward, terminated.copy(), truncated.copy(), self._masks(info))

    def _info(self, out: dict[str, np.ndarray]) -> dict[str, Any]:
        """The step's info arrays (verdict fields at rest; the twin's range said where it is
        beyond)."""
        n = self.num_envs
        info: dict[str, Any] = {"time_s": self._t * self.params.dt, "step": self._t.copy()}
        info.update({k: out[k] for k in INFO_KEYS})
        for key in TEXT_KEYS:
            info[key] = np.full(n, "", dtype=object)
        for key in FLAG_KEYS:
            info[key] = np.zeros(n, dtype=bool)
        refs = self.params.references
        for i in np.flatnonzero(out["reference_outside_range"]):
            for k, (_, _, motion) in zip(POSITIONS, PIVOT_KEYS, strict=True):
                ref = refs[k] if isinstance(refs, dict) else refs
                why = reference_range_reason(ref, float(info[motion[2]][i]))
                if why:
                    info["reference_outside_range"][i] = f"{k}: {why}"
                    break
        return info

    def _why(self, side: str, info: dict[str, Any], i: int) -> str:
        """Why car ``side`` of column ``i`` left its bounds, in ``HalfCarEnv``'s words."""
        prefix = "" if side == "model" else "reference_"
        keys = ("body_x_m", "body_y_m", "wheel_left_y_m", "wheel_right_y_m", "roll_rad",
                "travel_left_m", "travel_right_m")  # fmt: skip
        out = {k: float(info[prefix + k][i]) for k in keys}
        forces = np.array([[info[key[side == "reference"]][i] for key in force_keys]
                           for force_keys, _, _ in PIVOT_KEYS])  # fmt: skip
        motion = 1 if side == "model" else 2
        q = np.array([[info[k][i] for k in keys3[motion]] for keys3 in PIVOT_KEYS])
        return (
            self.batch.raised[side]
            or force_reason(self.params, forces)
            or out_of_bounds(self.params, out, q)
            or "out of bounds"
        )

    def _reset_columns(self, mask: np.ndarray) -> None:
        self.batch.reset_columns(mask)
        self._inputs[:, mask] = 0.0

    def _rest_info(self) -> dict[str, Any]:
        rest: dict[str, Any] = {"time_s": 0.0, "step": 0}
        rest.update(dict.fromkeys(INFO_KEYS, 0.0))
        for side in ("left", "right"):
            for prefix in ("", "reference_"):
                rest[f"{prefix}wheel_load_{side}_n"] = self.params.tyre_static_n
                rest[f"{prefix}wheel_lift_{side}"] = False
        rest.update(dict.fromkeys(TEXT_KEYS, ""))
        rest.update(dict.fromkeys(FLAG_KEYS, False))
        return rest

    def render(self):
        """A frame of column 0: a ``HalfCarEnv`` drawing with its bodies set from the batch."""
        if self.render_mode is None:
            return None
        if self._render_env is None:
            self._render_env = HalfCarEnv(render_mode="rgb_array", **self._overrides)
        env, s, n = self._render_env, self.batch.state, self.num_envs
        for car, col in ((env.car, 0), (env.twin, n)):
            for k, name in enumerate(BODIES):
                car.bodies[name].position = (float(s[PX, k, col]), float(s[PY, k, col]))
                car.bodies[name].angle = float(s[ANG, k, col])
        last = self._last_info or {}
        env._info_last = {k: v[0].item() for k, v in last.items() if isinstance(v, np.ndarray)}
        return (env.render(),)

    def close_extras(self, **kwargs: Any) -> None:
        if self._render_env is not None:
            self._render_env.close()


def observations(p: Any, info: dict[str, Any]) -> np.ndarray:
    """(N, 16) float32: ``HalfCarEnv``'s observation of every column's info."""
    rows = observation_values(p, info, np.hypot)
    obs = np.nan_to_num(np.stack(rows, axis=1), nan=0.0, posinf=1.0, neginf=-1.0)
    return np.clip(obs, -1.0, 1.0).astype(np.float32)


def _replay(p: Any, options: dict[str, Any], n: int) -> np.ndarray | None:
    """(T, 3, N) replayed inputs from the options ((T,) or (T, N) each), or None."""
    given = {k: np.asarray(v, dtype=np.float64) for k, v in options.items() if v is not None}
    if not given:
        return None
    for k, v in given.items():
        if k in REPLAY_KEYS and (v.ndim not in (1, 2) or (v.ndim == 2 and v.shape[1] != n)):
            raise RigError(f"{ENV_ID}: reset option {k} must be (T,) or (T, {n}), got {v.shape}")
    columns = []
    for j in range(n):
        one = {k: (v[:, j] if v.ndim == 2 else v) for k, v in given.items()}
        columns.append(replay_inputs(p, one))  # the scalar env's checks, its error messages
    return np.stack(columns, axis=2)
