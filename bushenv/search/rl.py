"""Reinforcement-learning searchers: stable-baselines3 PPO and SAC acting in the target's env.

The environment the agents act in belongs to the target (``targets.py``): on the rig
(``rl_rig.py``) ``N_ENVS`` rigs of BushRig-v0's vector env, steered through an oscillator --
the episode's first action sets a sine's frequency and amplitude, later ones move them -- because
the NN's failures need many coherent cycles, which a policy on raw displacement steps does not
find (docs/search.md measured why); on the quarter car (``rl_road.py``) the road under the
wheel, with a gentler action than the env's.

Reward (the rig's ``DivergenceReward``): a dense deviation term normalised as ``divergence.py``
does, an energy-shaping term (the work the model gave back beyond the reference's at returns to
the start), and at each episode's end ``-min(clip(robustness), 0.25)`` from the evaluator's
verdict on the whole profile: graded only below the hold term's margin, or holding still would
score best.

An episode is one model evaluation: the budget counts episodes, and what the result records is
the evaluator's verdict on those profiles, so a failure found by an agent means what it means
for random search. Seeded (SB3's seed, one torch thread): the same episodes for the same seed.
"""

from __future__ import annotations

from bushenv.search.base import SearchContext, Searcher, SearchError

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

    def search(self, ctx: SearchContext) -> None:
        evaluator, budget, recorder, seed = ctx.evaluator, ctx.budget, ctx.recorder, ctx.seed
        import torch
        from stable_baselines3 import PPO, SAC
        from stable_baselines3.common.callbacks import BaseCallback
        from stable_baselines3.common.logger import Logger

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
            ctx.progress(
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
        # SB3's default logger makes an empty SB3-<date> folder in the temp folder on every
        # learn(); a logger with no outputs writes nothing
        agent.set_logger(Logger(folder=None, output_formats=[]))
        total = (budget // n_envs + 2) * episode_steps * n_envs
        try:
            agent.learn(total_timesteps=total, callback=StopAtBudget())
        finally:
            env.close()


def PPOSearch(**kwargs) -> RLSearch:  # noqa: N802 (a searcher factory, named as the classes)
    return RLSearch("ppo", **kwargs)


def SACSearch(**kwargs) -> RLSearch:  # noqa: N802
    return RLSearch("sac", **kwargs)
