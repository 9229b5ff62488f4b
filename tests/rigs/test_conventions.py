"""Gymnasium conventions of both envs: pickling and deep copies that continue bit for bit, the
episode length in the spec (TimeLimit, TimeAwareObservation) without double truncation,
``render_fps`` matching the simulated time, and the docstring examples."""

from __future__ import annotations

import copy
import doctest
import importlib
import math
import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.wrappers import TimeAwareObservation
from rig_test_models import model_or_skip

ENV_IDS = ("BushRig-v0", "QuarterCar-v0")
DT = 1.0 / 204.8


def same_step(a, b) -> bool:
    """Two step results equal to the last bit (NaN equal to NaN)."""
    if not (np.array_equal(a[0], b[0]) and a[1:4] == b[1:4]) or a[4].keys() != b[4].keys():
        return False
    for k, v in a[4].items():
        w = b[4][k]
        if not (v == w or (isinstance(v, float) and math.isnan(v) and math.isnan(w))):
            return False
    return True


def actions(n=300, seed=0):
    return np.random.default_rng(seed).uniform(-0.6, 0.6, (n, 1)).astype(np.float32)


@pytest.mark.parametrize("model", ["linear", "nn", "rubber"])
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_a_pickled_env_round_trips_and_continues_identically(env_id, model):
    model_or_skip(model, "radial")
    model_or_skip(model, "axial")
    acts = actions()
    reference = gym.make(env_id, model=model)
    reference.reset(seed=1)
    expected = [reference.step(a) for a in acts]
    env = gym.make(env_id, model=model)
    env.reset(seed=1)
    for a in acts[:150]:
        env.step(a)
    restored = pickle.loads(pickle.dumps(env))
    assert type(restored.unwrapped) is type(env.unwrapped)
    for i, a in enumerate(acts[150:]):
        assert same_step(restored.step(a), expected[150 + i]), i
        assert same_step(env.step(a), expected[150 + i]), i


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_a_deep_copy_is_independent_stepping_it_leaves_the_original_unchanged(env_id):
    acts = actions()
    reference = gym.make(env_id, model="nn" if env_id == "BushRig-v0" else "linear")
    kwargs = reference.spec.kwargs
    reference.reset(seed=2)
    expected = [reference.step(a) for a in acts]
    env = gym.make(env_id, model=kwargs["model"])
    env.reset(seed=2)
    for a in acts[:100]:
        env.step(a)
    twin = copy.deepcopy(env)
    if env_id == "QuarterCar-v0":  # nothing pymunk is shared any more
        assert twin.unwrapped.car.space is not env.unwrapped.car.space
        assert twin.unwrapped.car.chassis is not env.unwrapped.car.chassis
    for a in -acts[:120]:  # the copy drives elsewhere ...
        twin.step(a)
    for i, a in enumerate(acts[100:]):  # ... the original goes on as if it had not been copied
        assert same_step(env.step(a), expected[100 + i]), i
    copy_again = copy.deepcopy(env)
    assert same_step(copy_again.step(acts[0]), env.step(acts[0]))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_a_pickled_env_mid_replay_with_rendering_goes_on(env_id):
    road = np.linspace(0.0, 0.01, 40)
    env = gym.make(env_id, render_mode="rgb_array")
    env.reset(seed=0, options={"excitation": road})
    for _ in range(20):
        env.step(np.zeros(1, np.float32))
    frame = env.render()
    restored = pickle.loads(pickle.dumps(env))
    assert np.array_equal(restored.render(), frame)
    for _ in range(19):
        assert not restored.step(np.zeros(1, np.float32))[3]
    assert restored.step(np.zeros(1, np.float32))[3]  # the replay's end, at its length


# ----- episode length --------------------------------------------------------------------------
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_the_spec_states_the_episode_length_and_time_aware_observation_accepts_it(env_id):
    env = gym.make(env_id)
    assert env.spec.max_episode_steps == gym.spec(env_id).max_episode_steps == 2048
    timed = TimeAwareObservation(env)
    obs, _ = timed.reset(seed=0)
    assert obs.shape == (13,) and obs[-1] == 0
    obs, *_ = timed.step(np.zeros(1, np.float32))
    assert obs[-1] == 1


