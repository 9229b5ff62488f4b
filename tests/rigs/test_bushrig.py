"""BushRig-v0: the prescribed-motion bushing test rig."""

from __future__ import annotations

import math
import tracemalloc

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from hypothesis import given, settings
from hypothesis import strategies as st
from rig_test_models import ALL_MODELS, Buggy, RaisesAfter, ValueAfter, model_or_skip
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from bushenv import excitation
from bushenv.models import get_model
from bushenv.models.linear import LinearBushing
from bushenv.rigs.common import RigError
from bushenv.rigs.specs import load_spec

DT = 1.0 / 204.8
MAX_STEP = excitation.MAX_VELOCITY_M_PER_S * DT


def make(**kw):
    return gym.make("BushRig-v0", **kw)


def run(env, actions, seed=0, options=None):
    obs, info = env.reset(seed=seed, options=options)
    out = [(obs, 0.0, False, False, info)]
    for a in actions:
        out.append(env.step(a))
        if out[-1][2] or out[-1][3]:
            break
    return out


# ----- spec and limits ---------------------------------------------------------------------
def test_spec_machine_limits_equal_the_excitation_modules_constants():
    kw = load_spec("BushRig-v0")["kwargs"]
    assert kw["max_displacement_m"] == excitation.MAX_DISPLACEMENT_M
    assert kw["max_velocity_m_per_s"] == pytest.approx(excitation.MAX_VELOCITY_M_PER_S, rel=1e-15)
    assert kw["force_limit_n"] == excitation.MAX_DYNAMIC_FORCE_N
    assert kw["dt_s"] == DT


def test_unknown_argument_is_refused_naming_it():
    with pytest.raises(RigError, match="stiffnes"):
        make(stiffnes=3.0)


def test_action_one_moves_the_actuator_by_the_velocity_limit_per_step():
    env = make()
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([1.0], np.float32))
    assert info["displacement_m"] == pytest.approx(MAX_STEP, rel=1e-6)
    assert info["velocity_m_per_s"] == pytest.approx(excitation.MAX_VELOCITY_M_PER_S, rel=1e-6)


def test_displacement_never_leaves_the_stroke():
    env = make()
    env.reset(seed=0)
    xs = [env.step(np.array([1.0], np.float32))[4]["displacement_m"] for _ in range(20)]
    assert max(xs) == excitation.MAX_DISPLACEMENT_M
    assert all(abs(x) <= excitation.MAX_DISPLACEMENT_M for x in xs)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.one_of(
            st.floats(allow_nan=True, allow_infinity=True, width=32),
            st.sampled_from([np.nan, np.inf, -np.inf, 1e30, -1e30]),
        ),
        min_size=1,
        max_size=30,
    )
)
def test_any_action_is_cleaned_never_raises_and_keeps_obs_in_the_box(actions):
    env = make()
    env.reset(seed=0)
    step = env.unwrapped.params.max_step
    x_prev = 0.0
    for a in actions:
        obs, r, term, trunc, info = env.step(np.array([a], dtype=np.float32))
        assert env.observation_space.contains(obs)
        assert math.isfinite(r)
        a32 = float(np.float32(a))
        expected = 0.0 if math.isnan(a32) else max(-1.0, min(1.0, a32))
        want = max(-0.0125, min(0.0125, x_prev + expected * step))
        assert info["displacement_m"] == want
        x_prev = want
        if term or trunc:
            break


# ----- physics: the analytic prescribed-motion force -----------------------------------------
def test_linear_model_force_equals_kelvin_voigt_of_the_prescribed_motion():
    """x prescribed, piecewise linear between samples: F_k = k x_k + c (x_k - x_k-1) / dt
    exactly (to 1e-9 relative), and within the O(dt) velocity error of the smooth sine."""
    k, c = 379.68e3, 4.4e3
    f_hz, amp = 10.0, 4.0e-3
    t = np.arange(1, 410) * DT
    x = amp * np.sin(2 * np.pi * f_hz * t)
    env = make(reference="linear")
    out = run(env, [0.0] * len(x), options={"excitation": x})
    force = np.array([o[4]["force_model_n"] for o in out[1:]])
    xs = np.array([o[4]["displacement_m"] for o in out[1:]])
    np.testing.assert_array_equal(xs, x)
    v_piecewise = np.diff(x, prepend=0.0) / DT
    np.testing.assert_allclose(force, k * x + c * v_piecewise, rtol=1e-9, atol=1e-9)
    w = 2 * np.pi * f_hz
    smooth = k * x + c * amp * w * np.cos(w * t)
    # backward-difference velocity error <= A w^2 dt / 2 (plus the w^3 term), times c
    bound = c * amp * w**2 * DT / 2 * 1.05
    assert np.max(np.abs(force[1:] - smooth[1:])) <= bound


