"""Reinforcement-learning searchers: stable-baselines3 PPO and SAC acting in BushRig-v0.

The agents act sample by sample in BushRig-v0, ``N_ENVS`` (32) rigs at once through the rig's
vector env (``gym.make_vec(..., vectorization_mode="vector_entry_point")``: the models' batched
kernels, ~40 us per rig-step instead of ~600 us for a wrapped single env), adapted to SB3's
``VecEnv`` by ``RigVecEnv`` and steered through ``OscillatorActions``: the episode's first action
sets the frequency and amplitude of a sine, later ones move them ("rate") or set targets they
follow ("follow"), and the rig is sent the velocity action that tracks the sine (within the
machine's stroke and velocity limit; at the lowest amplitude the rig holds). Why not the rig's
raw action (the displacement change per step): a Gaussian policy on it draws white-noise random
walks, and measured on the shipped NN, 64 such walks per noise level (std 0.1-1) and
rate-limited random positions (+-1 to +-12.5 mm) never diverged -- the NN's failures need many
coherent cycles at 45-70 Hz, which an agent on raw increments must first learn to phase-lock
(PPO and SAC did not, in 64 episodes of 10 s or 256 of 0.25-1 s).

Reward (``DivergenceReward``, the env's ``reward_fn`` hook):

- every step, a dense deviation term: ``min(|F_model - F_ref| / scale_so_far, 5) / steps``,
  scale_so_far the reference's running peak |F| (floored at ``FORCE_FLOOR_N``), the same
  normalisation as ``divergence.py``;
- every step, energy shaping: the change of the potential "work the model gave back beyond the
  reference's, at the last return to the start deflection" (see the class);
- at the end of every episode, the episode's whole displacement profile is evaluated ONCE by
  the ``BatchEvaluator`` (the prescribed-motion path and ``divergence.judge``, the single
  definition of divergence) and the agent gets ``-min(clip(robustness, -10, 10), 0.25)``: the
  STL robustness, graded only below 0.25 -- every profile ending in a hold has robustness
  <= 0.25 (the hold term's margin), so uncapped, PPO learned to hold still. Robustness alone is
  flat until a profile fails, so without the shaping the agents settled on slow large strokes,
  where the NN is merely inaccurate.

The same reward and actions are used for every model (target, hybrid, control).

An episode is one model evaluation: the budget is the number of episodes, and the evaluator's
verdicts on those profiles are what the result records (so a "failure" found by an agent
means exactly what it means for random search). The rig itself ends an episode early only
for non-finite or > 25 kN model forces; the profile up to there is judged the same way.

Seeded: SB3's ``seed``, ``torch.set_num_threads(1)`` and a deterministic CPU run give the same
episodes for the same seed. The vector env auto-resets on
the step after an episode ends ("next-step" mode); SB3 sees that step as one extra no-op
transition from the rest state (observation zeros, reward 0), which is harmless: the rig truly
is at rest then.

For road searches (``env="quartercar"``) the agents drive QuarterCar-v0's car through
``QuarterCarBatch``, its array integrator (the pymunk env itself costs milliseconds per step;
there is no vector entry point), with QuarterCar-v0's 12 observations and a gentler action
(``ROAD_ACTION_SCALE``, ``ROAD_DEAD_ZONE``); the episodes' roads are judged like any other
road profile.
"""

from __future__ import annotations

import numpy as np

from bushenv.divergence import CLOSURE_FRACTION, FORCE_FLOOR_N, SETTLE_FRACTION
from bushenv.search.searchers import Searcher, SearchError

