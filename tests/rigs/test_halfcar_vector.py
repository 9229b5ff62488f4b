"""HalfCarVectorEnv: HalfCar-v0's vector entry point on HalfCarBatch, against the scalar env."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest

import bushenv  # noqa: F401  (registers the ids)
from bushenv.rigs.common import RigError

AGREEMENT = 0.01  # of each compared output's peak over the run (the batch's, docs/envs.md)
COMPARED = ("wheel_load_left_n", "wheel_load_right_n", "roll_rad", "camber_right_rad",
            "force_lower_left_radial_model_n", "force_upper_right_axial_reference_n",
            "moment_lower_right_model_nm", "error_n")  # fmt: skip


def make_vec(n, **kw):
    return gym.make_vec("HalfCar-v0", num_envs=n, vectorization_mode="vector_entry_point", **kw)


def scalar_infos(options=None, actions=None, steps=200):
    env = gym.make("HalfCar-v0", max_episode_steps=-1).unwrapped
    env.reset(seed=0, options=options)
    return [env.step(None if actions is None else actions[k])[4] for k in range(steps)]


def assert_agrees(single, column):
    for k in COMPARED:
        e = np.array([i[k] for i in single])
        peak = np.abs(e - e[0]).max()
        assert np.abs(e - column[k]).max() <= AGREEMENT * peak, (k, np.abs(e - column[k]).max())


def test_columns_replaying_their_own_manoeuvres_follow_the_scalar_env():
    t = np.arange(200) / 204.8
    left = 0.02 * np.sin(2 * np.pi * 1.5 * t)
    ay = np.minimum(0.2 * np.arange(200), 4.0)
    venv = make_vec(2, max_episode_steps=200)
    venv.reset(seed=0, options={"road_left": np.stack([left, -left], 1), "lateral_accel": ay})
    rows = [venv.step(np.zeros((2, 3), np.float32))[4] for _ in range(200)]
    for j, sign in enumerate((1.0, -1.0)):
        single = scalar_infos({"road_left": sign * left, "lateral_accel": ay})
        assert_agrees(single, {k: np.array([r[k][j] for r in rows]) for k in COMPARED})


def test_actions_drive_the_columns_as_they_drive_the_scalar_env_and_time_limits_reset():
    rng = np.random.default_rng(0)
    acts = rng.uniform(-0.3, 0.3, (120, 3)).astype(np.float32)
    venv = make_vec(2, max_episode_steps=120)
    venv.reset(seed=0)
    rows = []
    for k in range(120):
        obs, reward, terminated, truncated, info = venv.step(np.stack([acts[k]] * 2))
        rows.append(info)
        assert not terminated.any()
    assert truncated.all()
    single = scalar_infos(actions=acts, steps=120)
    for j in range(2):
        assert_agrees(single, {k: np.array([r[k][j] for r in rows]) for k in COMPARED})
    obs, reward, *_ = venv.step(np.stack([acts[0]] * 2))  # NextStep: the reset observation
    assert not obs.any() and not reward.any()


def test_a_runaway_model_terminates_its_column_with_the_scalar_envs_reason():
    from bushenv.models import get_model

    model = get_model("linear", coords=3)
    model.c_matrix[2, 2] = -50 * abs(model.c_matrix[2, 2]) - 500.0
    k = np.arange(400)
    venv = make_vec(1, model=model, max_episode_steps=400)
    venv.reset(seed=0, options={"road_left": 0.01 * np.sin(2 * np.pi * 2 * k / 204.8)})
    for _ in range(400):
        obs, reward, terminated, truncated, info = venv.step(np.zeros((1, 3), np.float32))
        if terminated[0]:
            break
    assert terminated[0] and not truncated[0] and info["diverged"][0]
    assert info["divergence_reason"][0] == info["model_out_of_bounds"][0] != ""
    assert np.isfinite(obs).all()


def test_a_pickled_vector_env_continues_identically():
    venv = make_vec(2, max_episode_steps=60)
    venv.reset(seed=0)
    act = np.full((2, 3), 0.2, np.float32)
    for _ in range(10):
        venv.step(act)
    twin = pickle.loads(pickle.dumps(venv))
    for _ in range(10):
        a, b = venv.step(act), twin.step(act)
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[4]["roll_rad"], b[4]["roll_rad"])


def test_bad_actions_and_options_are_refused():
    venv = make_vec(2)
    venv.reset(seed=0)
    with pytest.raises(RigError, match=r"\(2, 3\)"):
        venv.step(np.zeros((2, 1), np.float32))
    with pytest.raises(RigError, match=r"\(T, 2\)"):
        venv.reset(options={"road_left": np.zeros((5, 3))})
    with pytest.raises(RigError, match="max_road_step_m"):
        venv.reset(options={"road_left": np.array([0.0, 0.06])})