def test_linear_model_and_linear_reference_agree_so_reward_is_zero():
    env = make(reference="linear")
    out = run(env, np.full((50, 1), 0.7, np.float32))
    assert all(o[1] == 0.0 for o in out[1:])


# ----- models and files -----------------------------------------------------------------------
def test_model_can_be_a_name_an_object_or_a_saved_file(tmp_path):
    soft = LinearBushing(200e3, 2e3)
    path = soft.save(tmp_path / "soft.npz")
    forces = []
    for spec in (soft, str(path), path):
        env = make(model=spec)
        env.reset(seed=0)
        forces.append(env.step(np.array([1.0], np.float32))[4]["force_model_n"])
    assert forces[0] == forces[1] == forces[2]
    assert forces[0] == pytest.approx(200e3 * MAX_STEP + 2e3 * MAX_STEP / DT, rel=1e-12)
    env = make(model="linear")
    env.reset(seed=0)
    assert env.step(np.array([1.0], np.float32))[4]["force_model_n"] != forces[0]


def test_a_model_object_is_copied_so_two_envs_do_not_share_state():
    m = get_model("linear")
    a, b = make(model=m), make(model=m)
    assert a.unwrapped.model is not b.unwrapped.model
    assert a.unwrapped.model is not m


@pytest.mark.parametrize("axis", ["axial", "radial"])
@pytest.mark.parametrize("name", ALL_MODELS)
def test_env_checkers_of_gymnasium_and_sb3_pass(name, axis):
    model_or_skip(name, axis)
    env = gym.make("BushRig-v0", model=name, axis=axis).unwrapped
    gym_check_env(env, skip_render_check=True)
    sb3_check_env(env, warn=False)


def test_env_checkers_pass_with_a_saved_model_file(tmp_path):
    path = get_model("linear", "radial").save(tmp_path / "radial_linear.npz")
    env = gym.make("BushRig-v0", model=str(path), axis="radial").unwrapped
    gym_check_env(env, skip_render_check=True)
    sb3_check_env(env, warn=False)


# ----- determinism and replay -------------------------------------------------------------------
def test_same_seed_gives_the_same_episode_also_after_a_second_reset():
    rng = np.random.default_rng(3)
    actions = rng.uniform(-1, 1, size=(200, 1)).astype(np.float32)
    env = make(model="linear", reference="rubber")
    first = run(env, actions, seed=7)
    second = run(env, actions, seed=7)
    third = run(make(model="linear", reference="rubber"), actions, seed=7)
    for a, b, c in zip(first, second, third, strict=True):
        np.testing.assert_array_equal(a[0], b[0])
        np.testing.assert_array_equal(a[0], c[0])
        assert a[1] == b[1] == c[1]
        assert a[4] == b[4] == c[4]


def test_excitation_replay_is_exact_ignores_actions_and_ends_with_the_profile():
    x = excitation.random_rpc(1.5, 1.0, DT, seed=1)
    assert excitation.within_limits(np.concatenate([[0.0], x]), DT)[0]
    env = make()
    out_a = run(env, np.full((len(x) + 5, 1), 1.0, np.float32), options={"excitation": x})
    out_b = run(env, np.full((len(x) + 5, 1), -1.0, np.float32), options={"excitation": x})
    assert len(out_a) == len(x) + 1
    assert out_a[-1][3] is True and not any(o[3] for o in out_a[:-1])
    xs = np.array([o[4]["displacement_m"] for o in out_a[1:]])
    np.testing.assert_array_equal(xs, x)
    fa = [o[4]["force_model_n"] for o in out_a]
    fb = [o[4]["force_model_n"] for o in out_b]
    assert fa == fb
    # the next reset without options is back to agent control
    env.reset()
    assert env.step(np.array([1.0], np.float32))[4]["displacement_m"] == pytest.approx(MAX_STEP)


@pytest.mark.parametrize(
    "bad, match",
    [
        (np.array([0.0, np.nan]), "not finite"),
        (np.array([0.0, 0.02]), "stroke"),
        (np.array([0.0, 0.0, 0.01]), "velocity"),
        (np.array([0.01]), "velocity"),
        (np.zeros((0,)), "shape"),
    ],
)
def test_excitation_outside_the_machine_limits_is_refused(bad, match):
    env = make()
    with pytest.raises(RigError, match=match):
        env.reset(options={"excitation": bad})


