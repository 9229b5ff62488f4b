import numpy as np
import pytest

from bushenv import excitation as ex
from bushenv.diagnose.rigs import RigDiagnoseError, diagnose_rig
from bushenv.models.base import PAPER_DT
from bushenv.reference.rubber import RubberBushing

DT = PAPER_DT


def bushrig_profiles():
    train = ex.random_rpc(1.0, 20.0, DT, seed=0)
    tests = [
        ex.random_rpc(1.5, 10.0, DT, seed=1),
        ex.sequence(
            ex.step_hold(3e-3, 4.0, DT, rise_s=0.05),
            ex.ramp(0.0, 0.05, DT, start_m=3e-3, hold_s=1.0),
        ),
    ]
    return train, tests


def road_profiles():
    train = ex.random_band(8.0, DT, seed=0, peak_m=0.03, spectrum="durability")
    tests = [
        ex.random_band(6.0, DT, seed=1, peak_m=0.045, spectrum="durability"),
        ex.bump(0.4, 0.1, 30 / 3.6, DT, pre_s=0.3, post_s=1.5),
        ex.pothole(0.7, 0.06, 30 / 3.6, DT, pre_s=0.3, post_s=1.5),
    ]
    return train, tests


def car_reference(effects, **overrides):
    return {
        "radial": RubberBushing.preset("radial", effects=effects, measurement=False, **overrides),
        "axial": RubberBushing.preset("axial", effects=(), measurement=False),
    }


def test_bushrig_with_withheld_relaxation_names_relaxation_on_the_force_channel():
    train, tests = bushrig_profiles()
    ref = RubberBushing.preset("axial", effects=("relaxation",), measurement=False)
    r = diagnose_rig("BushRig-v0", "identify", ref, train, tests, axis="axial")
    assert r["channel"] == "force" and r["force_channel"] == "force"
    assert r["channels"][0]["gap"] > 0.05 and r["channels"][0]["share"] == pytest.approx(1.0)
    assert r["effect"] == "relaxation"
    assert r["shrink"] > 0.2
    # the best row that passes; thermal, whose judged record may start warm (no warmer than
    # the warmest record fitted), must not take the step's relaxation under the hold
    assert next(x for x in r["ranking"] if x["passes"])["effect"] == "relaxation"
    rows = r["ranking"] + r["bushing_diagnosis"]["failed_to_fit"]
    thermal = next(x for x in rows if x["effect"] == "thermal")
    assert thermal["passes"] is False


def test_bushrig_with_a_linear_reference_and_its_identified_model_names_none():
    train, tests = bushrig_profiles()
    ref = RubberBushing.preset("axial", effects=(), measurement=False)
    r = diagnose_rig("BushRig-v0", "identify", ref, train, tests, axis="axial")
    assert r["rig_gap"] < 1e-6
    assert r["effect"] == "none" and r["shrink"] == 0.0
    # the bushing record alone keeps the rig's velocity convention's second-order residue
    # (0.57 % gap), which a delay and a mass together describe; the rig gate answers none
    assert r["bushing_diagnosis"]["gap_before"] < 0.01
    ident = r["model"]["identified"]["axial"]
    assert ident["k_n_per_m"] == pytest.approx(ref.k_n_per_m, rel=1e-6)


def test_quartercar_with_hardening_radial_bushing_names_hardening_on_a_radial_channel():
    train, tests = road_profiles()
    ref = car_reference(("hardening",), hardening_x_m=4e-3)
    r = diagnose_rig("QuarterCar-v0", "identify", ref, train, tests)
    assert r["axis"] == "radial"
    assert r["channel"].startswith("radial_")
    assert r["force_channel"] == "radial_force_n"
    names = [c["channel"] for c in r["channels"]]
    assert {"chassis_acceleration_m_per_s2", "axial_force_n", "tyre_force_n"} <= set(names)
    assert sum(c["share"] for c in r["channels"]) == pytest.approx(1.0)
    assert r["effect"] == "hardening"
    assert r["shrink"] > 0.5


def test_quartercar_with_a_linear_twin_and_its_identified_model_shows_no_gap_and_names_none():
    train, tests = road_profiles()
    r = diagnose_rig("QuarterCar-v0", "identify", car_reference(()), train, tests)
    assert r["rig_gap"] < 1e-6
    assert r["effect"] == "none" and r["shrink"] == 0.0


def test_unknown_rig_and_missing_tests_are_refused():
    train, tests = bushrig_profiles()
    with pytest.raises(RigDiagnoseError, match="unknown rig"):
        diagnose_rig("CartPole-v1", "linear", "rubber", train, tests)
    with pytest.raises(RigDiagnoseError, match="no TEST"):
        diagnose_rig("BushRig-v0", "linear", "rubber", train, [])
    with pytest.raises(RigDiagnoseError, match=r"TRAIN: the replay ended at step \d+ of 4096"):
        diagnose_rig(
            "BushRig-v0", "linear", "rubber", train, tests, env_kwargs={"force_limit_n": 1.0}
        )
    with pytest.raises(RigDiagnoseError, match="shape"):
        diagnose_rig("BushRig-v0", "linear", "rubber", np.zeros((4, 2)), tests)