# Road agents: QuarterCar-v0's full action (50 mm per 4.9 ms step, 10 m/s) on a random policy
# throws the twin car against its bump stops within 0.1-0.3 s, after which nothing can be
# judged; the agent's road step is a fifth of it (2 m/s road rate), and |a| < 0.1 holds the
# road (a hold is where the free response is judged).
ROAD_ACTION_SCALE = 0.2
ROAD_DEAD_ZONE = 0.1
N_ENVS = 32  # one policy call serves 32 rigs: SB3's per-call cost dominates below that
EPISODE_S = 2.0  # 100-160 cycles of the NN's failing band; short episodes = more policy updates
DENSE_CAP = 5.0
ROBUSTNESS_CLIP = 10.0
# Rig agents steer an oscillator (``OscillatorActions``): its log-frequency and log-amplitude.
# Band: the machine's 0.1-80 Hz, from 0.5 Hz (a 2 s episode holds a whole cycle); amplitude
# 0.1 mm (resolution of the papers' data) to the stroke; at its lowest the amplitude is 0: the
# rig holds at rest. The episode's first action sets both directly; later actions either move
# them at most OSC_LOG_RATE per step ("rate") or set a target they follow with a first-order lag
# of OSC_FOLLOW per step ("follow"): see ``ACTIONS_BY_ALGO``.
OSC_F_HZ = (0.5, 80.0)
OSC_A_M = (1e-4, 0.0125)
OSC_LOG_RATE = 0.05  # ln-units per step at |a| = 1: x e in 20 steps (0.1 s)
OSC_FOLLOW = 0.05  # lag: 20 steps (0.1 s) time constant
VELOCITY_MARGIN = 0.98  # amplitude capped so the sine stays 2 % inside the velocity limit
# Measured (docs/search.md): PPO learns to fail with "follow" (a Gaussian policy's mean is the
# frequency; per-step noise is averaged out) and not with "rate"; SAC finds failures with "rate"
# (its broad first actions explore the band) and none with "follow" (its near-uniform per-step
# actions average to mid-band).
ACTIONS_BY_ALGO = {"ppo": "follow", "sac": "rate"}
# Energy shaping (``DivergenceReward``): weight of the potential "work deficit at the last return
# to the start deflection", the energy criterion's quantity, telescoped into per-step rewards.
ENERGY_SHAPING = 5.0


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
        self.on_episodes = on_episodes
        self.reset()

    def reset(self) -> None:
        self.xs: list[list[float]] = [[] for _ in range(self.n)]
        self.peak = np.full(self.n, FORCE_FLOOR_N)
        # judged already; the env's next-step autoreset calls us once more before resetting
        self.finished = np.zeros(self.n, dtype=bool)
        # x, F_model, F_ref at the last step; W_model, W_ref, normaliser, span, phi
        self.acc = np.zeros((8, self.n))

    @property
    def x_now(self) -> np.ndarray:
        return self.acc[0]

    def reset_columns(self, mask) -> None:
        for i in np.flatnonzero(mask):
            self.xs[i] = []
            self.peak[i] = FORCE_FLOOR_N
            self.finished[i] = False
        self.acc[:, np.asarray(mask, dtype=bool)] = 0.0

    def _energy_shaping(self, x, fm, fr) -> np.ndarray:
        x_prev, fm_prev, fr_prev, w_m, w_r, norm, span, phi = self.acc
        fm = np.where(np.isfinite(fm), fm, 0.0)
        dx = x - x_prev
        w_m += 0.5 * (fm + fm_prev) * dx
        w_r += 0.5 * (fr + fr_prev) * dx
        norm += np.abs(0.5 * (fr + fr_prev) * dx) + FORCE_FLOOR_N * np.abs(dx)
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


