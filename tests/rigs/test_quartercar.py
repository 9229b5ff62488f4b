"""QuarterCar-v0: the planar quarter car hanging its control arm on the bushing."""

from __future__ import annotations

import math
import tracemalloc

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from hypothesis import given, settings
from hypothesis import strategies as st
from rig_test_models import (
    ALL_MODELS,
    Buggy,
    DiffKV,
    NanAfter,
    RaisesAfter,
    ValueAfter,
    model_or_skip,
)
from scipy import signal
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from bushenv import excitation
from bushenv.models import get_model
from bushenv.models.linear import TABLE1, LinearBushing
from bushenv.rigs.car import CarParameters
from bushenv.rigs.common import RigError
from bushenv.rigs.quartercar_batch import QuarterCarBatch

DT = 1.0 / 204.8
STEP = 0.05  # max_road_step_m of the spec
LOOSE = dict(  # bounds out of the way: look for instability, not for bump stops
    max_suspension_travel_m=10.0,
    max_body_displacement_m=10.0,
    max_bushing_deflection_m=1.0,
    force_limit_n=1e9,
)


def make(**kw):
    return gym.make("QuarterCar-v0", **kw)


def replay(env, road, seed=0):
    obs, info = env.reset(seed=seed, options={"excitation": road})
    rows = [(obs, 0.0, False, False, info)]
    while True:
        rows.append(env.step(np.zeros(1, np.float32)))
        if rows[-1][2] or rows[-1][3]:
            return rows


