"""The environments (BushRig-v0, its vector form, QuarterCar-v0) on bad input: bad arguments are
refused naming them, non-finite and huge model forces end the episode with a verdict, stepping
on after the end never raises, and memory stays flat over long rollouts.

tests/rigs/ already covers NaN/inf/huge actions (hypothesis), a model returning NaN or raising
a ModelError, replayed excitations beyond the limits and memory over 5e3/1e6 steps; this file
adds what those do not try. The defects it found (non-numeric and wrong-shape actions, options
that are not a dict, text excitations, arithmetic errors from a model, a quarter-car model force
beyond the limit reaching the twin) are fixed; their tests close the file. The catalogue is
docs/bad-inputs.md.
"""

from __future__ import annotations

import math
import tracemalloc

import gymnasium as gym
import numpy as np
import pytest

import bushenv  # noqa: F401  (registers the envs)
from bushenv.judge import JudgeError
from bushenv.models import ModelError
from bushenv.models.base import PAPER_DT, BushingModel
from bushenv.models.linear import LinearBushing
from bushenv.rigs.common import RigError


class BadAfter(BushingModel):
    """Test double: a spring k x for ``after`` samples, then ``value`` (or raises ``error``)."""

    name = ""  # test-only, not registered
    param_names = ()

    def __init__(self, after=3, value=math.nan, error=None, k=1.0e5, dt=PAPER_DT):
        self.after, self.value, self.error, self.k = int(after), value, error, float(k)
        super().__init__(dt)

    @property
    def n_state(self) -> int:
        return 1

    def _advance(self, x, v, out):
        for t in range(x.shape[0]):
            self.state[0] += 1
            if self.state[0, 0] > self.after:
                if self.error is not None:
                    raise self.error
                out[t] = self.value
            else:
                out[t] = self.k * x[t]

    def copy(self):
        return BadAfter(self.after, self.value, self.error, self.k, self.dt)


def skip_slow_unless_asked(request) -> None:
    if "slow" not in (request.config.getoption("-m") or ""):
        pytest.skip("slow test; run with -m slow")


def rig(**kwargs):
    return gym.make("BushRig-v0", **kwargs)


def push(env, steps, a=0.3):
    """Step ``steps`` times with +-a (a triangle wave); returns the outcomes."""
    plus, minus = np.array([a], np.float32), np.array([-a], np.float32)
    return [env.step(plus if (i // 4) % 2 else minus) for i in range(steps)]


# ----- arguments ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"dt_s": 0}, RigError, "dt_s must be a positive finite number, got 0"),
        ({"dt_s": math.nan}, RigError, "dt_s must be a positive finite number, got nan"),
        ({"episode_steps": 100}, RigError, "episode_steps: the episode length is Gymnasium's"),
        ({"history": -1}, RigError, "history must be a positive integer, got -1"),
        ({"physics_substeps": 0}, RigError, "physics_substeps must be a positive integer"),
        ({"force_limit_n": math.inf}, RigError, "force_limit_n must be a positive finite"),
        ({"max_displacement_m": -1}, RigError, "max_displacement_m must be a positive"),
        ({"axis": "up"}, RigError, "axis must be one of ('axial', 'radial'), got 'up'"),
        ({"model": "lstm"}, ModelError, "unknown model 'lstm'"),
        ({"reward_fn": 5}, RigError, "reward_fn must be callable(info) or None, got 5"),
        pytest.param(
            {"render_mode": "3d"},
            RigError,
            "render_mode must be one of",
            marks=pytest.mark.filterwarnings("ignore:.*render_mode"),
        ),
        ({"force_scale_n": {"axial": "big"}}, RigError, "force_scale_n[axial] must be a number"),
    ],
    ids=lambda v: str(v)[:30] if isinstance(v, dict) else None,
)
def test_bushrig_refuses_bad_arguments_naming_them(kwargs, error, message):
    with pytest.raises(error) as info:
        rig(**kwargs)
    assert message in str(info.value)


def test_bushrig_refuses_a_model_file_of_another_sample_time(tmp_path):
    path = LinearBushing.preset("axial", dt=1e-3).save(tmp_path / "fast.npz")
    with pytest.raises(ModelError, match=r"fast\.npz: model sampled at 1000 Hz.*expected 204\.8"):
        rig(model=str(path))


def test_bushrig_refuses_a_png_given_as_model(tmp_path):
    png = tmp_path / "model.png"
    png.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR")
    with pytest.raises(ModelError, match=r"model\.png: not a bushenv model file: a PNG image"):
        rig(model=str(png))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"model": "lstm"}, "unknown model 'lstm'"),
        ({"model": {"radial": "linear"}}, "needs exactly the keys"),
        ({"dt_s": -1}, "dt_s must be a positive finite number"),
        ({"bogus": 1}, "unknown argument(s) ['bogus']"),
    ],
    ids=["unknown-model", "one-axis-only", "negative-dt", "unknown-argument"],
)
def test_quartercar_refuses_bad_arguments_naming_them(kwargs, message):
    with pytest.raises(ValueError) as info:  # RigError and ModelError are ValueErrors
        gym.make("QuarterCar-v0", **kwargs)
    assert message in str(info.value)


