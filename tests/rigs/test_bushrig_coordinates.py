"""The bushing rig over C coordinates: BushRig-v0 (C = 1) and BushRig3-v0 (C = 3) are one env
class; what holds for one holds for both, and the three-axis reference's own rules."""

from __future__ import annotations

import doctest
import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from rig_test_models import NanAfter, NanAfter3
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import bushenv  # noqa: F401  (registers the envs)
from bushenv.models.planar_linear import PlanarLinear
from bushenv.models.planar_narx import N_IN, PlanarNarx
from bushenv.rigs import bushrig
from bushenv.rigs.bushrig import BushRigEnv
from bushenv.rigs.common import RigError
from bushenv.rigs.vector import BushRigVectorEnv

IDS = {"BushRig-v0": 1, "BushRig3-v0": 3}


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


@pytest.mark.parametrize("env_id", IDS)
def test_both_ids_are_one_class_sized_by_their_coordinates(env_id):
    env = gym.make(env_id).unwrapped
    venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point").unwrapped
    c = IDS[env_id]
    assert type(env) is BushRigEnv and type(venv) is BushRigVectorEnv
    assert env.params.n_coords == venv.params.n_coords == c
    assert env.action_space.shape == (c,) and env.observation_space.shape == (3 * c * 4,)
    assert env.params.max_x.shape == env.params.force_scale.shape == (c,)


@pytest.mark.parametrize("model", ["linear", "reference", "file", "file judged"])
def test_gymnasium_and_sb3_checkers_pass_over_three_coordinates(model, tmp_path):
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
    assert env.params.reference is None
    env.reset(seed=0)
    _, reward, _, _, info = env.step(np.array([0.5, -0.5, 0.2], np.float32))
    assert "force_reference_axial" not in info
    f = np.array([info[f"force_model_{c}"] for c in ("axial", "radial", "rotation")])
    assert reward == pytest.approx(min(np.sum(np.abs(f) / env.params.force_scale), 10.0))


def test_reference_none_is_accepted_and_a_registered_reference_keeps_the_spec_scale():
    env = gym.make("BushRig3-v0", model="linear", reference="none").unwrapped
    assert env.params.reference is None
    builtin = gym.make("BushRig3-v0", model="linear").unwrapped
    assert builtin.params.reference.name == "rubber"
    np.testing.assert_array_equal(env.params.force_scale, builtin.params.force_scale)
    np.testing.assert_array_equal(builtin.params.force_scale, [4746.0, 18984.125, 450.0])


def test_a_users_reference_sets_the_force_scale_unless_one_is_given(tmp_path):
    from bushenv.identify.static_estimate import coordinate_stiffness

    soft = PlanarLinear(np.diag([1e5, 2e5, 300.0]), np.diag([100.0, 200.0, 1.0]))
    ref = str(soft.save(tmp_path / "soft.npz"))
    env = gym.make("BushRig3-v0", model="linear", reference=ref).unwrapped
    want = np.abs(coordinate_stiffness(soft)) * env.params.max_x
    np.testing.assert_allclose(env.params.force_scale, want)
    np.testing.assert_allclose(env.params.force_scale, [1250.0, 2500.0, 45.0], rtol=1e-9)
    given = {"axial": 1.0, "radial": 2.0, "rotation": 3.0}
    env = gym.make("BushRig3-v0", model="linear", reference=ref, force_scale=given).unwrapped
    np.testing.assert_array_equal(env.params.force_scale, [1.0, 2.0, 3.0])


@pytest.mark.parametrize("env_id", IDS)
def test_vector_env_equals_single_envs_bit_for_bit(env_id):
    c = IDS[env_id]
    rng = np.random.default_rng(1)
    actions = rng.uniform(-0.2, 0.2, (40, 3, c)).astype(np.float32)  # within every limit
    vec = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point")
    obs_v, _ = vec.reset(seed=0)
    singles = [gym.make(env_id) for _ in range(3)]
    for e in singles:
        e.reset(seed=0)
    for t in range(40):
        obs_v, rew_v, term_v, trunc_v, info_v = vec.step(actions[t])
        assert not (term_v.any() or trunc_v.any())
        for i, e in enumerate(singles):
            obs, rew, _, _, info = e.step(actions[t, i])
            np.testing.assert_array_equal(obs, obs_v[i])
            assert rew == rew_v[i]
            assert all(info[k] == info_v[k][i] for k in info if not k.startswith("_"))


@pytest.mark.parametrize("env_id", IDS)
def test_pickled_env_continues_identically(env_id):
    c = IDS[env_id]
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    for a in (0.3, -0.2, 0.5, 0.1, -0.4):
        env.step(np.full(c, a, np.float32))
    twin = pickle.loads(pickle.dumps(env))
    a = np.linspace(0.1, -0.6, c).astype(np.float32)
    np.testing.assert_array_equal(env.step(a)[0], twin.step(a)[0])


