"""bushenv.rigs.sb3: stable-baselines3's VecEnv over the array vector envs of both ids."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium.vector import AutoresetMode
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.logger import Logger
from stable_baselines3.common.vec_env import VecCheckNan, VecEnv, VecNormalize

from bushenv.rigs.common import RigError
from bushenv.rigs.sb3 import SB3VecEnv, make_sb3_vec_env

ENV_IDS = ("BushRig-v0", "QuarterCar-v0")


@pytest.fixture(autouse=True)
def one_thread():
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.mark.filterwarnings("ignore:Evaluation environment is not wrapped")
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_ppo_and_sac_learn_on_the_vector_env_for_a_few_hundred_steps(env_id):
    venv = make_sb3_vec_env(env_id, 4, model="linear", max_episode_steps=50)
    assert isinstance(venv, VecEnv)
    ppo = PPO("MlpPolicy", venv, n_steps=64, batch_size=64, n_epochs=2, seed=0, device="cpu")
    quiet = Logger(folder=None, output_formats=[])  # the default one leaves a folder in /tmp
    ppo.set_logger(quiet)
    ppo.learn(512)
    assert ppo.num_timesteps >= 512
    sac = SAC("MlpPolicy", venv, learning_starts=64, batch_size=32, seed=0, device="cpu")
    sac.set_logger(quiet)
    sac.learn(256)
    mean, _ = evaluate_policy(ppo, venv, n_eval_episodes=4)
    assert np.isfinite(mean)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_vec_env_keeps_sb3s_conventions_over_a_rollout(env_id):
    n, length = 3, 20
    venv = VecCheckNan(make_sb3_vec_env(env_id, n, max_episode_steps=length), raise_exception=True)
    space = venv.observation_space
    assert space == gym.make(env_id).observation_space and venv.num_envs == n
    obs = venv.reset()
    assert obs.shape == (n, *space.shape) and obs.dtype == np.float32 and (obs == 0).all()
    rng = np.random.default_rng(0)
    ends = 0
    for t in range(3 * length):
        obs, reward, done, infos = venv.step(rng.uniform(-0.3, 0.3, (n, 1)).astype(np.float32))
        assert obs.shape == (n, *space.shape) and obs.dtype == np.float32
        assert reward.shape == (n,) and reward.dtype == np.float32
        assert done.shape == (n,) and done.dtype == bool
        assert len(infos) == n and all(isinstance(i, dict) for i in infos)
        for i in range(n):
            assert ("terminal_observation" in infos[i]) == bool(done[i])
            if done[i]:
                ends += 1
                assert space.contains(infos[i]["terminal_observation"])
                assert infos[i]["TimeLimit.truncated"]  # the time limit, not a verdict
                assert (obs[i] == 0).all()  # already the next episode: the rig at rest
                assert (t + 1) % length == 0
    assert ends == 3 * n


def test_the_terminal_observation_is_the_single_envs_last_one():
    rng = np.random.default_rng(1)
    acts = rng.uniform(-1, 1, (12, 2, 1)).astype(np.float32)
    venv = make_sb3_vec_env("BushRig-v0", 2, model="linear", max_episode_steps=12)
    venv.reset()
    for a in acts:
        _, _, done, infos = venv.step(a)
    env = gym.make("BushRig-v0", model="linear", max_episode_steps=12)
    env.reset(seed=0)
    for a in acts[:, 1]:
        last, *_ = env.step(a)
    assert done.all() and np.array_equal(infos[1]["terminal_observation"], last)


def test_a_verdict_is_done_but_not_a_time_limit():
    from rig_test_models import NanAfter

    venv = make_sb3_vec_env("BushRig-v0", 2, model=NanAfter(after=3), info_keys=("diverged",))
    venv.reset()
    for _ in range(4):
        _, _, done, infos = venv.step(np.full((2, 1), 0.5, np.float32))
    assert done.all()
    assert not infos[0]["TimeLimit.truncated"] and infos[0]["diverged"] is True
    assert venv.reset_infos[0] == {}


def test_seeds_reach_the_vector_env_at_the_next_reset_and_runs_repeat():
    runs = []
    for _ in range(2):
        venv = make_sb3_vec_env("QuarterCar-v0", 2)
        assert venv.seed(7) == [7, 8]
        venv.reset()
        assert venv.venv.unwrapped.np_random_seed == 7
        venv.step(np.full((2, 1), 0.4, np.float32))
        runs.append(venv.step(np.full((2, 1), -0.1, np.float32))[0])
    assert np.array_equal(runs[0], runs[1])


def test_options_replay_an_excitation_and_different_options_per_env_are_refused():
    venv = make_sb3_vec_env("BushRig-v0", 2)
    x = np.linspace(0.0, 0.004, 10)
    venv.set_options({"excitation": x})
    venv.reset()
    for _ in range(10):
        _, _, done, infos = venv.step(np.zeros((2, 1), np.float32))
    assert done.all() and infos[0]["terminal_observation"][0] == pytest.approx(x[-1] / 0.0125)
    venv.set_options([{"excitation": x}, {"excitation": 2 * x}])
    with pytest.raises(RigError, match="one dict for all"):
        venv.reset()


def test_attributes_methods_and_wrappers_reach_the_one_vector_env():
    venv = make_sb3_vec_env("BushRig-v0", 3)
    assert venv.get_attr("max_episode_steps") == [2048] * 3
    assert venv.get_attr("num_envs", indices=[0, 2]) == [3, 3]
    assert not venv.has_attr("no_such_attribute")
    venv.set_attr("max_episode_steps", 5)
    assert venv.venv.unwrapped.max_episode_steps == 5
    assert venv.env_method("reset", seed=1, indices=1)[0][0].shape == (3, 12)
    assert venv.env_is_wrapped(gym.Wrapper) == [False] * 3
    normalised = VecNormalize(venv)  # SB3's own wrappers stack on it
    assert normalised.reset().shape == (3, 12)


def test_over_a_next_step_vector_env_a_finished_column_shows_its_rest_state():
    """The compatibility mode: the vector env resets a column one step late, so SB3 sees the
    rest observation at once and then one transition whose action is ignored, reward 0."""
    inner = gym.make_vec(
        "BushRig-v0", num_envs=2, vectorization_mode="vector_entry_point", max_episode_steps=3
    )
    assert inner.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    venv = SB3VecEnv(inner)
    venv.reset()
    a = np.ones((2, 1), np.float32)
    for _ in range(3):
        obs, reward, done, infos = venv.step(a)
    assert done.all() and (obs == 0).all() and (infos[0]["terminal_observation"] != 0).any()
    obs, reward, done, _ = venv.step(a)
    assert (obs == 0).all() and (reward == 0).all() and not done.any()


def test_a_vector_env_without_next_or_same_step_autoreset_is_refused():
    inner = gym.make_vec("BushRig-v0", num_envs=2, vectorization_mode="vector_entry_point")
    inner.metadata = {**inner.metadata, "autoreset_mode": AutoresetMode.DISABLED}
    with pytest.raises(RigError, match="NextStep or SameStep"):
        SB3VecEnv(inner)
