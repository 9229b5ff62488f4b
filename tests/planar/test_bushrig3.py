"""BushRig3-v0: both env checkers, vector = single envs, pickling, limits, divergence."""

import doctest
import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import bushenv  # noqa: F401  (registers the envs)
from bushenv.models.planar_linear import PlanarLinear
from bushenv.models.planar_narx import N_IN, PlanarNarx
from bushenv.rigs import bushrig3
from bushenv.rigs.common import RigError


def _nn_file(tmp_path):
    rng = np.random.default_rng(0)
    m = PlanarNarx(
        q_offset=np.zeros(3),
        q_scale=np.array([2e-3, 2e-3, 0.05]),
        f_offset=np.zeros(3),
        f_scale=np.array([500.0, 2000.0, 150.0]),
        w1=rng.normal(0, 0.3, (9, N_IN)),
        b1=np.zeros(9),
        w_out=rng.normal(0, 0.3, (3, 9)),
        b_out=np.zeros(3),
    )
    return str(m.save(tmp_path / "nn.npz"))


@pytest.mark.parametrize("model", ["linear", "reference", "file", "file judged"])
def test_gymnasium_and_sb3_checkers_pass(model, tmp_path):
    kwargs = {"model": model}
    if model.startswith("file"):
        kwargs["model"] = _nn_file(tmp_path)
    if model == "file judged":
        kwargs["reference"] = "rubber"
    env = gym.make("BushRig3-v0", **kwargs)
    check_env(env.unwrapped, skip_render_check=True)
    sb3_check_env(env.unwrapped, warn=False)


def test_a_users_model_without_a_reference_runs_without_one_and_says_so(tmp_path):
    with pytest.warns(UserWarning, match="no reference was given, so the rig runs without one"):
        env = gym.make("BushRig3-v0", model=_nn_file(tmp_path)).unwrapped
    assert env.core.reference is None
    env.reset(seed=0)
    _, reward, _, _, info = env.step(np.array([0.5, -0.5, 0.2], np.float32))
    assert "force_reference_axial" not in info
    f = np.array([info[f"force_model_{c}"] for c in ("axial", "radial", "rotation")])
    assert reward == pytest.approx(min(np.sum(np.abs(f) / env.core.force_scale), 10.0))


def test_reference_none_is_accepted_and_a_registered_reference_keeps_the_spec_scale():
    env = gym.make("BushRig3-v0", model="linear", reference="none").unwrapped
    assert env.core.reference is None
    builtin = gym.make("BushRig3-v0", model="linear").unwrapped
    assert builtin.core.reference.name == "rubber"
    np.testing.assert_array_equal(env.core.force_scale, builtin.core.force_scale)
    np.testing.assert_array_equal(builtin.core.force_scale, [4746.0, 18984.125, 450.0])


def test_a_users_reference_sets_the_force_scale_unless_one_is_given(tmp_path):
    from bushenv.planar.static_estimate import static_stiffness3

    soft = PlanarLinear(np.diag([1e5, 2e5, 300.0]), np.diag([100.0, 200.0, 1.0]))
    ref = str(soft.save(tmp_path / "soft.npz"))
    env = gym.make("BushRig3-v0", model="linear", reference=ref).unwrapped
    want = np.abs(static_stiffness3(soft)) * env.core.limit
    np.testing.assert_allclose(env.core.force_scale, want)
    np.testing.assert_allclose(env.core.force_scale, [1250.0, 2500.0, 45.0], rtol=1e-9)
    given = {"axial": 1.0, "radial": 2.0, "rotation": 3.0}
    env = gym.make("BushRig3-v0", model="linear", reference=ref, force_scale=given).unwrapped
    np.testing.assert_array_equal(env.core.force_scale, [1.0, 2.0, 3.0])