def _oscillator_env(venv, reward, params, mode):
    """Wrap an SB3 rig ``VecEnv`` so the agent steers a sine oscillator (``OscillatorActions``)."""
    from gymnasium import spaces
    from stable_baselines3.common.vec_env import VecEnvWrapper

    if mode not in ("rate", "follow"):
        raise SearchError(f"oscillator actions must be 'rate' or 'follow', got {mode!r}")
    lo_f, hi_f = np.log(OSC_F_HZ[0]), np.log(OSC_F_HZ[1])
    lo_a, hi_a = np.log(OSC_A_M[0]), np.log(OSC_A_M[1])
    max_x, max_step, dt = params.max_x, params.max_step, params.dt
    a_cap_factor = VELOCITY_MARGIN * params.max_v / (2.0 * np.pi)

    class OscillatorActions(VecEnvWrapper):
        """Action (2,) in [-1, 1] for ln f and ln A over their ranges. The episode's first action
        sets them; later ones move them (``mode``). The rig is sent the velocity action that
        moves it toward ``A sin(phase)``; A is capped so the sine is drivable, and is 0 at its
        lowest (the rig holds). Observation: the rig's 12 values + sin, cos of the phase, ln f and
        ln A scaled to [-1, 1], and 1 on an episode's first step (else 0)."""

        def __init__(self) -> None:
            n_obs = venv.observation_space.shape[0] + 5
            obs = spaces.Box(-np.inf, np.inf, shape=(n_obs,), dtype=np.float32)
            act = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
            super().__init__(venv, observation_space=obs, action_space=act)
            n = venv.num_envs
            self.phase = np.zeros(n)
            self.log_f = np.full(n, lo_f)
            self.log_a = np.full(n, lo_a)
            self.first = np.ones(n, dtype=bool)

        def _extra(self) -> np.ndarray:
            return np.stack(
                [
                    np.sin(self.phase),
                    np.cos(self.phase),
                    2.0 * (self.log_f - lo_f) / (hi_f - lo_f) - 1.0,
                    2.0 * (self.log_a - lo_a) / (hi_a - lo_a) - 1.0,
                    self.first.astype(np.float64),
                ],
                axis=1,
            )

        def reset(self):
            self.phase[:] = 0.0
            self.first[:] = True
            return np.hstack([self.venv.reset(), self._extra()]).astype(np.float32)

        def step_async(self, actions) -> None:
            a = np.asarray(actions, dtype=np.float64).reshape(self.num_envs, 2)
            a = np.clip(np.nan_to_num(a, nan=0.0), -1.0, 1.0)
            target_f = lo_f + 0.5 * (a[:, 0] + 1.0) * (hi_f - lo_f)
            target_a = lo_a + 0.5 * (a[:, 1] + 1.0) * (hi_a - lo_a)
            if mode == "follow":
                log_f = self.log_f + OSC_FOLLOW * (target_f - self.log_f)
                log_a = self.log_a + OSC_FOLLOW * (target_a - self.log_a)
            else:
                log_f = np.clip(self.log_f + OSC_LOG_RATE * a[:, 0], lo_f, hi_f)
                log_a = np.clip(self.log_a + OSC_LOG_RATE * a[:, 1], lo_a, hi_a)
            self.log_f = np.where(self.first, target_f, log_f)
            self.log_a = np.where(self.first, target_a, log_a)
            self.first[:] = False
            f = np.exp(self.log_f)
            amp = np.minimum(np.exp(self.log_a), a_cap_factor / f)
            amp[self.log_a <= lo_a] = 0.0
            self.phase = np.mod(self.phase + 2.0 * np.pi * f * dt, 2.0 * np.pi)
            target = np.clip(amp * np.sin(self.phase), -max_x, max_x)
            u = np.clip((target - reward.x_now) / max_step, -1.0, 1.0)
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

    return OscillatorActions()


def _rig_vec_env(model, reference, axis, n_envs, episode_steps, reward):
    import gymnasium as gym

    import bushenv  # noqa: F401  (registers BushRig-v0)

    return gym.make_vec(
        "BushRig-v0",
        num_envs=n_envs,
        vectorization_mode="vector_entry_point",
        model=model,
        reference=reference,
        axis=axis,
        episode_steps=episode_steps,
        reward_fn=reward,
    )