# ----- the model misbehaves ----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("value", "reason"),
    [
        (math.inf, "model force is not finite"),
        (-math.inf, "model force is not finite"),
        (1e300, "|F_model| = 1e+300 N exceeds 25000 N"),
    ],
)
def test_bushrig_model_force_infinite_or_huge_terminates_with_its_reason(value, reason):
    env = rig(model=BadAfter(after=3, value=value), reference="linear")
    env.reset(seed=0)
    outcomes = push(env, 10)
    ends = [i for i, (_, _, term, _, _) in enumerate(outcomes) if term]
    assert ends and ends[0] == 3  # the fourth step is the first bad force
    obs, reward, term, trunc, info = outcomes[3]
    assert info["diverged"] and info["divergence_reason"] == reason
    assert env.observation_space.contains(obs) and reward == 10.0


def test_bushrig_stepping_on_after_a_nan_verdict_never_raises():
    env = rig(model=BadAfter(after=3), reference="rubber")
    env.reset(seed=0)
    for obs, reward, term, _, info in push(env, 200)[3:]:
        assert term and info["diverged"]
        assert env.observation_space.contains(obs)
        assert reward == 10.0
        assert info["divergence_reason"] == "model force is not finite"


def test_bushrig_reference_returning_nan_truncates_without_blaming_the_model():
    # such a reference fails its vetting (its holds are not finite): refused by default
    with pytest.raises(JudgeError, match="cannot judge|failed its vetting"):
        rig(model="linear", reference=BadAfter(after=3))
    env = rig(model="linear", reference=BadAfter(after=3), trust_reference=True)
    env.reset(seed=0)
    _, _, term, trunc, info = push(env, 4)[3]
    assert trunc and not term
    assert info["machine_limit"] and not info["diverged"]


def test_quartercar_model_force_infinite_terminates_with_its_reason():
    env = gym.make(
        "QuarterCar-v0", model={"radial": BadAfter(after=3, value=math.inf), "axial": "linear"}
    )
    env.reset(seed=0)
    outcomes = push(env, 6, a=0.01)
    obs, _, term, _, info = outcomes[3]
    assert term and info["diverged"]
    assert "not finite" in info["divergence_reason"]
    assert env.observation_space.contains(obs)


# ----- vector env --------------------------------------------------------------------------------
def test_vector_env_cleans_nan_inf_and_huge_actions_like_the_single_env():
    actions = np.array([[np.nan], [np.inf], [-np.inf], [1e30], [-0.25]], dtype=np.float32)
    venv = gym.make_vec("BushRig-v0", num_envs=5, vectorization_mode="vector_entry_point")
    venv.reset(seed=0)
    _, rewards, term, trunc, info = venv.step(actions)
    for i, a in enumerate(actions):
        env = rig()
        env.reset(seed=0)
        _, r, *_, single = env.step(a)
        assert info["displacement_m"][i] == single["displacement_m"]
        assert rewards[i] == r
    assert not term.any() and not trunc.any()
    assert venv.single_observation_space.contains(venv.step(actions)[0][0])


# ----- long runs ---------------------------------------------------------------------------------
def memory_growth(step, steps: int, warmup: int = 2000) -> int:
    """Bytes allocated and still held after ``steps`` calls of ``step(i)`` (after a warm-up)."""
    for i in range(warmup):
        step(i)
    tracemalloc.start()
    try:
        before = tracemalloc.take_snapshot()
        for i in range(steps):
            step(i)
        after = tracemalloc.take_snapshot()
    finally:
        tracemalloc.stop()
    return sum(s.size_diff for s in after.compare_to(before, "filename"))


