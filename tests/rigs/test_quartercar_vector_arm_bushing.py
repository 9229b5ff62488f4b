"""QuarterCar-v0's vector entry point with a planar arm bushing: the array car follows the pymunk
env (docs/planar.md), judges the moment as it does, and keeps the vector env's conventions."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.vec_env import VecCheckNan
from test_quartercar_arm_bushing import diagonal_linear3
from test_quartercar_vector import bump_then_rough_road, make_vec

from bushenv import excitation
from bushenv.models.planar_hybrid_bw import PlanarBoucWenHybrid
from bushenv.models.planar_linear import PlanarLinear
from bushenv.rigs.quartercar_batch import QuarterCarBatch
from bushenv.rigs.quartercar_vector import QuarterCarVectorEnv
from bushenv.rigs.sb3 import make_sb3_vec_env

DT = 1.0 / 204.8
# of each signal's peak over the episode; measured at most 0.10 % (docs/planar.md). Dropping
# the rotary spring, flipping its sign or the rotation's, or dropping its damper from the
# implicit solve gave 1.6-300 % (or a different episode end).
PEAK_TOLERANCE = 0.01
OBS_TOLERANCE = 0.005
SIGNALS = (
    "chassis_y_m",
    "wheel_y_m",
    "wheel_vy_m_per_s",
    "radial_deflection_m",
    "axial_deflection_m",
    "force_radial_model_n",
    "force_axial_model_n",
    "moment_model_nm",
    "arm_rotation_rad",
    "reference_chassis_y_m",
    "force_radial_reference_n",
    "force_axial_reference_n",
    "moment_reference_nm",
    "reference_arm_rotation_rad",
    "error_n",
)
PLANAR_KEYS = (
    "arm_rotation_rad",
    "reference_arm_rotation_rad",
    "reference_outside_range",
    "moment_model_nm",
    "moment_reference_nm",
)


def pothole():
    return -excitation.bump(0.3, 0.06, 20 / 3.6, DT, pre_s=0.2, post_s=0.8)


def run_both(road, n=2, **kw):
    """The pymunk env and every column of the vector env replaying ``road`` (T,) to the end of
    either's episode."""
    env, venv = gym.make("QuarterCar-v0", **kw), make_vec(n, **kw)
    env.reset(seed=0, options={"excitation": road})
    venv.reset(seed=0, options={"excitation": road})
    single, vector = [], []
    for _ in range(len(road)):
        single.append(env.step(np.zeros(1, np.float32)))
        vector.append(venv.step(np.zeros((n, 1), np.float32)))
        if single[-1][2] or single[-1][3] or vector[-1][2].any() or vector[-1][3].any():
            break
    return single, vector


@pytest.mark.parametrize("road", ["bump_then_rough", "pothole"])
@pytest.mark.parametrize("arm", ["linear", "reference"])
def test_a_column_follows_the_pymunk_env_with_a_planar_arm_bushing(arm, road):
    road = bump_then_rough_road() if road == "bump_then_rough" else pothole()
    single, vector = run_both(road, arm_bushing=arm)
    assert len(single) == len(road)  # both run the whole road
    s = np.array([[out[4][k] for k in SIGNALS] for out in single])
    v = np.array([[out[4][k][0] for k in SIGNALS] for out in vector])
    peak = np.abs(s).max(axis=0)
    zero = peak == 0.0  # error_n when model and twin are one law
    assert not zero[:-1].any() and (v[:, zero] == 0.0).all()
    errors = dict(zip(SIGNALS, np.abs(s - v).max(axis=0) / np.where(zero, 1.0, peak), strict=True))
    assert max(errors.values()) < PEAK_TOLERANCE, errors
    obs = np.abs(np.array([o[0] for o in single]) - np.array([o[0][0] for o in vector]))
    assert obs.max() < OBS_TOLERANCE
    assert [o[3] for o in single] == [o[3][0] for o in vector]  # both end with the road only
    assert not any(o[2] for o in single) and not any(o[2].any() for o in vector)


def test_make_vec_gives_the_single_envs_planar_info_keys_as_arrays():
    venv = make_vec(3, arm_bushing="reference")
    assert isinstance(venv.unwrapped, QuarterCarVectorEnv)
    single = gym.make("QuarterCar-v0", arm_bushing="reference")
    _, info = venv.reset(seed=0)
    _, single_info = single.reset(seed=0)
    assert set(PLANAR_KEYS) <= set(single_info)
    assert {k for k in info if not k.startswith("_")} == set(single_info)
    obs, r, term, trunc, info = venv.step(np.full((3, 1), 0.5, np.float32))
    _, _, _, _, single_info = single.step(np.full(1, 0.5, np.float32))
    assert venv.observation_space.contains(obs) and r.shape == term.shape == (3,)
    assert {k for k in info if not k.startswith("_")} == set(single_info)
    assert all(info[k].shape == (3,) and info["_" + k].all() for k in single_info)
    assert (info["arm_rotation_rad"] != 0).all()  # after the step; the moment at its start
    info = venv.step(np.full((3, 1), 0.5, np.float32))[4]
    assert (info["moment_model_nm"] != 0).all() and (info["moment_reference_nm"] != 0).all()