# ----- episode end ------------------------------------------------------------------------------
def test_model_returning_nan_terminates_with_info_saying_so(nan_model):
    env = make(model=nan_model)
    out = run(env, np.full((20, 1), 0.1, np.float32))
    assert len(out) == 7  # reset + 5 good samples + the NaN one
    obs, r, term, trunc, info = out[-1]
    assert term and not trunc
    assert info["diverged"] and not info["model_force_finite"]
    assert "not finite" in info["divergence_reason"]
    assert r == 10.0 and env.observation_space.contains(obs)


def test_model_raising_an_error_terminates_instead_of_crashing():
    env = make(model=RaisesAfter(after=3))
    out = run(env, np.full((20, 1), 0.1, np.float32))
    info = out[-1][4]
    assert out[-1][2] and info["diverged"]
    assert "test double gave up" in info["divergence_reason"]


def test_a_model_bug_ends_the_episode_as_a_model_error_not_a_divergence():
    env = make(model=Buggy(after=3))
    out = run(env, np.full((20, 1), 0.1, np.float32))
    terminated, info = out[-1][2], out[-1][4]
    assert terminated and not info["diverged"]
    assert "ValueError" in info["model_error"] and "broadcast" in info["model_error"]
    assert info["divergence_reason"] == ""
    assert all(step[4]["model_error"] == "" for step in out[:-1])


def test_model_beyond_the_machine_force_terminates_as_divergence():
    env = make(model=LinearBushing(5e6, 0.0), reference="linear")
    out = run(env, np.full((20, 1), 1.0, np.float32))
    info = out[-1][4]
    assert out[-1][2] and info["model_over_force_limit"] and info["diverged"]
    assert abs(info["force_model_n"]) > 25e3 and abs(info["force_reference_n"]) <= 25e3


def test_reference_beyond_the_machine_force_truncates_without_a_verdict():
    env = make(model="linear", reference=LinearBushing(5e6, 0.0))
    out = run(env, np.full((20, 1), 1.0, np.float32))
    info = out[-1][4]
    assert out[-1][3] and not out[-1][2]
    assert info["machine_limit"] and not info["diverged"]


def test_episode_truncates_after_episode_steps():
    env = make(max_episode_steps=30)
    out = run(env, np.zeros((100, 1), np.float32))
    assert len(out) == 31 and out[-1][3] and not out[-1][2]


def test_divergence_monitor_hook_ends_the_episode_with_its_reason():
    calls = []

    class Monitor:
        def reset(self):
            calls.append("reset")

        def __call__(self, info):
            return "too far" if info["displacement_m"] > 0.01 else False

    env = make(divergence_monitor=Monitor())
    out = run(env, np.full((20, 1), 1.0, np.float32))
    info = out[-1][4]
    assert out[-1][2] and info["monitor_verdict"] and info["divergence_reason"] == "too far"
    assert info["displacement_m"] > 0.01 and calls == ["reset"]


def test_reward_fn_hook_replaces_the_reward():
    env = make(reward_fn=lambda info: -info["displacement_m"])
    env.reset(seed=0)
    _, r, *_ = env.step(np.array([1.0], np.float32))
    assert r == pytest.approx(-MAX_STEP)


def test_default_reward_is_the_normalised_force_deviation():
    env = make(model=LinearBushing(300e3, 4.4e3), reference="linear")
    env.reset(seed=0)
    _, r, _, _, info = env.step(np.array([1.0], np.float32))
    assert r == pytest.approx(abs(info["error_n"]) / 4746.0)
    assert info["error_n"] == pytest.approx((300e3 - 379.68e3) * MAX_STEP)


def test_info_holds_plain_python_values():
    env = make(reference="rubber")
    _, info = env.reset(seed=0)
    _, _, _, _, info2 = env.step(np.array([0.5], np.float32))
    for d in (info, info2):
        for k, v in d.items():
            assert type(v) in (float, int, bool, str), (k, type(v))