def truncation_steps(env, steps, options=None):
    """The 1-based steps at which ``truncated`` came, over ``steps`` steps (no reset)."""
    env.reset(seed=0, options=options)
    return [t + 1 for t in range(steps) if env.step(np.zeros(1, np.float32))[3]]


def test_bushrig_truncates_once_at_the_spec_length_not_before():
    assert truncation_steps(gym.make("BushRig-v0"), 2048) == [2048]


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_a_longer_or_shorter_limit_given_to_make_is_the_only_one(env_id):
    """No second limit of the env's own cuts an episode before or after gym.make's."""
    assert truncation_steps(gym.make(env_id, max_episode_steps=7), 7) == [7]
    if env_id == "BushRig-v0":
        assert truncation_steps(gym.make(env_id, max_episode_steps=2100), 2100) == [2100]
    env = gym.make(env_id, max_episode_steps=-1)  # no limit at all
    assert not any(isinstance(w, gym.wrappers.TimeLimit) for w in _wrappers(env))


def test_a_replay_ends_at_its_length_within_the_time_limit():
    x = np.zeros(100)
    assert truncation_steps(gym.make("BushRig-v0"), 100, {"excitation": x}) == [100]
    long = np.zeros(2100)  # longer than the spec's limit: gym.make(..., max_episode_steps=-1)
    env = gym.make("BushRig-v0", max_episode_steps=-1)
    assert truncation_steps(env, 2100, {"excitation": long}) == [2100]


def _wrappers(env):
    while isinstance(env, gym.Wrapper):
        yield env
        env = env.env


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_vector_envs_take_the_spec_length_or_their_own(env_id):
    kw = dict(num_envs=2, vectorization_mode="vector_entry_point")
    assert gym.make_vec(env_id, **kw).unwrapped.max_episode_steps == 2048
    venv = gym.make_vec(env_id, max_episode_steps=5, **kw)
    venv.reset(seed=0)
    flags = [venv.step(np.zeros((2, 1), np.float32))[3].all() for _ in range(5)]
    assert flags == [False] * 4 + [True]
    # the former name still works for the vector envs, and wins over the spec's default
    assert gym.make_vec(env_id, episode_steps=9, **kw).unwrapped.max_episode_steps == 9


# ----- rendering -------------------------------------------------------------------------------
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_render_fps_is_one_frame_per_simulated_step(env_id):
    env = gym.make(env_id, render_mode="rgb_array")
    assert env.metadata["render_fps"] == pytest.approx(1.0 / DT) == 204.8
    env.reset(seed=0)
    env.render()
    assert env.unwrapped._canvas.fps == 204.8  # what "human" paces its window by
    slow = gym.make(env_id, dt_s=2 * DT)
    assert slow.metadata["render_fps"] == pytest.approx(102.4)
    assert type(slow.unwrapped).metadata["render_fps"] == 204.8  # the class is untouched
    vec = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    assert vec.metadata["render_fps"] == pytest.approx(204.8)


# ----- docstring examples ------------------------------------------------------------------------
@pytest.mark.parametrize(
    "module",
    ["bushrig", "quartercar", "vector", "quartercar_vector", "sb3"],
)
def test_the_docstring_examples_run(module):
    mod = importlib.import_module(f"bushenv.rigs.{module}")
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_human_mode_shows_the_simulated_time_in_real_time():
    """204.8 frames per second of wall time (pygame's Clock.tick would wait 4 ms, not 4.88)."""
    import time

    from bushenv.rigs.drawing import Canvas

    canvas = Canvas(60, 40, "human", 204.8, "pace")
    canvas.clear()
    canvas.frame()
    t0 = time.perf_counter()
    for _ in range(103):  # 0.5 s of simulated time
        canvas.frame()
    elapsed = time.perf_counter() - t0
    canvas.close()
    assert 0.495 <= elapsed < 1.5  # never faster than real time; slower only under load
