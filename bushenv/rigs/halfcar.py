"""HalfCar-v0: a roll-plane front axle whose four inner arm pivots are bushings (Gymnasium env).

The car (pymunk bodies, springs, the split bushing coupling) is ``halfcar_car.py``, its
parameters and geometry ``halfcar_params.py``; this module steps a model car beside its
reference twin and turns them into observations, rewards, ``info`` and the episode's end.
``halfcar_vector.py`` steps N car pairs as a vector env through ``halfcar_batch.py``.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from bushenv.rigs.actions import check_options
from bushenv.rigs.car_verdict import MODEL_ERROR_PREFIX, reference_range_reason
from bushenv.rigs.common import (
    ForceDeviationReward,
    RigError,
    ask_monitor,
    call_reset,
    check_hook,
)
from bushenv.rigs.halfcar_car import HalfCar, HalfCarPair
from bushenv.rigs.halfcar_inputs import replay_inputs, unit_actions3
from bushenv.rigs.halfcar_outputs import (
    PIVOT_KEYS,
    car_outputs,
    observation_values,
    out_of_bounds,
    sample,
)
from bushenv.rigs.halfcar_params import ENV_ID, POSITIONS, HalfCarParameters
from bushenv.rigs.specs import spec_kwargs

OBS_SIZE = 16


class HalfCarEnv(gym.Env):
    """
    ## Description

    A roll-plane front axle seen from the front (seeds 000 §5.3 and 001 §5 drove
    full cars with bushing models over bumps, potholes and pulse steer). A sprung body (lateral,
    vertical, roll) sits on two double wishbones; each has a lower and an upper arm whose inner
    pivots hang on the body *through bushings* (no joint: each pivot is one three-coordinate
    bushing model -- axial: lateral in the body frame, outboard positive; radial: vertical in
    the body frame; rotation: the arm relative to the body, wheel-up positive; the right side
    mirrored), an upright with its wheel on two ball joints, a coil-over on the lower arm and a
    tyre (vertical spring and damper, lift-off; lateral spring and damper). A twin car with the
    reference bushings drives the same roads under the same lateral load. One step is one
    bushing-model sample (204.8 Hz); pymunk takes ``physics_substeps`` steps in between, the
    bushing forces split as QuarterCar-v0's (``coupling.SplitBushing``: the planar linear
    torsion preset, ``linear-torsion``, inside every sub-step, the model's remainder held; the
    arms turn their pivots' bushes in torsion, ``halfcar_params.PIVOT_ROTATION``). Geometry
    and data: Project Chrono's Sedan, cited in ``envs/HalfCar-v0.toml``; docs/envs.md gives the
    checks.

    ## Action Space

    ``Box(-1, 1, (3,), float32)``: the left and right road heights' change and the lateral
    acceleration's change this step::

        h_k = clip(h_{k-1} + a_side * max_road_step_m, +-max_road_height_m)       (each side)
        a_y,k = clip(a_y,k-1 + a_2 * max_lateral_accel_step_m_per_s2, +-max_lateral_accel)

    (50 mm, 0.4 m/s^2 per step; +-150 mm, +-8 m/s^2 by default: 0.4 m/s^2 per step is 82
    m/s^3, the standards' fastest steering, NHTSA's fishhook at 720 deg/s, needing 0.375).
    a_y > 0 accelerates the car to its left (a left turn): every body feels -m a_y. NaN counts
    as 0, beyond +-1 as +-1.

    ## Observation Space

    ``Box(-1, 1, (16,), float32)``, each entry clipped, NaN shown as 0 (model car unless
    stated):

    | index | observation                                   | unit  | scale                      |
    |-------|-----------------------------------------------|-------|----------------------------|
    | 0, 1  | road height left, right                       | m     | max_road_height_m          |
    | 2     | lateral acceleration input                    | m/s^2 | max_lateral_accel_m_per_s2 |
    | 3     | body vertical displacement                    | m     | max_body_displacement_m    |
    | 4     | body vertical velocity                        | m/s   | v_s = max_road_step / dt   |
    | 5     | body lateral displacement                     | m     | max_body_displacement_m    |
    | 6     | body roll                                     | rad   | max_roll_rad               |
    | 7     | body roll rate                                | rad/s | 2 v_s / track              |
    | 8, 9  | dynamic wheel load left, right                | N     | tyre static load           |
    | 10-13 | |bushing force| (axial, radial) per pivot     | N     | force_limit_n              |
    | 14    | largest bushing force difference to the twin  | N     | force_limit_n              |
    | 15    | body roll, model car minus reference car      | rad   | max_roll_rad               |

    Pivots in the order ``lower_left, upper_left, lower_right, upper_right``.

    ## Rewards

    ``ForceDeviationReward`` on ``info["error_n"]``, the largest over the four pivots of
    hypot(axial, radial) difference of the two cars' bushing forces: min(error /
    force_scale_n, reward_cap). Replace with ``reward_fn(info)``.

    ## Starting State

    Both cars at rest at design position on flat roads, no lateral load (an exact
    equilibrium), models reset. Deterministic: every seed gives the same episode.

    ## Episode End

    Termination (``info["diverged"]``): the model car leaves its bounds while its twin does
    not -- a state or force not finite, |bushing force| > ``force_limit_n`` or |moment| >
    ``moment_limit_nm`` (judged before it is applied, and never applied), a bushing
    deflection > ``max_bushing_deflection_m``, suspension travel >
    ``max_suspension_travel_m``, body or wheel beyond ``max_body_displacement_m``, roll beyond
    ``max_roll_rad`` -- or the model raised (``ValueError``, ``ArithmeticError``), or
    ``divergence_monitor(info)``. Truncation: the twin leaving its bounds
    (``info["physical_limit"]``), the end of a replay, and through ``gym.make`` the spec's
    ``max_episode_steps`` (2048 = 10 s).

    ## Info

    Plain values. Inputs: ``time_s, step, road_left_m, road_right_m,
    lateral_accel_m_per_s2``. Per car (the twin's with the prefix ``reference_``):
    ``body_y_m, body_x_m, body_vy_m_per_s, body_vertical_accel_m_per_s2,
    body_lateral_accel_m_per_s2`` (inertial: a_y + the body's own), ``roll_rad,
    roll_rate_rad_per_s, track_change_m``, per side ``wheel_load_{side}_n`` (total, >= 0),
    ``wheel_lift_{side}`` (bool), ``camber_{side}_rad`` (top outward positive),
    ``travel_{side}_m``; per pivot ``force_{pivot}_{axial|radial}_{model|reference}_n``,
    ``moment_{pivot}_{model|reference}_nm``, ``deflection_{pivot}_{axial|radial}_m``,
    ``rotation_{pivot}_rad`` (model car) and ``reference_deflection_{pivot}_{axial|radial}_m``,
    ``reference_rotation_{pivot}_rad`` (its twin; all sampled at the step's start, where the
    forces are). Verdict: ``error_n, roll_error_rad,
    model_out_of_bounds, reference_out_of_bounds, monitor_verdict, diverged, physical_limit,
    divergence_reason, model_error``, ``reference_outside_range`` (why a twin's pivot judges
    beyond the rotation its law is calibrated for, "" if none does).

    ## Arguments

    Every key of ``envs/HalfCar-v0.toml`` ``[kwargs]``, plus ``reward_fn``,
    ``divergence_monitor``, ``render_mode``. ``model``/``reference``: a three-axis name
    (``bushenv.models.names_for(3)``), ``.npz`` or model object for all four pivots, or a
    table ``{"lower_left": ..., "upper_left": ..., "lower_right": ..., "upper_right": ...}``.
    ``reset(options={"road_left": (T,), "road_right": (T,), "lateral_accel": (T,)})`` replays
    those inputs exactly (any subset; the others stay 0; equal lengths), ignoring actions, and
    truncates after T steps.

    ## Vectorized environment

    ``gym.make_vec("HalfCar-v0", num_envs=N, vectorization_mode="vector_entry_point")`` gives
    ``HalfCarVectorEnv``: N car pairs as arrays through ``HalfCarBatch`` (the same car in one
    compiled integrator; within 1 % of this env's outputs, not bit for bit), about 20x cheaper
    per car-step (docs/benchmarks.md).

    ## Example

    >>> import gymnasium as gym
    >>> import numpy as np
    >>> import bushenv
    >>> env = gym.make("bushenv/HalfCar-v0")
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape, float(abs(obs).max()), round(info["wheel_load_left_n"])
    ((16,), 0.0, 4096)
    >>> obs, reward, terminated, truncated, info = env.step(np.array([1, 0, 0], np.float32))
    >>> info["road_left_m"], info["road_right_m"], terminated, truncated
    (0.05, 0.0, False, False)

    ## Version History

    - v0: the car of ``envs/HalfCar-v0.toml``; ``max_lateral_accel_step_m_per_s2`` raised
      from 0.25 to 0.4 m/s^2 so the standards' steering events replay as they are (the
      action's a_y step scales with it); info carries the twin's deflections.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 204.8}

    def __init__(
        self, *, render_mode=None, reward_fn=None, divergence_monitor=None, **overrides: Any
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise RigError(f"render_mode must be one of {self.metadata['render_modes']}")
        p = HalfCarParameters(spec_kwargs(ENV_ID, overrides))
        self.params = p
        self.metadata = {**type(self).metadata, "render_fps": 1.0 / p.dt}
        self.render_mode = render_mode
        self.models, self.references = p.models, p.references
        self.action_space = spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        self.observation_space = spaces.Box(-1.0, 1.0, shape=(OBS_SIZE,), dtype=np.float32)
        self.reward_fn = check_hook("reward_fn", reward_fn) or ForceDeviationReward(
            p.force_scale, p.reward_cap
        )
        self.divergence_monitor = check_hook("divergence_monitor", divergence_monitor)
        self.cars = HalfCarPair(p)
        self._inputs = np.zeros(3)  # road left, road right, a_y: the last step's
        self._t = 0
        self._replay: np.ndarray | None = None
        self._prev_v = [(0.0, 0.0), (0.0, 0.0)]  # (car) -> (vx, vy) at the last step
        self._obs = np.zeros(OBS_SIZE, dtype=np.float32)
        self._canvas = None
        self._info_last: dict[str, Any] = {}

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "_canvas": None}

    @property
    def car(self) -> HalfCar:
        return self.cars.car

    @property
    def twin(self) -> HalfCar:
        return self.cars.twin

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        self._replay = replay_inputs(self.params, check_options(ENV_ID, options))
        for models in (self.models, self.references):
            for m, b in _model_batches(models):
                m.reset(b)
        call_reset(self.reward_fn)
        call_reset(self.divergence_monitor)
        self.cars = HalfCarPair(self.params)  # fresh bodies: nothing from the last episode
        self._inputs = np.zeros(3)
        self._t = 0
        self._prev_v = [(0.0, 0.0), (0.0, 0.0)]
        self._obs[:] = 0.0
        zero = np.zeros((4, 3))
        info = self._info((zero, zero, zero, ""), (zero, zero, zero, ""), *self._outputs(), "")
        self._info_last = info
        if self.render_mode == "human":
            self.render()
        return self._obs.copy(), info

    def _next_inputs(self, action) -> np.ndarray:
        if self._replay is not None:
            return self._replay[min(self._t, len(self._replay) - 1)]
        p = self.params
        a = unit_actions3(action)
        step = np.array([p.max_road_step, p.max_road_step, p.max_ay_step])
        limit = np.array([p.max_road, p.max_road, p.max_ay])
        return np.clip(self._inputs + a * step, -limit, limit)

    def step(self, action):
        p = self.params
        before = self._inputs
        now = self._next_inputs(action)
        self._inputs = now
        self._t += 1
        sample_m = sample(self.car, self.models, p)
        sample_r = sample(self.twin, self.references, p)
        self.cars.integrate(before[:2], now[:2], before[2], now[2])
        out_m, out_r = self._outputs((now[:2] - before[:2]) / p.dt)
        why_m = sample_m[3] or out_of_bounds(p, out_m, sample_m[0])
        why_r = sample_r[3] or out_of_bounds(p, out_r, sample_r[0])
        truncated = bool(why_r)
        model_error = (
            why_m[len(MODEL_ERROR_PREFIX) :] if why_m.startswith(MODEL_ERROR_PREFIX) else ""
        )
        terminated = bool(why_m) and not truncated
        info = self._info(sample_m, sample_r, out_m, out_r, why_m if terminated else "")
        info["model_out_of_bounds"], info["reference_out_of_bounds"] = why_m, why_r
        info["physical_limit"] = truncated
        if self.divergence_monitor is not None and not (terminated or truncated):
            terminated = ask_monitor(self.divergence_monitor, info)
        info["diverged"] = terminated and not model_error
        info["model_error"] = model_error
        if self._replay is not None and self._t >= len(self._replay):
            truncated = True
        reward = float(self.reward_fn(info))
        self._observe(info)
        self._info_last = info
        if self.render_mode == "human":
            self.render()
        return self._obs.copy(), reward, terminated, truncated, info

    def _observe(self, info: dict[str, Any]) -> None:
        values = observation_values(self.params, info, math.hypot)
        o = self._obs
        for i, v in enumerate(values):
            o[i] = 0.0 if v != v else (1.0 if v > 1.0 else (-1.0 if v < -1.0 else v))

    def _outputs(self, road_v=(0.0, 0.0)) -> tuple[dict[str, Any], dict[str, Any]]:
        """Both cars' ``car_outputs`` after a step whose roads moved at ``road_v`` (m/s; each
        car remembers its body velocity)."""
        p, roads, ay = self.params, self._inputs[:2].tolist(), float(self._inputs[2])
        road_v = [float(v) for v in road_v]
        outs = []
        for j, car in enumerate((self.car, self.twin)):
            out = car_outputs(p, car, roads, road_v, self._prev_v[j], ay)
            self._prev_v[j] = (out["body_vx_m_per_s"], out["body_vy_m_per_s"])
            outs.append(out)
        return outs[0], outs[1]

    def _info(self, sample_m, sample_r, out_m, out_r, reason: str) -> dict[str, Any]:
        p = self.params
        r_l, r_r, ay = self._inputs.tolist()
        info: dict[str, Any] = {"time_s": self._t * p.dt, "step": self._t, "road_left_m": r_l,
                                "road_right_m": r_r, "lateral_accel_m_per_s2": ay}  # fmt: skip
        info.update(out_m)
        info.update(zip(_reference_keys(out_r), out_r.values(), strict=True))
        q, q_r = sample_m[0].tolist(), sample_r[0].tolist()
        f_m, f_r = sample_m[2].tolist(), sample_r[2].tolist()
        for i, (force_keys, motion_keys, reference_keys) in enumerate(PIVOT_KEYS):
            for c, (key_m, key_r) in enumerate(force_keys):
                info[key_m] = f_m[i][c]
                info[key_r] = f_r[i][c]
            info.update(zip(motion_keys, q[i], strict=True))
            info.update(zip(reference_keys, q_r[i], strict=True))
        info["error_n"] = max(
            math.hypot(a[0] - b[0], a[1] - b[1]) for a, b in zip(f_m, f_r, strict=True)
        )
        info["roll_error_rad"] = info["roll_rad"] - info["reference_roll_rad"]
        info["reference_outside_range"] = self._range_reason(sample_r[0])
        info.update(model_out_of_bounds="", reference_out_of_bounds="", monitor_verdict=False,
                    diverged=False, physical_limit=False, divergence_reason=reason,
                    model_error="")  # fmt: skip
        return info

    def _range_reason(self, q: np.ndarray) -> str:
        """Why a twin's pivot judges by extrapolation ("" if none does): its rotation beyond the
        range its law is calibrated for (``car_verdict.reference_range_reason``)."""
        refs = self.references
        for i, k in enumerate(POSITIONS):
            why = reference_range_reason(refs[k] if isinstance(refs, dict) else refs, q[i, 2])
            if why:
                return f"{k}: {why}"
        return ""

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() without a render_mode; pass render_mode='rgb_array'")
            return None
        from bushenv.rigs.halfcar_scene import draw_halfcar

        if self._canvas is None:
            from bushenv.rigs.drawing import Canvas

            self._canvas = Canvas(600, 400, self.render_mode, self.metadata["render_fps"], ENV_ID)
        draw_halfcar(self._canvas, self.params, self.car, self.twin, self._info_last)
        return self._canvas.frame()

    def close(self) -> None:
        if self._canvas is not None:
            self._canvas.close()
            self._canvas = None


_REFERENCE_KEYS: dict[tuple, tuple] = {}


def _reference_keys(out: dict[str, Any]) -> tuple:
    """The twin's info keys for ``out``'s (``reference_`` + key), built once."""
    keys = tuple(out)
    if keys not in _REFERENCE_KEYS:
        _REFERENCE_KEYS[keys] = tuple("reference_" + k for k in keys)
    return _REFERENCE_KEYS[keys]


def _model_batches(models: Any):
    """(model, batch size) of a car's pivots: one model with four histories, or four."""
    if isinstance(models, dict):
        return [(m, 1) for m in models.values()]
    return [(models, len(POSITIONS))]
