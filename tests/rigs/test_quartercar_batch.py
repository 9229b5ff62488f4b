"""QuarterCarBatch: the quarter car as arrays, cross-checked against the pymunk env."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from rig_test_models import NanAfter, ValueAfter

from bushenv import excitation
from bushenv.models import get_model
from bushenv.rigs.common import RigError
from bushenv.rigs.quartercar_batch import QuarterCarBatch

DT = 1.0 / 204.8
KEYS = ("chassis_y_m", "wheel_y_m", "force_radial_model_n", "force_axial_model_n")


def env_rows(road, **kw):
    env = gym.make("QuarterCar-v0", **kw)
    env.reset(seed=0, options={"excitation": road})
    rows = []
    while True:
        *_, term, trunc, info = env.step(np.zeros(1, np.float32))
        rows.append([info[k] for k in KEYS])
        if term or trunc:
            return np.array(rows)


def roads():
    bump = excitation.bump(0.4, 0.1, 30 / 3.6, DT, 0.05, 0.5)
    rng = np.random.default_rng(1)
    steps = np.clip(rng.normal(0.0, 0.012, 300), -0.05, 0.05)
    rough = np.concatenate([[0.0], np.clip(np.cumsum(steps), -0.06, 0.06)])
    return {"bump": bump, "rough": rough}


@pytest.mark.parametrize("reference", ["linear", "rubber"])
@pytest.mark.parametrize("name", ["bump", "rough"])
def test_batch_matches_the_pymunk_car_within_one_percent_of_the_peaks(name, reference):
    """Same car, same coupling, different integrators (pymunk's per-damper implicit Euler with
    Gauss-Seidel joints vs one coupled implicit solve): within 1 % of each signal's peak."""
    road = roads()[name]
    want = env_rows(road, reference=reference)
    out = QuarterCarBatch(1, reference=reference).simulate(road)
    got = np.stack([out[k][:, 0] for k in KEYS], axis=1)[: len(want)]
    err = np.abs(got - want).max(axis=0) / np.abs(want).max(axis=0)
    assert (err < 0.01).all(), dict(zip(KEYS, err, strict=True))


def test_batch_columns_equal_the_same_roads_run_one_by_one():
    road = roads()["bump"]
    R = np.stack([road, 0.5 * road, -0.8 * road], axis=1)
    together = QuarterCarBatch(3, model="linear", reference="rubber").simulate(R)
    for j in range(3):
        alone = QuarterCarBatch(1, model="linear", reference="rubber").simulate(R[:, j])
        for k in (*KEYS, "force_radial_reference_n"):
            np.testing.assert_array_equal(together[k][:, j], alone[k][:, 0])


def test_batch_flags_the_car_whose_model_returns_nan():
    model = {"radial": NanAfter(after=10, k=1.5e6), "axial": get_model("linear", "axial")}
    road = roads()["bump"]
    out = QuarterCarBatch(2, model=model, reference="linear").simulate(road)
    assert out["diverged"].all() and (out["divergence_step"] == 10).all()
    assert not out["physical_limit"].any()


def test_batch_judges_a_force_beyond_the_limit_without_applying_it():
    model = {"radial": ValueAfter(after=10, value=1e300), "axial": get_model("linear", "axial")}
    road = roads()["bump"]
    out = QuarterCarBatch(2, model=model, reference="linear").simulate(road)
    ref = QuarterCarBatch(2, model="linear", reference="linear").simulate(road)
    assert out["diverged"].all() and (out["divergence_step"] == 10).all()
    assert np.isfinite(out["chassis_y_m"]).all() and np.isfinite(out["wheel_y_m"]).all()
    np.testing.assert_array_equal(out["reference_chassis_y_m"], ref["reference_chassis_y_m"])


@pytest.mark.parametrize("error", [ZeroDivisionError("k / 0"), FloatingPointError("overflow")])
def test_batch_flags_the_cars_whose_model_raises_an_arithmetic_error(error):
    model = {"radial": ValueAfter(after=10, error=error), "axial": get_model("linear", "axial")}
    out = QuarterCarBatch(2, model=model, reference="linear").simulate(roads()["bump"])
    assert out["diverged"].all() and (out["divergence_step"] == 10).all()


def test_batch_refuses_a_road_beyond_the_limits():
    with pytest.raises(RigError, match="max_road_step_m"):
        QuarterCarBatch(1).simulate(np.array([0.0, 0.06]))
