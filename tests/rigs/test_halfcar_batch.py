"""HalfCarBatch: the half car as arrays, cross-checked against the pymunk HalfCar-v0."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import bushenv  # noqa: F401  (registers the ids)
from bushenv.rigs.common import RigError
from bushenv.rigs.halfcar_batch import HalfCarBatch
from bushenv.rigs.halfcar_batch_outputs import RESULT_KEYS
from bushenv.rigs.halfcar_params import POSITIONS

DT = 1.0 / 204.8
# the batch against the env: every compared output within this fraction of its own peak
# (measured on the manoeuvre below: 3.3e-3 at most, a radial bushing force; docs/envs.md)
AGREEMENT = 0.01
LOADS = ("wheel_load_left_n", "wheel_load_right_n")
MOTION = ("roll_rad", "roll_rate_rad_per_s", "body_y_m", "camber_left_rad", "travel_right_m",
          "track_change_m")  # fmt: skip
BUSHINGS = tuple(
    f"{'moment' if c == 'moment' else 'force'}_{p}{'' if c == 'moment' else '_' + c}_{r}_"
    f"{'nm' if c == 'moment' else 'n'}"
    for p in POSITIONS for c in ("axial", "radial", "moment") for r in ("model", "reference")
) + tuple(f"deflection_{p}_radial_m" for p in POSITIONS)  # fmt: skip


def manoeuvre(n=600):
    """A bump under the left wheel, a pothole under the right, then a lateral-load step and
    its release (2 m/s^2 at 0.2 m/s^2 per step: the twin's upper pivots stay within the
    reference's calibrated +-0.15 rad, which the torsion-soft car's roll overshoot passes from
    about 3 m/s^2)."""
    t = np.arange(n) * DT
    left = np.where((t > 0.2) & (t < 0.3), 0.03 * np.sin(np.pi * (t - 0.2) / 0.1), 0.0)
    right = np.where((t > 0.6) & (t < 0.65), -0.02 * np.sin(np.pi * (t - 0.6) / 0.05), 0.0)
    k = np.arange(n)
    ay = np.clip(np.minimum(0.2 * (k - 200), 0.2 * (450 - k)), 0.0, 2.0)
    return {"road_left": left, "road_right": right, "lateral_accel": ay}


def env_run(inputs, **kw):
    env = gym.make("HalfCar-v0", max_episode_steps=-1, **kw).unwrapped
    env.reset(seed=0, options=inputs)
    infos = []
    for _ in range(len(inputs["road_left"])):
        _, _, terminated, truncated, info = env.step(None)
        infos.append(info)
        assert not terminated and not info["physical_limit"]
    return {k: np.array([i[k] for i in infos]) for k in infos[0] if k in RESULT_KEYS}


@pytest.mark.parametrize(
    "kw",
    [
        {"model": "linear"},
        {"model": {"lower_left": "linear", "upper_left": "rubber", "lower_right": "rubber",
                   "upper_right": "linear"}},
    ],
)  # fmt: skip
def test_the_batch_agrees_with_the_pymunk_env_on_loads_roll_and_bushing_forces(kw):
    inputs = manoeuvre()
    env = env_run(inputs, **kw)
    out = HalfCarBatch(1, **kw).simulate(**inputs)
    assert not out["diverged"][0] and not out["physical_limit"][0]
    for k in (*LOADS, *MOTION, *BUSHINGS):
        e, b = env[k], out[k][:, 0]
        peak = np.abs(e - e[0]).max()
        assert peak > 0, k
        assert np.abs(e - b).max() <= AGREEMENT * peak, (k, np.abs(e - b).max() / peak)
    for k in ("reference_roll_rad", "reference_wheel_load_left_n", "error_n"):
        peak = np.abs(env[k] - env[k][0]).max()
        assert np.abs(env[k] - out[k][:, 0]).max() <= AGREEMENT * peak, k
    assert not out["reference_outside_range"].any()


def test_the_twin_beyond_its_calibrated_rotation_is_flagged_as_the_env_flags_it():
    """A 100 mm road rise at the rate limit: the upper arms turn past the torsion preset's
    calibrated +-0.442 rad; the env says so exactly where a twin pivot's rotation is beyond the
    preset's own range (not the cardanic 0.15 rad), and the batch's flag is the env's
    ``reference_outside_range`` being said, step by step."""
    from bushenv.reference.planar import MAX_ROTATION_RAD, TORSION_MAX_ROTATION_RAD

    road = np.minimum(0.05 * np.arange(60), 0.1)
    inputs = {"road_left": road, "road_right": road}
    env = gym.make("HalfCar-v0", max_episode_steps=-1).unwrapped
    env.reset(seed=0, options=inputs)
    said, theta = [], []
    for _ in range(60):
        info = env.step(None)[4]
        said.append(info["reference_outside_range"] != "")
        theta.append(max(abs(info[f"reference_rotation_{k}_rad"]) for k in POSITIONS))
    theta = np.array(theta)
    assert env.params.references.calibrated_rotation_rad == TORSION_MAX_ROTATION_RAD
    assert any(said) and said == list(theta > TORSION_MAX_ROTATION_RAD)
    assert np.any((theta > MAX_ROTATION_RAD) & ~np.array(said))  # beyond 0.15 rad: not flagged
    flag = HalfCarBatch(1).simulate(**inputs, keys=("reference_outside_range",))
    np.testing.assert_array_equal(flag["reference_outside_range"][:, 0].astype(bool), said)
    np.testing.assert_array_equal(HalfCarBatch(1).calibrated_rotation, TORSION_MAX_ROTATION_RAD)


def test_each_car_of_a_batch_is_the_car_alone_bit_for_bit():
    """Three different manoeuvres in one batch equal each run alone (the chunks' padding and
    the vectorised loops change nothing)."""
    base = manoeuvre(200)
    scale = np.array([1.0, 0.5, -0.7])
    inputs = {k: np.clip(v[:, None] * scale, -8.0, 8.0) for k, v in base.items()}
    together = HalfCarBatch(3, model="linear").simulate(**inputs)
    for j in range(3):
        alone = HalfCarBatch(1, model="linear").simulate(**{k: v[:, j] for k, v in inputs.items()})
        for k in ("roll_rad", "wheel_load_left_n", "force_lower_right_radial_reference_n"):
            np.testing.assert_array_equal(together[k][:, j], alone[k][:, 0], err_msg=k)


def test_two_threads_give_the_numbers_of_one():
    inputs = {k: np.repeat(v[:120, None], 40, axis=1) * np.linspace(0.2, 1, 40)
              for k, v in manoeuvre(120).items()}  # fmt: skip
    one = HalfCarBatch(40, model="linear").simulate(**inputs)
    two = HalfCarBatch(40, model="linear", threads=2).simulate(**inputs)
    for k in ("roll_rad", "wheel_load_right_n", "force_upper_left_radial_reference_n"):
        np.testing.assert_array_equal(one[k], two[k], err_msg=k)


def test_a_column_reset_returns_that_car_to_rest_and_leaves_the_others():
    batch = HalfCarBatch(2, model="linear")
    for _ in range(30):
        out = batch.step([0.02, 0.01], 0.0, [1.0, 2.0])
    batch.reset_columns(np.array([True, False]))
    fresh = HalfCarBatch(1, model="linear")
    a = batch.step([0.02, 0.01], 0.0, [1.0, 2.0])
    b = fresh.step(0.02, 0.0, 1.0)
    assert a["roll_rad"][0] == b["roll_rad"][0]
    assert a["roll_rad"][1] != 0.0 and abs(a["roll_rad"][1] - out["roll_rad"][1]) < 1e-2


def test_a_model_that_runs_away_is_the_models_divergence_and_stops_its_car():
    """A linear model with negative rotational damping: the model car leaves its bounds, its
    twin does not; the car is then held still (its outputs repeat)."""
    from bushenv.models import get_model

    model = get_model("linear", coords=3)
    model.c_matrix[2, 2] = -50 * abs(model.c_matrix[2, 2]) - 500.0
    steps = 400
    inputs = {"road_left": 0.01 * np.sin(2 * np.pi * 2 * np.arange(steps) * DT)}
    out = HalfCarBatch(1, model=model).simulate(**inputs)
    assert out["diverged"][0] and not out["physical_limit"][0]
    k = out["divergence_step"][0]
    assert 0 <= k < steps - 2
    assert out["roll_rad"][k + 1, 0] == out["roll_rad"][-1, 0]


def test_runs_repeat_exactly():
    inputs = manoeuvre(150)
    a = HalfCarBatch(2).simulate(**inputs)
    b = HalfCarBatch(2).simulate(**inputs)
    for k in RESULT_KEYS:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_bad_inputs_are_refused_naming_the_value():
    batch = HalfCarBatch(2)
    with pytest.raises(RigError, match="max_road_step_m"):
        batch.simulate(road_left=np.array([0.0, 0.06]))
    with pytest.raises(RigError, match=r"\(T, 2\)"):
        batch.simulate(road_left=np.zeros((5, 3)))
    with pytest.raises(RigError, match="differ in length"):
        batch.simulate(road_left=np.zeros(5), lateral_accel=np.zeros(6))
    with pytest.raises(RigError, match="unknown output"):
        batch.simulate(road_left=np.zeros(5), keys=("roll",))
    with pytest.raises(RigError, match="num_cars"):
        HalfCarBatch(0)