def test_vector_env_equals_single_envs_bit_for_bit():
    rng = np.random.default_rng(1)
    actions = rng.uniform(-0.2, 0.2, (40, 3, 3)).astype(np.float32)  # within every limit
    vec = gym.make_vec("BushRig3-v0", num_envs=3, vectorization_mode="vector_entry_point")
    obs_v, _ = vec.reset(seed=0)
    singles = [gym.make("BushRig3-v0") for _ in range(3)]
    for e in singles:
        e.reset(seed=0)
    for t in range(40):
        obs_v, rew_v, term_v, trunc_v, _ = vec.step(actions[t])
        assert not (term_v.any() or trunc_v.any())
        for i, e in enumerate(singles):
            obs, rew, *_ = e.step(actions[t, i])
            np.testing.assert_array_equal(obs, obs_v[i])
            assert rew == rew_v[i]


def test_pickled_env_continues_identically():
    env = gym.make("BushRig3-v0").unwrapped
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.array([0.3, -0.2, 0.5], np.float32))
    twin = pickle.loads(pickle.dumps(env))
    a = np.array([0.1, 0.4, -0.6], np.float32)
    np.testing.assert_array_equal(env.step(a)[0], twin.step(a)[0])


def test_stroke_and_rate_limits_hold():
    env = gym.make("BushRig3-v0").unwrapped
    env.reset(seed=0)
    info = env.step(np.ones(3, np.float32))[4]
    assert info["q_axial"] == pytest.approx(1.2566370614359172 * env.core.dt)
    for _ in range(20):
        info = env.step(np.ones(3, np.float32))[4]
    assert info["q_axial"] == 0.0125 and info["q_rotation"] == 0.15


def test_a_model_beyond_the_force_limit_terminates():
    stiff = PlanarLinear(np.diag([1e9, 1e9, 1e9]), np.zeros((3, 3)))
    env = gym.make("BushRig3-v0", model=stiff, reference="rubber")
    env.reset(seed=0)
    _, _, terminated, truncated, info = env.step(np.array([0.01, 0, 0], np.float32))
    assert terminated and not truncated and info["diverged"]


def test_bad_models_and_actions_are_refused_with_the_fix():
    with pytest.raises(RigError, match="known names"):
        gym.make("BushRig3-v0", model="lstm")
    with pytest.raises(RigError, match="no preset.*npz"):
        gym.make("BushRig3-v0", model="nn")
    env = gym.make("BushRig3-v0").unwrapped
    env.reset(seed=0)
    with pytest.raises(RigError, match=r"shape \(3,\)"):
        env.step(np.zeros(2, np.float32))


def test_the_docstring_example_runs():
    result = doctest.testmod(bushrig3)
    assert result.attempted > 0 and result.failed == 0


def test_a_column_reset_takes_a_hybrid_bw_backbone_to_rest_too():
    """The vector env's autoreset: the Bouc-Wen backbone's hysteresis and relaxation of the
    reset column go back to rest, the other column's stay."""
    from bushenv.models.planar_hybrid_bw import PlanarBoucWenHybrid

    model = PlanarBoucWenHybrid.untrained(seed=0)
    gain = np.diag([1e5, 3e5, 500.0])[None]
    backbone = dict(model.backbone.params, relax_tau=[0.05], relax_gain=gain)
    model = PlanarBoucWenHybrid(**{**model.params, **backbone})
    core = bushrig3.Rig3Core(
        {**gym.spec("BushRig3-v0").kwargs, "model": model, "reference": "linear"}, 2
    )
    rng = np.random.default_rng(0)
    for _ in range(20):
        core.step(rng.uniform(-0.2, 0.2, (2, 3)).astype(np.float32))
    run = core.model
    assert run.backbone.relax_tau.shape == (1,) and np.all(run.backbone.state[:, 1] != 0)
    core.reset(np.array([False, True]))
    assert np.all(run.backbone.state[:, 1] == 0)
    assert np.array_equal(run.state[:, 1], run.initial_state(1)[:, 0])
    assert np.any(run.backbone.state[:, 0] != 0)
