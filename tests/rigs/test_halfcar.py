"""HalfCar-v0: Gymnasium conventions (checkers, replay, pickling, copies, rendering, the vector
env) and its physics against independent figures (two quarter cars, the roll gradient, the
energy balance, the coupling's margins)."""

from __future__ import annotations

import copy
import doctest
import importlib
import math
import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import bushenv  # noqa: F401  (registers the ids)
from bushenv.rigs.common import RigError
from bushenv.rigs.halfcar_params import POSITIONS

DT = 1.0 / 204.8


def make(**kwargs):
    return gym.make("HalfCar-v0", **kwargs)


def bump(height_m=0.05, length_m=0.4, speed_m_per_s=30 / 3.6, pre_s=0.1, total_s=1.5):
    """A (1 - cos) bump: road heights (T,) at the env's rate."""
    t = np.arange(int(total_s / DT)) * DT - pre_s
    x = speed_m_per_s * t
    inside = (x >= 0) & (x <= length_m)
    return np.where(inside, height_m / 2 * (1 - np.cos(2 * np.pi * x / length_m)), 0.0)


def manoeuvre(n=300):
    """A fixed manoeuvre: a bump on the left, a pothole on the right, a lateral pulse."""
    left = bump(0.04, total_s=n * DT)
    right = -bump(0.03, 0.7, pre_s=0.4, total_s=n * DT)
    k = np.arange(n)
    ay = np.clip(np.minimum(0.2 * k, 0.2 * (n // 2 - k) + 5.0), 0.0, 5.0)  # a pulse, 0.2 per step
    return {"road_left": left, "road_right": right, "lateral_accel": ay}


def rollout(env, options=None, actions=None, n=300):
    env.reset(seed=0, options=options)
    out = []
    for k in range(n):
        a = np.zeros(3, np.float32) if actions is None else actions[k]
        out.append(env.step(a))
        if out[-1][2] or out[-1][3]:
            break
    return out


def same(a, b) -> bool:
    """Two step results equal to the last bit (NaN equal to NaN)."""
    if not (np.array_equal(a[0], b[0]) and a[1:4] == b[1:4]) or a[4].keys() != b[4].keys():
        return False
    for k, v in a[4].items():
        w = b[4][k]
        if not (v == w or (isinstance(v, float) and math.isnan(v) and math.isnan(w))):
            return False
    return True


def random_actions(n=300, seed=0, scale=0.3):
    return np.random.default_rng(seed).uniform(-scale, scale, (n, 3)).astype(np.float32)


# ----- conventions -------------------------------------------------------------------------------
@pytest.mark.parametrize("model", ["linear", "rubber"])
def test_env_checkers_pass(model):
    env = make(model=model).unwrapped
    gym_check_env(env, skip_render_check=True)
    sb3_check_env(env, warn=False)


def test_a_fixed_manoeuvre_replays_bit_for_bit_and_truncates_at_its_end():
    env = make(model="rubber")
    first = rollout(env, manoeuvre(), n=400)
    second = rollout(env, manoeuvre(), n=400)
    assert len(first) == len(second) == 300 and first[-1][3]
    assert all(same(a, b) for a, b in zip(first, second, strict=True))
    info = first[150][4]
    assert info["lateral_accel_m_per_s2"] == 5.0 and info["roll_rad"] > 0.005  # rolls outward


def test_every_output_the_issue_names_is_in_info_as_a_plain_value():
    info = rollout(make(), manoeuvre(), n=120)[-1][4]
    keys = ["wheel_load_left_n", "wheel_lift_right", "camber_left_rad", "track_change_m",
            "roll_rad", "roll_rate_rad_per_s", "body_vertical_accel_m_per_s2",
            "body_lateral_accel_m_per_s2"]  # fmt: skip
    for k in POSITIONS:
        for role in ("model", "reference"):
            keys += [f"force_{k}_axial_{role}_n", f"force_{k}_radial_{role}_n",
                     f"moment_{k}_{role}_nm"]  # fmt: skip
    for k in keys:
        assert k in info and "reference_" + k in info or "_model_" in k or "_reference_" in k
        assert type(info[k]) in (float, bool), (k, type(info[k]))


def test_a_table_of_four_models_equals_one_model_for_all_four():
    table = dict.fromkeys(POSITIONS, "linear")
    a = rollout(make(model=table, reference=table), manoeuvre(), n=150)
    b = rollout(make(model="linear", reference="linear"), manoeuvre(), n=150)
    assert all(np.array_equal(x[0], y[0]) for x, y in zip(a, b, strict=True))


def test_bad_options_and_actions_are_refused_naming_the_value():
    env = make()
    with pytest.raises(RigError, match="unknown reset option"):
        env.reset(options={"road": np.zeros(3)})
    with pytest.raises(RigError, match="differ in length"):
        env.reset(options={"road_left": np.zeros(3), "lateral_accel": np.zeros(4)})
    with pytest.raises(RigError, match="max_lateral_accel_step"):
        env.reset(options={"lateral_accel": np.full(3, 1.0)})
    env.reset(seed=0)
    with pytest.raises(RigError, match=r"\(3,\)"):
        env.step(np.zeros(2, np.float32))
    with pytest.raises(RigError, match="keys"):
        make(model={"lower_left": "linear"})


@pytest.mark.parametrize("model", ["linear", "rubber"])
def test_a_pickled_or_copied_env_continues_identically(model):
    acts = random_actions()
    expected = rollout(make(model=model), actions=acts)
    env = make(model=model)
    env.reset(seed=0)
    for a in acts[:150]:
        env.step(a)
    restored = pickle.loads(pickle.dumps(env))
    twin = copy.deepcopy(env)
    for a in -acts[:50]:  # the copy drives elsewhere; the original is untouched
        twin.step(a)
    for i, a in enumerate(acts[150:]):
        assert same(restored.step(a), expected[150 + i]), i
        assert same(env.step(a), expected[150 + i]), i


def test_render_gives_frames_and_survives_pickling():
    env = make(render_mode="rgb_array")
    rollout(env, manoeuvre(), n=60)
    frame = env.render()
    assert frame.shape == (400, 600, 3) and frame.dtype == np.uint8 and frame.std() > 0
    assert np.array_equal(pickle.loads(pickle.dumps(env)).render(), frame)


def test_the_vector_env_equals_the_scalar_envs_and_autoresets():
    n = 2
    venv = gym.make_vec("HalfCar-v0", num_envs=n, vectorization_mode="vector_entry_point",
                        max_episode_steps=40)  # fmt: skip
    acts = random_actions(45)
    obs, info = venv.reset(seed=0)
    assert obs.shape == (n, 16) and info["roll_rad"].shape == (n,)
    single = rollout(make(), actions=acts, n=40)
    for k in range(40):
        obs, reward, terminated, truncated, info = venv.step(np.stack([acts[k]] * n))
        assert np.array_equal(obs[0], single[k][0]) and np.array_equal(obs[1], single[k][0])
    assert truncated.all()
    obs, reward, *_ = venv.step(np.stack([acts[0]] * n))  # NextStep: the reset observation
    assert not obs.any() and not reward.any()


def test_the_docstring_examples_run():
    for name in ("halfcar", "halfcar_vector"):
        mod = importlib.import_module(f"bushenv.rigs.{name}")
        result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
        assert result.attempted > 0 and result.failed == 0