def test_memory_stays_flat_over_a_long_rollout():
    env = make(model="linear", reference="rubber", max_episode_steps=-1)
    env.reset(seed=0)
    a = np.array([0.3], np.float32)
    b = np.array([-0.3], np.float32)
    for i in range(2000):
        env.step(a if (i // 4) % 2 else b)
    tracemalloc.start()
    before = tracemalloc.take_snapshot()
    for i in range(5000):
        env.step(a if (i // 4) % 2 else b)
    after = tracemalloc.take_snapshot()
    tracemalloc.stop()
    grown = sum(s.size_diff for s in after.compare_to(before, "filename"))
    assert grown < 64 * 1024


@pytest.mark.slow
def test_memory_stays_flat_over_a_million_steps():
    env = make(model="linear", reference="rubber", max_episode_steps=-1, render_mode="rgb_array")
    env.reset(seed=0)
    a = np.array([0.3], np.float32)
    b = np.array([-0.3], np.float32)
    tracemalloc.start()
    before = None
    for i in range(10**6):
        env.step(a if (i // 4) % 2 else b)
        if i == 10_000:
            before = tracemalloc.take_snapshot()
    after = tracemalloc.take_snapshot()
    tracemalloc.stop()
    grown = sum(s.size_diff for s in after.compare_to(before, "filename"))
    assert grown < 64 * 1024


# ----- bad input -------------------------------------------------------------------------------
def test_a_refused_action_leaves_the_episode_where_it_was():
    good = np.array([0.5], np.float32)
    env, twin = make(), make()
    env.reset(seed=0)
    twin.reset(seed=0)
    env.step(good)
    with pytest.raises(RigError, match=r"^BushRig-v0: action .* shape \(1,\)$"):
        env.step(np.array([0.1, 0.2], np.float32))
    twin.step(good)
    assert env.step(good)[4] == twin.step(good)[4]  # as if the bad call never happened


@pytest.mark.parametrize(
    "error",
    [ZeroDivisionError("k / 0"), FloatingPointError("overflow"), OverflowError("range")],
    ids=lambda e: type(e).__name__,
)
def test_model_raising_an_arithmetic_error_terminates_with_its_name(error):
    env = make(model=ValueAfter(after=3, error=error))
    out = run(env, np.full((20, 1), 0.1, np.float32))
    assert len(out) == 5  # reset + 3 good samples + the one that raised
    obs, r, term, trunc, info = out[-1]
    assert term and not trunc and info["diverged"] and not info["model_force_finite"]
    assert info["divergence_reason"] == f"model raised {type(error).__name__}: {error}"
    assert r == 10.0 and env.observation_space.contains(obs)


def test_history_beyond_ten_thousand_samples_is_refused_before_allocating():
    with pytest.raises(RigError, match=r"history must be at most 10000 samples, got 1000000000"):
        make(history=10**9)
    with pytest.raises(RigError, match=r"history must be at most 10000"):
        make(history=10_001)
    assert make(history=10_000).observation_space.shape == (30_000,)


@pytest.mark.parametrize("options", [5, "excitation", [0.0, 0.001], np.zeros(3)], ids=repr)
def test_reset_options_that_are_not_a_dict_are_refused_naming_them(options):
    with pytest.raises(RigError, match=r"^BushRig-v0: reset options must be a dict"):
        make().reset(options=options)


@pytest.mark.parametrize(
    "profile", ["abc", ["0.001", "0.002"], [0.0, None], [[0.0], [0.0, 0.001]]], ids=repr
)
def test_excitation_that_is_not_numbers_is_refused(profile):
    with pytest.raises(RigError, match=r"^excitation must be numbers"):
        make().reset(options={"excitation": profile})


# ----- rendering -------------------------------------------------------------------------------
def test_rgb_array_frame_shows_the_rig_and_changes_with_its_state():
    env = make(render_mode="rgb_array", reference="rubber")
    env.reset(seed=0)
    first = env.render()
    assert first.shape == (400, 600, 3) and first.dtype == np.uint8
    for _ in range(3):
        env.step(np.array([1.0], np.float32))
    second = env.render()
    assert (first != second).any(axis=2).sum() > 500
    assert len(np.unique(second.reshape(-1, 3), axis=0)) > 5


def test_force_termination_cannot_fire_where_the_single_env_skips_calling_it():
    """BushRigEnv.step calls divergence.force_termination only when a force is not finite or
    beyond the limit; within it, the function must decide "go on" (so skipping it is exact)."""
    from bushenv.divergence import force_termination

    limit = 25e3
    rng = np.random.default_rng(0)
    edges = np.array([0.0, -0.0, 5e-324, limit, -limit, np.nextafter(limit, 0), 1e-300])
    f_m = np.concatenate([edges, rng.uniform(-limit, limit, 10_000), edges[::-1]])
    f_r = np.concatenate([edges[::-1], rng.uniform(-limit, limit, 10_000), edges])
    assert np.all(np.abs(f_m) <= limit) and np.all(np.abs(f_r) <= limit)
    for flags in force_termination(f_m, f_r, limit):
        assert not flags.any()
    # and just beyond it, it does fire: the skip is no wider than the criteria
    over = np.nextafter(limit, np.inf)
    non_finite, model_over, reference_over = force_termination(
        np.array([over, np.nan, 0.0]), np.array([0.0, 0.0, over]), limit
    )
    assert list(model_over) == [True, False, False] and list(non_finite) == [False, True, False]
    assert list(reference_over) == [False, False, True]