def test_the_sb3_vec_env_keeps_its_conventions_with_a_planar_arm_bushing():
    """The vector env's checks (there is no checker of a vector env in Gymnasium 1.x or sb3):
    spaces, dtypes, no NaN (VecCheckNan), episode ends and restarts from rest."""
    n, length = 3, 20
    venv = make_sb3_vec_env("QuarterCar-v0", n, arm_bushing="reference", max_episode_steps=length)
    venv = VecCheckNan(venv, raise_exception=True)
    space = venv.observation_space
    assert venv.reset().shape == (n, *space.shape)
    rng = np.random.default_rng(0)
    ends = 0
    for t in range(2 * length):
        obs, reward, done, infos = venv.step(rng.uniform(-0.3, 0.3, (n, 1)).astype(np.float32))
        assert obs.dtype == np.float32 and reward.shape == done.shape == (n,)
        for i in range(n):
            assert ("terminal_observation" in infos[i]) == bool(done[i])
            if done[i]:
                ends += 1
                assert space.contains(infos[i]["terminal_observation"]) and (obs[i] == 0).all()
                assert (t + 1) % length == 0
    assert ends == 2 * n


def test_a_planar_file_is_the_preset_it_holds_bit_for_bit(tmp_path):
    path = PlanarLinear.preset().save(tmp_path / "arm.npz")
    road = pothole()
    rows = {}
    for arm in ("linear", str(path)):
        venv = make_vec(2, arm_bushing=arm)
        venv.reset(seed=0, options={"excitation": np.stack([road, -road], axis=1)})
        rows[arm] = [venv.step(np.zeros((2, 1), np.float32)) for _ in range(len(road))]
    for a, b in zip(rows["linear"], rows[str(path)], strict=True):
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
        for k in PLANAR_KEYS[:2] + PLANAR_KEYS[3:]:
            assert np.array_equal(a[4][k], b[4][k]), k
    moments = np.array([r[4]["moment_model_nm"] for r in rows[str(path)]])
    assert np.abs(moments).max(axis=0).min() > 1.0  # N m: both columns load the arm


def test_the_same_seed_and_actions_give_the_same_episode_bit_for_bit():
    acts = np.random.default_rng(4).uniform(-0.6, 0.6, (150, 3, 1)).astype(np.float32)
    first = make_vec(3, arm_bushing="reference")
    again = make_vec(3, arm_bushing="reference")
    runs = []
    for venv in (first, again, first):  # two envs, then the first one reset
        venv.reset(seed=7)
        runs.append([venv.step(a) for a in acts])
    for a, b, c in zip(*runs, strict=True):
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[0], c[0])
        for k in ("moment_model_nm", "moment_reference_nm", "force_radial_model_n", "chassis_y_m"):
            assert np.array_equal(a[4][k], b[4][k]) and np.array_equal(a[4][k], c[4][k]), k


# The default car's outputs before the planar rotary term entered the sub-step kernel (exact
# values; the term is zero without arm_bushing and must leave every sum as it was).
DEFAULT_CAR = (
    ("chassis_y_m", 150, 0, "-0x1.15ee9b72502a9p-7"),
    ("chassis_y_m", 500, 1, "0x1.431a61eda5fbcp-4"),
    ("wheel_y_m", 150, 0, "-0x1.1c81f3e64bb5cp-9"),
    ("wheel_y_m", 500, 1, "0x1.20e4e6e9dcf32p-4"),
    ("force_radial_model_n", 150, 0, "-0x1.7be207874b8b6p+7"),
    ("force_radial_model_n", 500, 1, "0x1.b25c0caee81b6p+5"),
    ("force_axial_model_n", 150, 0, "0x1.90706661ae8ddp+0"),
    ("force_axial_model_n", 500, 1, "0x1.57497f5d59c84p-3"),
    ("force_radial_reference_n", 150, 0, "-0x1.7bb4a280620fap+7"),
    ("force_radial_reference_n", 500, 1, "0x1.a22cc3eb686fap+5"),
    ("force_axial_reference_n", 150, 0, "0x1.78b44ba8d6e24p+0"),
    ("force_axial_reference_n", 500, 1, "0x1.649fff5e3901bp-3"),
)


def test_the_default_car_is_unchanged_bit_for_bit_and_has_no_planar_keys():
    bump = excitation.bump(0.4, 0.1, 30 / 3.6, DT, pre_s=0.3, post_s=0.5)
    rough = np.clip(np.cumsum(np.random.default_rng(1).normal(0.0, 0.004, 400)), -0.1, 0.1)
    road = np.concatenate([bump, bump[-1] + rough])
    for kw in ({}, {"arm_bushing": ""}):
        out = QuarterCarBatch(2, model="linear", reference="rubber", **kw).simulate(
            np.stack([road, -0.7 * road], axis=1)
        )
        assert not set(PLANAR_KEYS) & set(out)
        for key, t, j, want in DEFAULT_CAR:
            assert float(out[key][t, j]).hex() == want, (key, t, j)
    _, info = make_vec(2).reset(seed=0)
    assert not set(PLANAR_KEYS) & set(info)