def _sb3_vec_env(venv):
    """SB3 ``VecEnv`` over a next-step-autoreset gymnasium vector env."""
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv

    class RigVecEnv(VecEnv):
        def __init__(self, inner) -> None:
            self.inner = inner
            super().__init__(
                inner.num_envs, inner.single_observation_space, inner.single_action_space
            )
            self._actions = None
            self._seed = None

        def reset(self):
            obs, _ = self.inner.reset(seed=self._seed)
            self._seed = None
            return obs

        def step_async(self, actions) -> None:
            self._actions = np.asarray(actions, dtype=np.float32).reshape(self.num_envs, -1)

        def step_wait(self):
            obs, rew, term, trunc, info = self.inner.step(self._actions)
            done = term | trunc
            infos = [{} for _ in range(self.num_envs)]
            for i in np.flatnonzero(done):
                infos[i]["terminal_observation"] = obs[i].copy()
                infos[i]["TimeLimit.truncated"] = bool(trunc[i] and not term[i])
                obs[i] = 0.0  # the rest state the rig returns to (next-step autoreset)
            return obs, rew.astype(np.float32), done, infos

        def close(self) -> None:
            self.inner.close()

        def seed(self, seed=None):
            self._seed = seed
            return [seed] * self.num_envs

        def get_attr(self, attr_name, indices=None):
            return [getattr(self.inner, attr_name, None)] * self.num_envs

        def set_attr(self, attr_name, value, indices=None) -> None:
            setattr(self.inner, attr_name, value)

        def env_method(self, method_name, *args, indices=None, **kwargs):
            return [None] * self.num_envs

        def env_is_wrapped(self, wrapper_class, indices=None):
            return [False] * self.num_envs

    return RigVecEnv(venv)


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


class RLSearch(Searcher):
    """PPO or SAC in BushRig-v0 (or the QuarterCar-v0 car); the budget counts episodes."""

    def __init__(
        self,
        algo: str,
        n_envs: int = N_ENVS,
        episode_s: float = EPISODE_S,
        actions: str | None = None,
    ) -> None:
        if algo not in ("ppo", "sac"):
            raise SearchError(f"RL searcher must be 'ppo' or 'sac', got {algo!r}")
        self.actions = actions or ACTIONS_BY_ALGO[algo]
        if self.actions not in ("rate", "follow"):
            raise SearchError(f"RL actions must be 'rate' or 'follow', got {self.actions!r}")
        self.name = algo
        self.n_envs = int(n_envs)
        self.episode_s = float(episode_s)

    def _search(self, evaluator, budget, rng, recorder, seed, progress) -> None:
        import torch
        from stable_baselines3 import PPO, SAC
        from stable_baselines3.common.callbacks import BaseCallback

        torch.set_num_threads(1)
        episode_steps = int(round(self.episode_s / evaluator.dt))
        n_envs = max(1, min(self.n_envs, budget))
        state = {"episodes": 0}

        def on_episodes(batch) -> None:
            k = len(batch.lengths)
            room = budget - state["episodes"]
            if room <= 0:
                return
            state["episodes"] += min(k, room)
            recorder.record(batch, [f"agent-{self.name}"] * k, [None] * k, limit=room)
            progress(
                f"{self.name} {state['episodes']}/{budget} episodes, "
                f"best robustness {recorder.best:.3g}"
            )

        if evaluator.env == "rig":
            reward = DivergenceReward(n_envs, episode_steps, evaluator, on_episodes)
            venv = _rig_vec_env(
                evaluator.model.copy(),
                evaluator.reference.copy(),
                evaluator.axis,
                n_envs,
                episode_steps,
                reward,
            )
            env = _oscillator_env(_sb3_vec_env(venv), reward, venv.params, self.actions)
        else:
            env = _road_vec_env(evaluator, n_envs, episode_steps, on_episodes)

        class StopAtBudget(BaseCallback):
            def _on_step(self) -> bool:
                return state["episodes"] < budget

        policy_kwargs = {"net_arch": [64, 64]}
        if self.name == "ppo":
            agent = PPO(
                "MlpPolicy",
                env,
                n_steps=64,
                batch_size=min(1024, 64 * n_envs),
                n_epochs=4,
                learning_rate=3e-4,
                gamma=0.99,
                seed=int(seed),
                device="cpu",
                policy_kwargs=policy_kwargs,
                verbose=0,
            )
        else:
            agent = SAC(
                "MlpPolicy",
                env,
                buffer_size=200_000,
                learning_starts=32 * n_envs,
                batch_size=256,
                train_freq=8,
                gradient_steps=4,
                gamma=0.99,
                seed=int(seed),
                device="cpu",
                policy_kwargs=policy_kwargs,
                verbose=0,
            )
        total = (budget // n_envs + 2) * episode_steps * n_envs
        try:
            agent.learn(total_timesteps=total, callback=StopAtBudget())
        finally:
            env.close()
