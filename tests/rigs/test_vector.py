"""BushRigVectorEnv: N rigs as arrays, equal to N single envs bit for bit."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from rig_test_models import ALL_MODELS, NanAfter, ValueAfter, model_or_skip

from bushenv.rigs.common import RigError, resolve_reference
from bushenv.rigs.vector import BushRigVectorEnv

KEYS = ("displacement_m", "velocity_m_per_s", "force_model_n", "force_reference_n", "diverged")


def make_vec(n, **kw):
    return gym.make_vec("BushRig-v0", num_envs=n, vectorization_mode="vector_entry_point", **kw)


def single_rollout(actions, seed, **kw):
    """One BushRigEnv driven like a next-step autoreset vector column."""
    env = gym.make("BushRig-v0", **kw)
    obs, _ = env.reset(seed=seed)
    rows, done = [], False
    for a in actions:
        if done:
            obs, info = env.reset()
            rows.append((obs, 0.0, False, False, None))
            done = False
            continue
        obs, r, term, trunc, info = env.step(a)
        rows.append((obs, r, term, trunc, info))
        done = term or trunc
    return rows


def test_make_vec_with_vector_entry_point_gives_the_array_env():
    env = make_vec(3)
    assert isinstance(env.unwrapped, BushRigVectorEnv)
    obs, info = env.reset(seed=0)
    assert obs.shape == (3, 12) and obs.dtype == np.float32
    assert env.observation_space.contains(obs)
    obs, r, term, trunc, info = env.step(env.action_space.sample())
    assert r.shape == term.shape == trunc.shape == (3,)
    assert info["force_model_n"].shape == (3,) and info["_force_model_n"].all()


@pytest.mark.parametrize("axis", ["axial", "radial"])
@pytest.mark.parametrize("name", ALL_MODELS)
def test_vector_columns_equal_single_envs_bit_for_bit(name, axis):
    model_or_skip(name, axis)
    if name == "rubber":
        # get_model("rubber") includes the load cell's noise, drawn per batch layout; the
        # equality holds for the deterministic specimen
        name = resolve_reference("rubber", axis, 1.0 / 204.8)
    n, steps = 4, 150
    rng = np.random.default_rng(11)
    actions = rng.uniform(-1.3, 1.3, size=(steps, n, 1)).astype(np.float32)
    actions[3, 0, 0] = np.nan
    actions[4, 1, 0] = np.inf
    kw = dict(model=name, axis=axis, max_episode_steps=60)
    venv = make_vec(n, **kw)
    venv.reset(seed=5)
    vec = [venv.step(a) for a in actions]
    for j in range(n):
        single = single_rollout(actions[:, j], 5, **kw)
        for t, (obs, r, term, trunc, info) in enumerate(single):
            v_obs, v_r, v_term, v_trunc, v_info = vec[t]
            assert np.array_equal(obs, v_obs[j]), (j, t)
            assert r == v_r[j] and term == v_term[j] and trunc == v_trunc[j], (j, t)
            if info is not None:
                for k in KEYS:
                    assert info[k] == v_info[k][j] or (info[k] != info[k]), (k, j, t)


def test_vector_autoreset_is_next_step_and_restarts_from_rest():
    env = make_vec(2, max_episode_steps=5)
    env.reset(seed=0)
    a = np.ones((2, 1), np.float32)
    for _ in range(4):
        env.step(a)
    obs, r, term, trunc, _ = env.step(a)
    assert trunc.all() and not term.any()
    obs, r, term, trunc, info = env.step(a)
    assert (obs == 0).all() and (r == 0).all() and not (term | trunc).any()
    assert (info["displacement_m"] == 0).all()
    _, _, _, _, info = env.step(a)
    assert info["displacement_m"] == pytest.approx(np.full(2, env.unwrapped.params.max_step))


def test_vector_replays_one_excitation_per_column():
    t = np.arange(1, 101) / 204.8
    x = np.stack([2e-3 * np.sin(2 * np.pi * 5 * t), -3e-3 * np.sin(2 * np.pi * 3 * t)], axis=1)
    env = make_vec(2)
    env.reset(seed=0, options={"excitation": x})
    xs = []
    for _ in range(100):
        _, _, term, trunc, info = env.step(np.ones((2, 1), np.float32))
        xs.append(info["displacement_m"])
    np.testing.assert_array_equal(np.array(xs), x)
    assert trunc.all()
    with pytest.raises(RigError, match="columns"):
        env.reset(options={"excitation": np.zeros((10, 3))})


def test_vector_marks_only_the_nan_column_as_diverged():
    env = BushRigVectorEnv(num_envs=3, model=NanAfter(after=4))
    env.reset(seed=0)
    a = np.array([[0.5], [0.5], [0.5]], np.float32)
    for _ in range(4):
        _, _, term, _, _ = env.step(a)
        assert not term.any()
    _, r, term, _, info = env.step(a)
    assert term.all() and info["diverged"].all() and (r == 10.0).all()
    assert info["divergence_reason"][0] == "model force is not finite"


@pytest.mark.parametrize(
    "actions",
    [np.zeros((2, 1), np.float32), np.zeros((3, 2), np.float32), None, "abc", [[0.1], ["x"], [0]]],
    ids=lambda a: type(a).__name__ + str(getattr(a, "shape", "")),
)
def test_vector_refuses_actions_of_another_shape_naming_n1_and_keeps_its_state(actions):
    env, twin = make_vec(3), make_vec(3)
    env.reset(seed=0)
    twin.reset(seed=0)
    with pytest.raises(RigError, match=r"^BushRig-v0: actions .* shape \(3, 1\)$"):
        env.step(actions)
    a = np.full((3, 1), 0.5, np.float32)
    got, want = env.step(a), twin.step(a)
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_array_equal(got[4]["step"], [1, 1, 1])


def test_vector_takes_actions_of_shape_n_like_n1():
    a = np.array([0.5, -0.25, 2.0], np.float32)
    env, twin = make_vec(3), make_vec(3)
    env.reset(seed=0)
    twin.reset(seed=0)
    np.testing.assert_array_equal(env.step(a)[0], twin.step(a.reshape(3, 1))[0])


@pytest.mark.parametrize("error", [ZeroDivisionError("k / 0"), OverflowError("range")], ids=repr)
def test_vector_model_raising_an_arithmetic_error_terminates_every_column(error):
    env = BushRigVectorEnv(num_envs=2, model=ValueAfter(after=3, error=error))
    env.reset(seed=0)
    a = np.full((2, 1), 0.5, np.float32)
    for _ in range(3):
        assert not env.step(a)[2].any()
    _, r, term, _, info = env.step(a)
    assert term.all() and info["diverged"].all() and (r == 10.0).all()
    assert list(info["divergence_reason"]) == [f"model raised {type(error).__name__}: {error}"] * 2


def test_vector_reset_options_that_are_not_a_dict_are_refused():
    with pytest.raises(RigError, match=r"^BushRig-v0: reset options must be a dict"):
        make_vec(2).reset(options=[1, 2])


def test_vector_render_gives_a_frame_of_rig_zero():
    env = BushRigVectorEnv(num_envs=2, render_mode="rgb_array")
    env.reset(seed=0)
    env.step(np.ones((2, 1), np.float32))
    (frame,) = env.render()
    assert frame.shape == (400, 600, 3)


def test_same_step_autoreset_columns_equal_single_envs_reset_at_once():
    """``autoreset_mode=SAME_STEP``: a finished column is reset in the step that ends it; its
    last observation and info are kept in ``final_obs`` / ``final_info``."""
    n, steps = 3, 90
    rng = np.random.default_rng(4)
    actions = rng.uniform(-1.3, 1.3, size=(steps, n, 1)).astype(np.float32)
    kw = dict(model=ValueAfter(after=12, value=4e4), max_episode_steps=20)
    venv = make_vec(n, autoreset_mode=gym.vector.AutoresetMode.SAME_STEP, **kw)
    venv.reset(seed=0)
    vec = [venv.step(a) for a in actions]
    ends = 0
    for j in range(n):
        env = gym.make("BushRig-v0", **kw)
        env.reset(seed=0)
        for t in range(steps):
            obs, r, term, trunc, info = env.step(actions[t, j])
            v_obs, v_r, v_term, v_trunc, v_info = vec[t]
            assert r == v_r[j] and term == v_term[j] and trunc == v_trunc[j], (j, t)
            if term or trunc:
                ends += 1
                assert np.array_equal(v_info["final_obs"][j], obs) and v_info["_final_obs"][j]
                assert all(v_info["final_info"][k][j] == info[k] for k in KEYS)
                obs, info = env.reset()
            else:
                assert not v_info.get("_final_obs", np.zeros(n, bool))[j]
            assert np.array_equal(obs, v_obs[j]), (j, t)
            assert all(info[k] == v_info[k][j] for k in KEYS), (j, t)
    assert ends == n * (steps // 13)  # each episode: the force beyond the limit at step 13