class PlanarAfter(PlanarLinear):
    """Test double: the planar linear preset until sample ``after``, then NaN forces
    (``mode="nan"``) or a ``ZeroDivisionError`` (``mode="raise"``)."""

    def __init__(self, k_matrix, c_matrix, after=10, mode="nan", dt=DT) -> None:
        self.after, self.mode = int(after), mode
        super().__init__(k_matrix, c_matrix, dt=dt)

    @classmethod
    def make(cls, after, mode):
        lin = PlanarLinear.preset()
        return cls(lin.k_matrix, lin.c_matrix, after, mode)

    def extra_meta(self):
        return {"after": self.after, "mode": self.mode}

    def reset(self, batch_size=1):
        super().reset(batch_size)
        self.samples = 0

    def _advance(self, q, v, out):
        super()._advance(q, v, out)
        self.samples += q.shape[0]
        if self.samples > self.after:
            if self.mode == "raise":
                raise ZeroDivisionError("k / 0")
            out[:] = np.nan


def ends_alike(arm, road, n=2):
    """(step, reason) of the pymunk env's verdict and of the vector env's column 0."""
    single, vector = run_both(road, n, arm_bushing=arm)
    s, v = single[-1], vector[-1]
    assert s[2] and v[2][0] and len(single) == len(vector)
    assert s[4]["diverged"] and v[4]["diverged"][0] and not v[4]["physical_limit"][0]
    assert s[4]["divergence_reason"] == v[4]["divergence_reason"][0] != ""
    assert s[4]["model_out_of_bounds"] == v[4]["model_out_of_bounds"][0]
    return len(single), v[4]


def test_a_moment_beyond_the_limit_ends_the_column_as_in_the_pymunk_env():
    coupled = diagonal_linear3(k_rot=3000.0)
    coupled.k_matrix[2, 1] = 1e8  # N m per m of radial deflection: 0.1 mm gives 10 kN m
    steps, info = ends_alike(coupled, pothole())
    assert "bushing moment" in info["divergence_reason"][0] and steps < len(pothole())


@pytest.mark.parametrize("mode", ["nan", "raise"])
def test_a_planar_model_giving_nan_or_raising_ends_the_column_as_in_the_pymunk_env(mode):
    steps, info = ends_alike(PlanarAfter.make(after=12, mode=mode), pothole())
    assert steps == 13
    reason = info["divergence_reason"][0]
    assert ("not finite" in reason) if mode == "nan" else reason.startswith("model raised Zero")


@pytest.mark.parametrize("arm", ["reference", "hybrid-bw"])
def test_autoreset_restarts_a_planar_column_from_rest(arm):
    """The models' histories too: the hybrid's Bouc-Wen backbone keeps its own state."""
    if arm == "hybrid-bw":
        arm = PlanarBoucWenHybrid.untrained()
    kw = dict(arm_bushing=arm, arm_bushing_reference=arm)
    venv = make_vec(2, max_episode_steps=4, **kw)
    venv.reset(seed=0)
    a = np.full((2, 1), 0.5, np.float32)
    for _ in range(5):  # four steps, then the step that resets
        obs, *_ = venv.step(a)
    assert (obs == 0).all()
    fresh = make_vec(2, **kw)
    fresh.reset(seed=0)
    for _ in range(2):
        obs, *_, info = venv.step(a)
        f_obs, *_, f_info = fresh.step(a)
        assert np.array_equal(obs, f_obs)
        for k in ("moment_model_nm", "moment_reference_nm", "force_radial_model_n"):
            assert np.array_equal(info[k], f_info[k]), k


def test_planar_batch_columns_equal_the_same_roads_run_one_by_one():
    road = pothole()
    R = np.stack([road, 0.5 * road, -0.8 * road], axis=1)
    together = QuarterCarBatch(3, arm_bushing="reference").simulate(R)
    for j in range(3):
        alone = QuarterCarBatch(1, arm_bushing="reference").simulate(R[:, j])
        for k in ("moment_model_nm", "arm_rotation_rad", "force_radial_model_n"):
            np.testing.assert_array_equal(together[k][:, j], alone[k][:, 0])


def test_info_says_where_the_reference_judges_beyond_its_calibrated_rotation():
    from test_quartercar import LOOSE, worst_roads

    from bushenv.reference.planar import MAX_ROTATION_RAD

    road = worst_roads(600, np.random.default_rng(0))[:, 15]
    kw = dict(LOOSE, arm_bushing="linear", arm_bushing_reference="reference")  # the tilt set
    _, vector = run_both(road, arm_moment_limit_nm=1e12, **kw)
    theta = np.array([o[4]["reference_arm_rotation_rad"] for o in vector])
    said = np.array([[bool(s) for s in o[4]["reference_outside_range"]] for o in vector])
    assert np.abs(theta).max() > MAX_ROTATION_RAD
    np.testing.assert_array_equal(said, np.abs(theta) > MAX_ROTATION_RAD)