def worst_roads(T: int, rng) -> np.ndarray:
    """Admissible roads at the rate limit: square waves of 2..60-step half periods (through
    the wheel-hop resonance, 12 Hz ~ 8-9 steps), random bang-bang, then back to 0 and held
    6 s (at the rate limit the car can be thrown metres high; it must land and settle)."""
    cols = []  # (action sequence, height limit)
    for amp in (0.03, 0.15):
        for half in (1, 2, 3, 4, 6, 8, 9, 12, 17, 25, 40, 60):
            cols.append((np.where((np.arange(T) // half) % 2 == 0, 1.0, -1.0), amp))
    for _ in range(8):
        cols.append((np.sign(rng.uniform(-1, 1, T)), 0.15))
    roads = []
    for a, amp in cols:
        h, x = np.zeros(T + 1230), 0.0
        for t in range(T):
            x = min(amp, max(-amp, x + a[t] * STEP))
            h[t] = x
        for t in range(T, T + 1230):  # back to the flat road at the rate limit, hold 6 s
            x = x - math.copysign(min(abs(x), STEP), x)
            h[t] = x
        roads.append(h)
    return np.array(roads).T


# ----- conventions -------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ALL_MODELS)
def test_env_checkers_of_gymnasium_and_sb3_pass(name):
    for axis in ("radial", "axial"):
        model_or_skip(name, axis)
    env = make(model=name).unwrapped
    gym_check_env(env, skip_render_check=True)
    sb3_check_env(env, warn=False)


def test_env_checkers_pass_with_saved_model_files(tmp_path):
    paths = {
        a: str(get_model("linear", a).save(tmp_path / f"{a}.npz")) for a in ("radial", "axial")
    }
    env = make(model=paths).unwrapped
    gym_check_env(env, skip_render_check=True)
    sb3_check_env(env, warn=False)


def test_one_model_object_for_both_axes_is_refused():
    with pytest.raises(RigError, match="one axis"):
        make(model=get_model("linear", "radial"))


def test_spec_vehicle_is_a_plausible_passenger_car_corner():
    from bushenv.rigs.specs import load_spec

    p = CarParameters(load_spec("QuarterCar-v0")["kwargs"], resolve_models=False)
    wheel_rate = p.k_s * p.mount**2
    ride_rate = wheel_rate * p.k_t / (wheel_rate + p.k_t)
    body_hz = math.sqrt(ride_rate / p.m_s) / (2 * math.pi)
    hop_hz = math.sqrt((wheel_rate + p.k_t) / p.m_u) / (2 * math.pi)
    zeta = p.c_s * p.mount**2 / (2 * math.sqrt(ride_rate * p.m_s))
    assert 350 <= p.m_s <= 400 and 35 <= p.m_u <= 45
    assert 25e3 <= wheel_rate <= 30e3 and 1.0 <= body_hz <= 1.5 and 10 <= hop_hz <= 13
    assert 0.2 <= zeta <= 0.4


def test_at_rest_on_a_flat_road_nothing_moves():
    env = make(reference="linear")
    env.reset(seed=0)
    for _ in range(50):
        obs, r, term, trunc, info = env.step(np.zeros(1, np.float32))
    assert not obs.any() and r == 0.0
    assert info["chassis_y_m"] == 0.0 and info["force_radial_model_n"] == 0.0


@settings(max_examples=30, deadline=None)
@given(
    st.lists(
        st.one_of(
            st.floats(allow_nan=True, allow_infinity=True, width=32),
            st.sampled_from([np.nan, np.inf, -np.inf]),
        ),
        min_size=1,
        max_size=12,
    )
)
def test_any_action_is_cleaned_never_raises_and_keeps_obs_in_the_box(actions):
    env = make(reference="linear")
    env.reset(seed=0)
    h_prev = 0.0
    for a in actions:
        obs, r, term, trunc, info = env.step(np.array([a], dtype=np.float32))
        assert env.observation_space.contains(obs) and math.isfinite(r)
        a32 = float(np.float32(a))
        unit = 0.0 if math.isnan(a32) else max(-1.0, min(1.0, a32))
        want = max(-0.15, min(0.15, h_prev + unit * STEP))
        assert info["road_height_m"] == want
        h_prev = want
        if term or trunc:
            break


def test_same_seed_gives_the_same_episode_also_after_a_second_reset():
    rng = np.random.default_rng(4)
    actions = rng.uniform(-1, 1, size=(120, 1)).astype(np.float32)

    def run(env):
        env.reset(seed=3)
        return [env.step(a) for a in actions]

    env = make()
    first, second, third = run(env), run(env), run(make())
    for a, b, c in zip(first, second, third, strict=True):
        np.testing.assert_array_equal(a[0], b[0])
        np.testing.assert_array_equal(a[0], c[0])
        assert a[1] == b[1] == c[1] and a[4] == b[4] == c[4]


def test_info_holds_plain_python_values():
    env = make()
    _, info = env.reset(seed=0)
    info2 = env.step(np.array([0.4], np.float32))[4]
    for d in (info, info2):
        for k, v in d.items():
            assert type(v) in (float, int, bool, str), (k, type(v))


# ----- roads -------------------------------------------------------------------------------------
@pytest.mark.parametrize("length_m", excitation.PAPER_BUMP_LENGTHS_M)
def test_the_papers_bumps_replay_exactly_and_are_reachable_by_actions(length_m):
    road = excitation.bump(length_m, 0.1, excitation.PAPER_VEHICLE_SPEED_M_PER_S, DT, 0.05, 0.2)
    rows = replay(make(reference="linear"), road)
    heights = [r[4]["road_height_m"] for r in rows[1:]]
    np.testing.assert_array_equal(heights, road)
    assert rows[-1][3] and len(rows) == len(road) + 1
    actions = np.diff(road, prepend=0.0) / STEP
    assert np.abs(actions).max() <= 1.0
    env = make(reference="linear")
    env.reset(seed=0)
    driven = [env.step(np.array([a], np.float32))[4]["road_height_m"] for a in actions]
    np.testing.assert_allclose(driven, road, atol=1e-8)


@pytest.mark.parametrize(
    "bad, match",
    [
        (np.array([0.0, np.inf]), "not finite"),
        (np.array([0.05, 0.1, 0.15, 0.2]), "max_road_height_m"),
        (np.array([0.0, 0.06]), "max_road_step_m"),
    ],
)
def test_roads_beyond_the_limits_are_refused(bad, match):
    with pytest.raises(RigError, match=match):
        make().reset(options={"excitation": bad})


def test_replay_ignores_the_actions():
    road = excitation.bump(0.7, 0.08, 8.0, DT, 0.02, 0.1)
    env = make()
    env.reset(options={"excitation": road})
    a = [env.step(np.ones(1, np.float32))[4]["force_radial_model_n"] for _ in road]
    env.reset(options={"excitation": road})
    b = [env.step(-np.ones(1, np.float32))[4]["force_radial_model_n"] for _ in road]
    assert a == b


# ----- physics ------------------------------------------------------------------------------------
def linear_quarter_car(p: CarParameters):
    """The env's car linearised about ride height: M q'' + C q' + K q = k_t J_w road, with
    q = (y_chassis, X, Y, theta) of the chassis and the unsprung body's centre of mass."""
    a_m, a_w = p.mount * p.L - p.x_cm, p.L - p.x_cm
    J_r = np.array([-1.0, 0, 1, -p.x_cm])  # radial bushing: inner end minus chassis, vertical
    J_a = np.array([0.0, 1, 0, 0])  # axial bushing: inner end horizontal
    J_c = np.array([-1.0, 0, 1, a_m])  # coil-over compression rate (mount minus top)
    J_w = np.array([0.0, 0, 1, a_w])  # wheel centre vertical
    kr, cr = TABLE1["radial"]["k_n_per_m"], TABLE1["radial"]["c_ns_per_m"]
    ka, ca = TABLE1["axial"]["k_n_per_m"], TABLE1["axial"]["c_ns_per_m"]
    K = kr * np.outer(J_r, J_r) + ka * np.outer(J_a, J_a) + p.k_s * np.outer(J_c, J_c)
    K += p.k_t * np.outer(J_w, J_w)
    C = cr * np.outer(J_r, J_r) + ca * np.outer(J_a, J_a) + p.c_s * np.outer(J_c, J_c)
    M = np.diag([p.m_s, p.m_u, p.m_u, p.i_u])
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((4, 4)), np.eye(4)], [-Minv @ K, -Minv @ C]])
    B = np.concatenate([np.zeros(4), Minv @ (p.k_t * J_w)])[:, None]
    return A, B, J_r, J_w, kr, cr


def test_linear_model_matches_the_linear_quarter_car_ode_within_2_percent():
    """A 20 mm, 400 mm bump at 30 km/h (small enough for the linearisation): chassis, wheel and
    radial bushing force of the pymunk car against the exact solution of the linear ODE for the
    same piecewise-linear road, within 2 % of each signal's peak."""
    road = excitation.bump(0.4, 0.02, 30 / 3.6, DT, 0.02, 0.6)
    env = make(reference="linear")
    rows = replay(env, road)[1:]
    p = env.unwrapped.params
    A, B, J_r, J_w, kr, cr = linear_quarter_car(p)
    t = np.arange(len(road) + 1) * DT
    u = np.concatenate([[0.0], road])
    _, _, states = signal.lsim((A, B, np.eye(8), np.zeros((8, 1))), u, t, interp=True)
    q, qd = states[1:, :4], states[1:, 4:]
    exact = {
        "chassis_y_m": q[:, 0],
        "wheel_y_m": q @ J_w,
        # the model's force is sampled at the start of each step (the state the last step left)
        "force_radial_model_n": np.concatenate([[0.0], (kr * q @ J_r + cr * qd @ J_r)[:-1]]),
    }
    for key, want in exact.items():
        got = np.array([r[4][key] for r in rows])
        err = np.abs(got - want).max() / np.abs(want).max()
        assert err < 0.02, (key, err)


def test_linear_model_stays_bounded_and_settles_under_the_worst_admissible_roads():
    """The coupling margin for the linear model: every admissible road at the rate limit
    (squares through the wheel-hop resonance, bang-bang) leaves all states finite and bounded
    even with the physical bounds switched off (the car may be thrown metres high and the arm
    swing over: a different equilibrium, never a numerical blow-up); and where the suspension
    stayed within its travel the car settles once the road is flat again (last 0.5 s below 1 %
    of the peak)."""
    roads = worst_roads(600, np.random.default_rng(0))
    out = QuarterCarBatch(roads.shape[1], with_reference=False, **LOOSE).simulate(roads)
    assert not out["diverged"].any()
    for key in ("chassis_y_m", "wheel_y_m", "force_radial_model_n", "force_axial_model_n"):
        assert np.isfinite(out[key]).all(), key
    assert np.abs(out["chassis_y_m"]).max() < 10.0
    travel = np.abs(out["wheel_y_m"] - out["chassis_y_m"]).max(axis=0)
    calm = travel < 0.12
    assert calm.sum() >= 10
    for key in ("chassis_y_m", "force_radial_model_n", "force_axial_model_n"):
        x = out[key][:, calm]
        assert (np.abs(x[-100:]).max(axis=0) < 0.01 * np.abs(x).max(axis=0)).all(), key
    # and the pymunk car itself on three of the roads
    for j in np.flatnonzero(calm)[:3]:
        rows = replay(make(reference="linear", **LOOSE), roads[:, j])
        assert not any(r[2] for r in rows)
        f = np.array([r[4]["force_radial_model_n"] for r in rows])
        assert np.isfinite(f).all() and np.abs(f[-100:]).max() < 0.01 * np.abs(f).max()


def test_reference_twin_stays_bounded_under_the_worst_admissible_roads():
    roads = worst_roads(600, np.random.default_rng(1))
    out = QuarterCarBatch(roads.shape[1], with_reference=True, **LOOSE).simulate(roads)
    assert not out["physical_limit"].any()
    for key in ("reference_chassis_y_m", "force_radial_reference_n", "force_axial_reference_n"):
        assert np.isfinite(out[key]).all(), key
    assert np.abs(out["reference_chassis_y_m"]).max() < 10.0
    travel = np.abs(out["reference_wheel_y_m"] - out["reference_chassis_y_m"]).max(axis=0)
    calm = travel < 0.12
    assert calm.sum() >= 10
    for key in ("reference_chassis_y_m", "force_radial_reference_n"):
        x = out[key][:, calm]
        assert (np.abs(x[-100:]).max(axis=0) < 0.05 * np.abs(x).max(axis=0)).all(), key


def test_a_model_without_velocity_input_is_not_destabilised_by_the_coupling():
    """A NARX network sees only displacements, so its damping comes from x_k - x_k-1, half a
    sample late. The same Kelvin-Voigt written that way settles after the papers' bump just
    like the linear model: a sustained oscillation of a network here is the network's own."""
    road = excitation.bump(0.4, 0.1, 30 / 3.6, DT, 0.3, 1.5)
    diff = {a: DiffKV(TABLE1[a]["k_n_per_m"], TABLE1[a]["c_ns_per_m"]) for a in TABLE1}
    tails = {}
    for name, model in (("linear", "linear"), ("diff", diff)):
        rows = replay(make(model=model, reference="linear"), road)
        f = np.array([r[4]["force_radial_model_n"] for r in rows])
        assert not rows[-1][2]
        tails[name] = np.abs(f[-100:]).max() / np.abs(f).max()
    assert tails["diff"] < 0.02 and tails["linear"] < 0.02


# ----- episode end --------------------------------------------------------------------------------
def test_model_returning_nan_terminates_with_info_saying_so():
    model = {"radial": NanAfter(after=5, k=1.5e6), "axial": get_model("linear", "axial")}
    env = make(model=model)
    env.reset(seed=0)
    for k in range(20):  # noqa: B007
        obs, r, term, trunc, info = env.step(np.array([0.5], np.float32))
        if term:
            break
    assert term and k == 5 and info["diverged"]
    assert "not finite" in info["divergence_reason"]
    assert env.observation_space.contains(obs) and r == 10.0


def test_model_raising_terminates_instead_of_crashing():
    model = {"radial": RaisesAfter(after=3, k=1.5e6), "axial": get_model("linear", "axial")}
    env = make(model=model)
    env.reset(seed=0)
    for _ in range(20):
        *_, term, _, info = env.step(np.array([0.5], np.float32))
        if term:
            break
    assert term and "test double gave up" in info["divergence_reason"]


def test_model_car_beyond_its_bounds_terminates_while_the_twin_is_fine():
    soft = {"radial": LinearBushing(1e3, 10.0), "axial": get_model("linear", "axial")}
    env = make(model=soft, reference="linear")
    env.reset(seed=0)
    for k in range(200):
        a = 0.5 if k < 4 else 0.0  # a 100 mm ramp, then hold
        *_, term, trunc, info = env.step(np.array([a], np.float32))
        if term or trunc:
            break
    assert term and info["diverged"] and "deflection" in info["model_out_of_bounds"]
    assert info["reference_out_of_bounds"] == ""


def reference_keys(info):
    return [k for k in info if k.startswith("reference_") or k.endswith("_reference_n")]


@pytest.mark.parametrize("value", [1e300, -3e4], ids=["1e300", "-30kN"])
def test_model_force_beyond_the_limit_is_judged_before_it_is_applied(value):
    """The verdict names the force and the limit; the force never reaches the model car (its
    state stays finite) nor the twin, which moves exactly as beside a linear model car."""
    acts = [np.array([a], np.float32) for a in (0.01, -0.01, 0.01, -0.01) + (0.005,) * 40]
    beside = make(model="linear")
    beside.reset(seed=0)
    expected = [beside.step(a)[4] for a in acts]
    env = make(model={"radial": ValueAfter(after=3, value=value), "axial": "linear"})
    env.reset(seed=0)
    for k, a in enumerate(acts):
        obs, r, term, trunc, info = env.step(a)
        assert term == (k >= 3) and not trunc and info["diverged"] == (k >= 3)
        for key in reference_keys(info):
            assert info[key] == expected[k][key], key
        assert all(math.isfinite(info[key]) for key in ("chassis_y_m", "wheel_y_m"))
        assert env.observation_space.contains(obs)
    assert (
        info["divergence_reason"] == f"|radial bushing force| = {abs(value):.6g} N exceeds 25000 N"
    )
    assert info["reference_out_of_bounds"] == "" and not info["physical_limit"]


def test_model_cars_blow_up_cannot_reach_the_twin():
    """With the force limit off, a 1e300 N model force is applied: the model car's state turns
    non-finite, and the twin (in its own pymunk space) still moves exactly as beside a linear
    model car."""
    acts = [np.array([a], np.float32) for a in (0.01, -0.01, 0.01, -0.01, 0.005, 0.005)]
    beside = make(model="linear", force_limit_n=1e301)
    beside.reset(seed=0)
    expected = [beside.step(a)[4] for a in acts]
    env = make(
        model={"radial": ValueAfter(after=3, value=1e300), "axial": "linear"}, force_limit_n=1e301
    )
    env.reset(seed=0)
    for k, a in enumerate(acts):
        *_, term, trunc, info = env.step(a)
        for key in reference_keys(info):
            assert info[key] == expected[k][key], key
    assert term and not trunc and info["diverged"]
    assert not math.isfinite(info["chassis_y_m"] + info["wheel_y_m"])


@pytest.mark.parametrize(
    "error", [ZeroDivisionError("k / 0"), FloatingPointError("overflow"), OverflowError("range")]
)
def test_model_raising_an_arithmetic_error_terminates_with_its_name(error):
    env = make(model={"radial": ValueAfter(after=3, error=error), "axial": "linear"})
    env.reset(seed=0)
    outs = [env.step(np.array([0.01], np.float32)) for _ in range(4)]
    assert not any(o[2] for o in outs[:3])
    _, _, term, trunc, info = outs[3]
    assert term and not trunc and info["diverged"]
    assert info["divergence_reason"] == f"model raised {type(error).__name__}: {error}"


def test_a_model_bug_ends_the_episode_as_a_model_error_not_a_divergence():
    env = make(model={"radial": Buggy(after=3), "axial": "linear"})
    env.reset(seed=0)
    outs = [env.step(np.array([0.01], np.float32)) for _ in range(4)]
    assert not any(o[2] for o in outs[:3]) and all(o[4]["model_error"] == "" for o in outs[:3])
    _, _, term, _, info = outs[3]
    assert term and not info["diverged"] and "broadcast" in info["model_error"]


def test_bad_actions_options_and_roads_are_refused_naming_them():
    env = make().unwrapped  # Gymnasium's checker wrapper trips over a first call that raised
    with pytest.raises(RigError, match=r"^QuarterCar-v0: reset options must be a dict"):
        env.reset(options=5)
    with pytest.raises(RigError, match=r"^road excitation must be numbers"):
        env.reset(options={"excitation": "abc"})
    env.reset(seed=0)
    env.step(np.array([0.1], np.float32))
    with pytest.raises(RigError, match=r"^QuarterCar-v0: action .* shape \(1,\)"):
        env.step(np.array([0.1, 0.2], np.float32))
    with pytest.raises(RigError, match=r"^QuarterCar-v0: action <str 'up'>"):
        env.step("up")
    assert env.step(np.array([0.1], np.float32))[4]["step"] == 2


def test_a_road_too_harsh_for_the_reference_car_truncates_without_a_verdict():
    env = make(reference="linear")
    env.reset(seed=0)
    for k in range(400):
        a = 1.0 if (k // 9) % 2 == 0 else -1.0  # squares near wheel hop
        *_, term, trunc, info = env.step(np.array([a], np.float32))
        if term or trunc:
            break
    assert trunc and not term and info["physical_limit"] and not info["diverged"]


def test_divergence_monitor_and_reward_hooks():
    env = make(
        divergence_monitor=lambda info: "chassis up" if info["chassis_y_m"] > 0.01 else None,
        reward_fn=lambda info: info["chassis_y_m"],
    )
    env.reset(seed=0)
    for _ in range(100):
        _, r, term, _, info = env.step(np.array([1.0], np.float32))
        assert r == info["chassis_y_m"]
        if term:
            break
    assert term and info["divergence_reason"] == "chassis up" and info["monitor_verdict"]


def test_episode_truncates_after_episode_steps():
    env = make(max_episode_steps=12)
    env.reset(seed=0)
    flags = [env.step(np.zeros(1, np.float32))[3] for _ in range(12)]
    assert flags == [False] * 11 + [True]


def test_memory_stays_flat_over_a_long_rollout():
    env = make(max_episode_steps=-1, render_mode="rgb_array")
    env.reset(seed=0)
    acts = [np.array([v], np.float32) for v in (0.3, 0.3, -0.3, -0.3)]
    for i in range(300):
        env.step(acts[i % 4])
    tracemalloc.start()
    before = tracemalloc.take_snapshot()
    for i in range(1500):
        env.step(acts[i % 4])
    after = tracemalloc.take_snapshot()
    tracemalloc.stop()
    assert sum(s.size_diff for s in after.compare_to(before, "filename")) < 64 * 1024


@pytest.mark.slow
def test_memory_stays_flat_over_a_hundred_thousand_steps():
    env = make(max_episode_steps=-1)
    env.reset(seed=0)
    acts = [np.array([v], np.float32) for v in (0.3, 0.3, -0.3, -0.3)]
    tracemalloc.start()
    before = None
    for i in range(100_000):
        env.step(acts[i % 4])
        if i == 2000:
            before = tracemalloc.take_snapshot()
    after = tracemalloc.take_snapshot()
    tracemalloc.stop()
    assert sum(s.size_diff for s in after.compare_to(before, "filename")) < 64 * 1024


def test_rgb_array_frame_shows_both_cars_and_changes_with_the_road():
    env = make(render_mode="rgb_array")
    env.reset(seed=0)
    first = env.render()
    assert first.shape == (400, 600, 3) and first.dtype == np.uint8
    for _ in range(4):
        env.step(np.ones(1, np.float32))
    second = env.render()
    assert (first != second).any(axis=2).sum() > 500


def test_sync_vector_env_works():
    env = gym.make_vec("QuarterCar-v0", num_envs=2, vectorization_mode="sync")
    obs, _ = env.reset(seed=0)
    obs, r, term, trunc, info = env.step(np.ones((2, 1), np.float32))
    assert obs.shape == (2, 12) and r.shape == (2,)
