"""Reinforcement-learning searchers: stable-baselines3 PPO and SAC acting in the target's env.

The environment the agents act in belongs to the target (``targets.py``): the rig's is built in
``rl_rig.py``, the quarter car's in ``rl_road.py``.

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

from bushenv.search.base import Searcher, SearchError

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

        env = evaluator.target.rl_env(evaluator, n_envs, episode_steps, on_episodes, self.actions)

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


def PPOSearch(**kwargs) -> RLSearch:  # noqa: N802 (a searcher factory, named as the classes)
    return RLSearch("ppo", **kwargs)


def SACSearch(**kwargs) -> RLSearch:  # noqa: N802
    return RLSearch("sac", **kwargs)
