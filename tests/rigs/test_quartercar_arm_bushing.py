"""QuarterCar-v0 with one planar (three-axis) bushing carrying the control arm's loads."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from bushenv.models.linear import TABLE1
from bushenv.models.planar_linear import PlanarLinear
from bushenv.rigs.common import RigError

STEP = 0.05  # max_road_step_m of the spec


def make(**kw):
    return gym.make("QuarterCar-v0", **kw)


def road(T=500, seed=0):
    """A rough road within the rate limit, then held: bumps of a few cm."""
    rng = np.random.default_rng(seed)
    a = np.clip(rng.normal(0, 0.25, T), -1, 1)
    a[T // 2 :] = 0.0
    return np.clip(np.cumsum(a) * STEP * 0.2, -0.05, 0.05)


def replay(env, h):
    env.reset(seed=0, options={"excitation": h})
    rows = []
    while True:
        rows.append(env.step(np.zeros(1, np.float32)))
        if rows[-1][2] or rows[-1][3]:
            return rows


def diagonal_linear3(k_rot=0.0, c_rot=0.0):
    """Table 1 on the diagonal: axial and radial as the one-axis linear bushings."""
    k = np.diag([TABLE1["axial"]["k_n_per_m"], TABLE1["radial"]["k_n_per_m"], k_rot])
    c = np.diag([TABLE1["axial"]["c_ns_per_m"], TABLE1["radial"]["c_ns_per_m"], c_rot])
    return PlanarLinear(k, c)


@pytest.mark.parametrize("arm", ["linear", "reference"])
def test_env_checkers_of_gymnasium_and_sb3_pass_with_a_planar_arm_bushing(arm):
    env = make(arm_bushing=arm).unwrapped
    gym_check_env(env, skip_render_check=True)
    sb3_check_env(env, warn=False)


def test_planar_file_is_taken_and_its_moment_reported(tmp_path):
    path = PlanarLinear.preset().save(tmp_path / "arm.npz")
    rows = replay(make(arm_bushing=str(path)), road())
    info = rows[-1][4]
    assert info["moment_model_nm"] != 0.0 and info["arm_rotation_rad"] != 0.0
    assert np.isfinite([r[4]["moment_reference_nm"] for r in rows]).all()


def test_default_has_no_planar_keys_and_an_empty_arm_bushing_is_the_default_bit_for_bit():
    h = road()
    a, b = replay(make(), h), replay(make(arm_bushing=""), h)
    assert "moment_model_nm" not in a[-1][4]
    for ra, rb in zip(a, b, strict=True):
        np.testing.assert_array_equal(ra[0], rb[0])
        assert ra[4] == rb[4]


def test_diagonal_linear3_equals_the_two_one_axis_linear_bushings():
    # no rotational stiffness: the arm hangs as on the two one-axis bushings; the only
    # difference is the rotation's in-sub-step spring, whose held remainder is exact at samples
    h = road()
    one = replay(make(model="linear", reference="linear"), h)
    three = replay(make(arm_bushing=diagonal_linear3(), arm_bushing_reference="linear"), h)
    assert len(one) == len(three)
    for key in ("force_radial_model_n", "force_axial_model_n", "chassis_y_m", "wheel_y_m"):
        x = np.array([r[4][key] for r in one])
        y = np.array([r[4][key] for r in three])
        assert np.abs(x - y).max() <= 0.01 * np.abs(x).max(), key
    assert max(abs(r[4]["moment_model_nm"]) for r in three) == 0.0


def test_pickled_mid_episode_continues_bit_for_bit():
    env = make(arm_bushing="reference")
    env.reset(seed=0)
    acts = np.random.default_rng(1).uniform(-0.3, 0.3, (120, 1)).astype(np.float32)
    for a in acts[:60]:
        env.step(a)
    copy = pickle.loads(pickle.dumps(env))
    for a in acts[60:]:
        r1, r2 = env.step(a), copy.step(a)
        np.testing.assert_array_equal(r1[0], r2[0])
        assert r1[4] == r2[4]


def test_a_model_moment_beyond_the_limit_terminates_while_the_twin_stays_within():
    coupled = diagonal_linear3(k_rot=3000.0)
    coupled.k_matrix[2, 1] = 1e8  # N m per m of radial deflection: 0.1 mm gives 10 kN m
    rows = replay(make(arm_bushing=coupled), road())
    obs, _, terminated, truncated, info = rows[-1]
    assert terminated and not truncated and info["diverged"]
    assert "bushing moment" in info["model_out_of_bounds"]


def test_an_unknown_arm_bushing_name_lists_the_planar_models():
    with pytest.raises(RigError, match="QuarterCar-v0: arm_bushing 'nope'.*three-axis: .*rubber"):
        make(arm_bushing="nope")


@pytest.mark.parametrize("arm", ["linear", "reference", "rubber-torsion"])
def test_the_coupling_keeps_linear_and_reference_stable_on_the_worst_roads_within_travel(arm):
    """DESIGN-NOTES' trap: held forces are an explicit scheme. The rate-limit square waves of
    test_quartercar (through wheel hop) and a random bang-bang road, within the car's travel
    (the arm turning up to 0.26 rad): both bushings settle to a constant, no episode ends."""
    from test_quartercar import LOOSE, worst_roads

    roads = worst_roads(600, np.random.default_rng(0))
    loose = dict(LOOSE, arm_moment_limit_nm=1e12)
    for j in (3, 8, 11, 15):  # travel 17-120 mm (measured): the bound is 120 mm
        rows = replay(make(arm_bushing=arm, arm_bushing_reference=arm, **loose), roads[:, j])
        assert not any(r[2] for r in rows) and len(rows) == roads.shape[0]
        assert max(abs(r[4]["suspension_travel_m"]) for r in rows) < 0.125  # about the bound
        for key in ("force_radial_model_n", "force_axial_model_n", "moment_model_nm"):
            x = np.array([r[4][key] for r in rows])
            assert np.isfinite(x).all() and np.ptp(x[-100:]) < 0.01 * np.abs(x).max(), key


def test_info_says_when_the_reference_arm_bushing_judges_beyond_its_calibrated_rotation():
    """The coupled reference is calibrated to +-0.15 rad; the arm turns further on harsh roads
    (up to 0.26 rad on these): info names the steps its forces are an extrapolation."""
    from test_quartercar import LOOSE, worst_roads

    from bushenv.reference.planar import MAX_ROTATION_RAD

    roads = worst_roads(600, np.random.default_rng(0))
    loose = dict(LOOSE, arm_moment_limit_nm=1e12)
    rows = replay(make(arm_bushing="linear", arm_bushing_reference="reference", **loose),
                  roads[:, 15])  # fmt: skip
    theta = np.array([r[4]["reference_arm_rotation_rad"] for r in rows])
    said = np.array([bool(r[4]["reference_outside_range"]) for r in rows])
    assert np.abs(theta).max() > MAX_ROTATION_RAD  # the road takes the arm beyond the range
    np.testing.assert_array_equal(said, np.abs(theta) > MAX_ROTATION_RAD)
    first = next(r[4]["reference_outside_range"] for r in rows if r[4]["reference_outside_range"])
    assert "calibrated +-0.15 rad" in first and "extrapolation" in first
    lin = replay(make(arm_bushing="linear", arm_bushing_reference="linear", **loose), roads[:, 15])
    assert not any(r[4]["reference_outside_range"] for r in lin)  # a law with no stated range


def test_the_default_twin_is_the_torsion_preset_and_judges_within_its_range():
    """The arm turns its pivot's bush about the bush's own axis: the twin is the torsion
    preset (+-0.442 rad), so on the worst roads within travel it judges inside its range,
    where the tilt preset (+-0.15 rad) extrapolates."""
    from test_quartercar import LOOSE, worst_roads

    env = make(arm_bushing="linear")
    assert env.unwrapped.params.reference_name == "planar rubber-torsion"
    roads = worst_roads(600, np.random.default_rng(0))
    loose = dict(LOOSE, arm_moment_limit_nm=1e12)
    rows = replay(make(arm_bushing="linear", **loose), roads[:, 15])
    theta = np.abs([r[4]["reference_arm_rotation_rad"] for r in rows])
    assert 0.15 < theta.max() < 0.442  # beyond the tilt's range, within the torsion's
    assert not any(r[4]["reference_outside_range"] for r in rows)
