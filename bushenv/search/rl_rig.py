"""The rig's environment for RL agents: BushRig-v0's vector env, the reward and the oscillator.

``rig_agent_env`` builds what ``RLSearch`` acts in on the rig (see ``rl.py`` for why the agent
steers a sine rather than the raw displacement step): ``N`` rigs of BushRig-v0's vector entry
point, adapted to SB3, with ``DivergenceReward`` as the env's reward hook.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import VecEnvWrapper

from bushenv.divergence import CLOSURE_FRACTION, SETTLE_FRACTION
from bushenv.rigs.sb3 import SB3VecEnv
from bushenv.scales import MACHINE
from bushenv.search.base import SearchError
from bushenv.search.rl import (
    DENSE_CAP,
    ENERGY_SHAPING,
    OSC_A_M,
    OSC_F_HZ,
    OSC_FOLLOW,
    OSC_LOG_RATE,
    ROBUSTNESS_CLIP,
    VELOCITY_MARGIN,
)


def rig_agent_env(evaluator, n_envs, episode_steps, on_episodes, actions):
    """SB3 ``VecEnv`` of ``n_envs`` rigs driven by an oscillator; episodes judged by
    ``evaluator`` and handed to ``on_episodes(batch)``."""
    reward = DivergenceReward(n_envs, episode_steps, evaluator, on_episodes)
    # With no reference the rig runs the model beside itself (the dense term is then zero);
    # the episodes are judged by the evaluator, reference-free.
    reference = evaluator.reference if evaluator.reference is not None else evaluator.model
    venv = _rig_vec_env(
        evaluator.model.copy(),
        reference.copy(),
        evaluator.axis,
        n_envs,
        episode_steps,
        reward,
        evaluator.scales,
    )
    return OscillatorActions(SB3VecEnv(venv), reward, venv.params, actions)


class DivergenceReward:
    """``reward_fn`` hook: dense shaping + terminal -robustness from the evaluator.

    Keeps each rig's episode (x, F_model, F_ref so far) and, when episodes end, evaluates
    their profiles in one batch and hands the result to ``on_episodes(batch)``. ``x_now`` is
    each rig's current displacement (what ``OscillatorActions`` steers from).

    Shaping, both terms normalised like ``divergence.py``:

    - deviation: ``min(|F_model - F_ref| / scale_so_far, 5) / steps``;
    - energy: ``ENERGY_SHAPING * (phi_t - phi_t-1)`` with the potential
      ``phi = (W_ref - W_model) / (sum |dW_ref| + 200 N x travel)`` taken at the last return to
      the start deflection (within 2 % of the span so far, as the energy criterion), held in
      between: the work a model gives back beyond the reference's, only where a cycle closes,
      so stored elastic energy in mid-cycle is not rewarded. It telescopes to the potential at
      the episode's last closure: a model whose loss factor falls below the rubber's scores
      higher, one that returns net work (the criterion) highest.
    """

    def __init__(self, n_envs, episode_steps, evaluator, on_episodes) -> None:
        self.n = n_envs
        self.episode_steps = episode_steps
        self.evaluator = evaluator
        self.floor = (evaluator.scales if evaluator is not None else MACHINE).force_floor_n
        self.on_episodes = on_episodes
        self.xs: list[list[float]] = [[] for _ in range(self.n)]
        self.peak = np.full(self.n, self.floor)
        # judged already; the env's next-step autoreset calls us once more before resetting
        self.finished = np.zeros(self.n, dtype=bool)
        # x, F_model, F_ref at the last step; W_model, W_ref, normaliser, span, phi
        self.acc = np.zeros((8, self.n))

    def reset(self) -> None:
        self.reset_columns(np.ones(self.n, dtype=bool))

    @property
    def x_now(self) -> np.ndarray:
        return self.acc[0]

    def reset_columns(self, mask) -> None:
        for i in np.flatnonzero(mask):
            self.xs[i] = []
            self.peak[i] = self.floor
            self.finished[i] = False
        self.acc[:, np.asarray(mask, dtype=bool)] = 0.0

    def _energy_shaping(self, x, fm, fr) -> np.ndarray:
        x_prev, fm_prev, fr_prev, w_m, w_r, norm, span, phi = self.acc
        fm = np.where(np.isfinite(fm), fm, 0.0)
        dx = x - x_prev
        w_m += 0.5 * (fm + fm_prev) * dx
        w_r += 0.5 * (fr + fr_prev) * dx
        norm += np.abs(0.5 * (fr + fr_prev) * dx) + self.floor * np.abs(dx)
        np.maximum(span, np.abs(x), out=span)  # the start deflection is 0 (rig at rest)
        closed = (np.abs(x) <= CLOSURE_FRACTION * span) & (span > 0) & (norm > 0)
        with np.errstate(invalid="ignore", divide="ignore"):
            new = np.where(closed, (w_r - w_m) / norm, phi)
        new = np.where(np.isfinite(new), new, phi)
        gain = new - phi
        phi[:] = new
        x_prev[:] = x
        fm_prev[:] = fm
        fr_prev[:] = fr
        return ENERGY_SHAPING * gain

    def __call__(self, info) -> np.ndarray:
        x = np.asarray(info["displacement_m"], dtype=np.float64)
        fm = np.asarray(info["force_model_n"], dtype=np.float64)
        fr = np.asarray(info["force_reference_n"], dtype=np.float64)
        for i in np.flatnonzero(~self.finished):
            self.xs[i].append(float(x[i]))
        np.maximum(self.peak, np.abs(fr), out=self.peak)
        with np.errstate(invalid="ignore"):
            dense = np.abs(fm - fr) / self.peak
        dense = np.where(np.isfinite(dense), np.minimum(dense, DENSE_CAP), DENSE_CAP)
        reward = dense / self.episode_steps + self._energy_shaping(x, fm, fr)
        reward[self.finished] = 0.0
        ended = (
            np.asarray(info["diverged"], dtype=bool)
            | np.asarray(info["machine_limit"], dtype=bool)
            | (np.asarray(info["step"]) >= self.episode_steps)
        )
        idx = np.flatnonzero(ended & ~self.finished)
        self.finished |= ended
        if idx.size:
            profiles = [np.r_[0.0, self.xs[i]] for i in idx]  # the rig starts at rest at 0
            batch = self.evaluator.evaluate(profiles)
            rob = np.clip(batch.verdict.robustness, -ROBUSTNESS_CLIP, ROBUSTNESS_CLIP)
            # Every profile ending in a hold has robustness <= SETTLE_FRACTION (the hold term's
            # margin at zero drift): uncapped, holding still "scores" better than any
            # non-failing motion, and PPO learned to hold. Only failures are graded.
            reward[idx] += -np.minimum(rob, SETTLE_FRACTION)
            self.on_episodes(batch)
        return reward


class OscillatorActions(VecEnvWrapper):
    """The agent steers a sine: action (2,) in [-1, 1] for ln f and ln A over their ranges.

    The episode's first action sets them; later ones move them (``mode`` "rate") or set targets
    they follow ("follow"). The rig is sent the velocity action that moves it toward
    ``A sin(phase)``; A is capped so the sine is drivable, and is 0 at its lowest (the rig
    holds). Observation: the rig's 12 values + sin, cos of the phase, ln f and ln A scaled to
    [-1, 1], and 1 on an episode's first step (else 0).
    """

    def __init__(self, venv, reward, params, mode: str) -> None:
        if mode not in ("rate", "follow"):
            raise SearchError(f"oscillator actions must be 'rate' or 'follow', got {mode!r}")
        self.mode, self.reward = mode, reward
        self.lo_f, self.hi_f = np.log(OSC_F_HZ[0]), np.log(OSC_F_HZ[1])
        self.lo_a, self.hi_a = np.log(OSC_A_M[0]), np.log(OSC_A_M[1])
        # the rig's one coordinate (BushRig-v0's limits are (1,) arrays)
        self.max_x, self.max_step = float(params.max_x[0]), float(params.max_step[0])
        self.dt = params.dt
        self.a_cap_factor = VELOCITY_MARGIN * float(params.max_v[0]) / (2.0 * np.pi)
        n_obs = venv.observation_space.shape[0] + 5
        obs = spaces.Box(-np.inf, np.inf, shape=(n_obs,), dtype=np.float32)
        act = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        super().__init__(venv, observation_space=obs, action_space=act)
        n = venv.num_envs
        self.phase = np.zeros(n)
        self.log_f = np.full(n, self.lo_f)
        self.log_a = np.full(n, self.lo_a)
        self.first = np.ones(n, dtype=bool)

    def _extra(self) -> np.ndarray:
        return np.stack(
            [
                np.sin(self.phase),
                np.cos(self.phase),
                2.0 * (self.log_f - self.lo_f) / (self.hi_f - self.lo_f) - 1.0,
                2.0 * (self.log_a - self.lo_a) / (self.hi_a - self.lo_a) - 1.0,
                self.first.astype(np.float64),
            ],
            axis=1,
        )

    def reset(self):
        self.phase[:] = 0.0
        self.first[:] = True
        return np.hstack([self.venv.reset(), self._extra()]).astype(np.float32)

    def _targets(self, a: np.ndarray) -> None:
        """ln f and ln A after action ``a`` (n, 2)."""
        lo_f, hi_f, lo_a, hi_a = self.lo_f, self.hi_f, self.lo_a, self.hi_a
        target_f = lo_f + 0.5 * (a[:, 0] + 1.0) * (hi_f - lo_f)
        target_a = lo_a + 0.5 * (a[:, 1] + 1.0) * (hi_a - lo_a)
        if self.mode == "follow":
            log_f = self.log_f + OSC_FOLLOW * (target_f - self.log_f)
            log_a = self.log_a + OSC_FOLLOW * (target_a - self.log_a)
        else:
            log_f = np.clip(self.log_f + OSC_LOG_RATE * a[:, 0], lo_f, hi_f)
            log_a = np.clip(self.log_a + OSC_LOG_RATE * a[:, 1], lo_a, hi_a)
        self.log_f = np.where(self.first, target_f, log_f)
        self.log_a = np.where(self.first, target_a, log_a)
        self.first[:] = False

    def step_async(self, actions) -> None:
        a = np.asarray(actions, dtype=np.float64).reshape(self.num_envs, 2)
        self._targets(np.clip(np.nan_to_num(a, nan=0.0), -1.0, 1.0))
        f = np.exp(self.log_f)
        amp = np.minimum(np.exp(self.log_a), self.a_cap_factor / f)
        amp[self.log_a <= self.lo_a] = 0.0
        self.phase = np.mod(self.phase + 2.0 * np.pi * f * self.dt, 2.0 * np.pi)
        target = np.clip(amp * np.sin(self.phase), -self.max_x, self.max_x)
        u = np.clip((target - self.reward.x_now) / self.max_step, -1.0, 1.0)
        self.venv.step_async(u[:, None])

    def step_wait(self):
        obs, rew, done, infos = self.venv.step_wait()
        extra = self._extra()
        for i in np.flatnonzero(done):
            term = infos[i]["terminal_observation"]
            infos[i]["terminal_observation"] = np.r_[term, extra[i]].astype(np.float32)
        self.phase[done] = 0.0
        self.first[done] = True
        obs = np.hstack([obs, self._extra()]).astype(np.float32)
        return obs, rew, done, infos


def _oscillator_env(venv, reward, params, mode):
    """An SB3 rig ``VecEnv`` the agent steers through a sine (``OscillatorActions``)."""
    return OscillatorActions(venv, reward, params, mode)


def _rig_vec_env(model, reference, axis, n_envs, episode_steps, reward, scales=MACHINE):
    return gym.make_vec(
        "BushRig-v0",
        num_envs=n_envs,
        vectorization_mode="vector_entry_point",
        model=model,
        reference=reference,
        axis=axis,
        dt_s=model.dt,
        max_episode_steps=episode_steps,
        reward_fn=reward,
        # the agent's episodes are judged by the evaluator, whose reference the one judge
        # vetted already (or the user trusted); with none, the model is its own twin here
        trust_reference=True,
        **_limits_kwargs(scales),
    )


def _limits_kwargs(scales) -> dict:
    """BushRig-v0 keyword arguments for the bushing's limits (none for the machine's own, so
    the env's spec defaults stand)."""
    if scales == MACHINE:
        return {}
    return {
        "max_displacement_m": scales.stroke_m,
        "max_velocity_m_per_s": scales.velocity_m_per_s,
        "force_limit_n": scales.force_limit_n,
    }