def test_stroke_and_rate_limits_hold_per_coordinate():
    env = gym.make("BushRig3-v0").unwrapped
    env.reset(seed=0)
    info = env.step(np.ones(3, np.float32))[4]
    assert info["q_axial"] == pytest.approx(1.2566370614359172 * env.params.dt)
    for _ in range(20):
        info = env.step(np.ones(3, np.float32))[4]
    assert info["q_axial"] == 0.0125 and info["q_rotation"] == 0.15


def test_a_model_beyond_the_force_limit_terminates_naming_the_coordinate():
    stiff = PlanarLinear(np.diag([1e9, 1e9, 1e9]), np.zeros((3, 3)))
    env = gym.make("BushRig3-v0", model=stiff, reference="rubber")
    env.reset(seed=0)
    _, _, terminated, truncated, info = env.step(np.array([0.01, 0, 0], np.float32))
    assert terminated and not truncated and info["diverged"]
    assert info["divergence_reason"].startswith("|F_model axial| = ")
    assert info["divergence_reason"].endswith("exceeds 25000 N")


@pytest.mark.parametrize("env_id", IDS)
def test_a_model_that_gives_nan_terminates_in_the_single_and_the_vector_env(env_id):
    c = IDS[env_id]
    nan = NanAfter(after=2) if c == 1 else NanAfter3(after=2)
    env = gym.make(env_id, model=nan, reference="rubber")
    env.reset(seed=0)
    ends = [env.step(np.full(c, 0.1, np.float32)) for _ in range(3)]
    first = next(i for i, s in enumerate(ends) if s[2])
    assert ends[first][4]["divergence_reason"] == "model force is not finite"
    assert ends[first][4]["diverged"] and not ends[first][4]["model_force_finite"]
    venv = gym.make_vec(
        env_id, num_envs=2, vectorization_mode="vector_entry_point", model=nan, reference="rubber"
    )
    venv.reset(seed=0)
    for _ in range(first + 1):
        _, _, term, _, info = venv.step(np.full((2, c), 0.1, np.float32))
    assert term.all() and list(info["divergence_reason"]) == ["model force is not finite"] * 2


def test_an_excitation_over_three_coordinates_is_replayed_exactly_and_checked():
    env = gym.make("BushRig3-v0").unwrapped
    q = np.zeros((30, 3))
    q[:, 0] = np.linspace(0.0, 2e-3, 30)
    q[:, 2] = np.linspace(0.0, -0.02, 30)
    env.reset(seed=0, options={"excitation": q})
    rows = [env.step(np.ones(3, np.float32)) for _ in range(30)]
    assert [r[4]["q_axial"] for r in rows] == q[:, 0].tolist()
    assert [r[4]["q_rotation"] for r in rows] == q[:, 2].tolist() and rows[-1][3]
    with pytest.raises(RigError, match=r"shape \(T, C\) with C = 3"):
        env.reset(options={"excitation": q[:, :2]})
    far = q.copy()
    far[-1, 2] = 0.5
    with pytest.raises(RigError, match="rotation excitation sample 29.*rad exceeds the stroke"):
        env.reset(options={"excitation": far})


def test_bad_models_and_actions_are_refused_with_the_fix():
    with pytest.raises(RigError, match="known names"):
        gym.make("BushRig3-v0", model="lstm")
    with pytest.raises(RigError, match="no preset.*npz"):
        gym.make("BushRig3-v0", model="nn")
    env = gym.make("BushRig3-v0").unwrapped
    env.reset(seed=0)
    with pytest.raises(RigError, match=r"shape \(3,\)"):
        env.step(np.zeros(2, np.float32))


def test_the_docstring_examples_run():
    result = doctest.testmod(bushrig)
    assert result.attempted > 0 and result.failed == 0


def test_a_column_reset_takes_a_hybrid_bw_backbone_to_rest_too():
    """The vector env's autoreset: the Bouc-Wen backbone's hysteresis and relaxation of the
    reset column go back to rest, the other column's stay."""
    from bushenv.models.planar_hybrid_bw import PlanarBoucWenHybrid

    model = PlanarBoucWenHybrid.untrained(seed=0)
    gain = np.diag([1e5, 3e5, 500.0])[None]
    backbone = dict(model.backbone.params, relax_tau=[0.05], relax_gain=gain)
    model = PlanarBoucWenHybrid(**{**model.params, **backbone})
    venv = gym.make_vec(
        "BushRig3-v0", num_envs=2, vectorization_mode="vector_entry_point", model=model,
        reference="linear",
    ).unwrapped  # fmt: skip
    venv.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(20):
        venv.step(rng.uniform(-0.2, 0.2, (2, 3)).astype(np.float32))
    run = venv.model
    assert run.backbone.relax_tau.shape == (1,) and np.all(run.backbone.state[:, 1] != 0)
    venv._reset_columns(np.array([False, True]))
    assert np.all(run.backbone.state[:, 1] == 0)
    assert np.array_equal(run.state[:, 1], run.initial_state(1)[:, 0])