def test_bushrig_memory_stays_flat_over_5e4_steps():
    env = rig(model="linear", reference="rubber", max_episode_steps=-1)
    env.reset(seed=0)
    plus, minus = np.array([0.3], np.float32), np.array([-0.3], np.float32)
    grown = memory_growth(lambda i: env.step(plus if (i // 4) % 2 else minus), 50_000)
    assert grown < 64 * 1024


def test_bushrig_memory_stays_flat_over_2e4_steps_after_a_nan_verdict():
    env = rig(model=BadAfter(after=10), reference="linear", max_episode_steps=-1)
    env.reset(seed=0)
    a = np.array([0.3], np.float32)
    grown = memory_growth(lambda i: env.step(a if (i // 4) % 2 else -a), 20_000)
    assert grown < 64 * 1024


def test_vector_env_memory_stays_flat_over_5e3_steps():
    venv = gym.make_vec(
        "BushRig-v0", num_envs=4, vectorization_mode="vector_entry_point", max_episode_steps=500
    )
    venv.reset(seed=0)  # 500-step episodes: autoreset happens 10 times in the run
    a = np.full((4, 1), 0.3, np.float32)
    grown = memory_growth(lambda i: venv.step(a if (i // 4) % 2 else -a), 5_000, warmup=500)
    assert grown < 64 * 1024


@pytest.mark.slow
def test_vector_env_memory_stays_flat_over_1e6_steps(request):
    skip_slow_unless_asked(request)
    venv = gym.make_vec(
        "BushRig-v0", num_envs=4, vectorization_mode="vector_entry_point", max_episode_steps=2048
    )
    venv.reset(seed=0)
    a = np.full((4, 1), 0.3, np.float32)
    grown = memory_growth(lambda i: venv.step(a if (i // 4) % 2 else -a), 10**6)
    assert grown < 64 * 1024


# ----- defects found here, since fixed in bushenv/rigs (were xfail) -----------------------------
@pytest.mark.parametrize("action", [None, "abc", np.array([]), 1 + 2j], ids=repr)
def test_non_numeric_action_is_refused_with_a_rig_error_naming_the_action_space(action):
    env = rig()
    env.reset(seed=0)
    with pytest.raises(RigError, match="action"):
        env.step(action)


def test_action_of_the_wrong_shape_is_refused():
    env = rig()
    env.reset(seed=0)
    with pytest.raises(RigError, match="shape"):
        env.step(np.array([0.1, 0.9, -0.9], np.float32))


def test_vector_env_action_of_the_wrong_shape_is_refused_naming_the_expected_shape():
    venv = gym.make_vec("BushRig-v0", num_envs=3, vectorization_mode="vector_entry_point")
    venv.reset(seed=0)
    with pytest.raises(RigError, match=r"\(3, 1\)"):
        venv.step(np.zeros((2, 1), np.float32))


def test_reset_options_that_are_not_a_dict_are_refused():
    with pytest.raises(RigError, match="options"):
        rig().reset(options=5)


def test_text_excitation_is_refused_with_a_rig_error():
    with pytest.raises(RigError, match="excitation"):
        rig().reset(options={"excitation": "abc"})


@pytest.mark.parametrize("error", [ZeroDivisionError("k/0"), FloatingPointError("overflow")])
def test_model_raising_an_arithmetic_error_ends_the_episode(error):
    env = rig(model=BadAfter(after=3, error=error))
    env.reset(seed=0)
    _, _, term, _, info = push(env, 4)[3]
    assert term and info["diverged"] and type(error).__name__ in info["divergence_reason"]


def test_quartercar_model_force_beyond_the_limit_is_a_verdict_not_a_harsh_road():
    env = gym.make(
        "QuarterCar-v0", model={"radial": BadAfter(after=3, value=1e300), "axial": "linear"}
    )
    env.reset(seed=0)
    _, _, term, trunc, info = push(env, 4, a=0.01)[3]
    assert term and info["diverged"]
    assert math.isfinite(info["force_radial_reference_n"])
