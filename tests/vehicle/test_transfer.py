"""The error-transfer map: the erring bushings are sized as stated, the single car is HalfCar-v0's
model car, the predictor is the superposition it claims to be, a campaign repeats, and the
command writes its report and refuses bad settings."""

import json

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.rigs.halfcar_params import ENV_ID, POSITIONS, REFERENCE
from bushenv.rigs.specs import spec_kwargs
from bushenv.vehicle.compare import run_car
from bushenv.vehicle.manoeuvres import standard_manoeuvres
from bushenv.vehicle.study import env_overrides
from bushenv.vehicle.transfer import (
    COMPONENTS,
    MAP_OUTPUTS,
    TransferConfig,
    combinations,
    pivot_table,
    run_transfer,
)
from bushenv.vehicle.transfer_car import single_car_run
from bushenv.vehicle.transfer_errors import (
    COORDS,
    KINDS,
    ErrorTerm,
    TransferInputError,
    bench_errors_pct,
    bench_motion,
    calibrate,
    erring_rubber,
    reference_rubber,
    scaled_rubber,
)
from bushenv.vehicle.transfer_predict import TransferPredictor, gram_matrix

DT = float(spec_kwargs(ENV_ID, {})["dt_s"])


@pytest.mark.parametrize("kind", KINDS)
def test_each_kind_errs_by_the_stated_size_on_its_own_coordinate(kind):
    for size in (10.0, -7.5):
        for i, coord in enumerate(COORDS):
            err = bench_errors_pct(erring_rubber(kind, coord, size, DT), DT)
            assert err[i] == pytest.approx(abs(size), rel=1e-6)
            assert np.all(np.delete(err, i) < 0.1 * abs(size))  # the others barely move
            assert (calibrate(kind, coord, size, DT) > 1) == (size > 0)


def test_a_scaled_friction_scales_the_friction_force_exactly():
    # the Iwan law is homogeneous in its slip forces and element stiffnesses: twice fmax is
    # twice the friction force, measured as the rubber with and without friction
    base = reference_rubber(DT)
    q = bench_motion(DT)
    no_friction = base.without_effects("friction").simulate(q)[:, 1]
    friction = base.simulate(q)[:, 1] - no_friction
    doubled = scaled_rubber(base, "hysteresis", "radial", 2.0).simulate(q)[:, 1] - no_friction
    np.testing.assert_allclose(doubled, 2 * friction, rtol=1e-9, atol=1e-9)


def test_an_unreachable_or_unknown_error_is_refused_naming_it():
    with pytest.raises(TransferInputError, match="relaxation on axial: -40 % cannot be reached"):
        calibrate("relaxation", "axial", -40.0, DT)
    with pytest.raises(TransferInputError, match="error kind 'creep'; known: stiffness"):
        calibrate("creep", "axial", 10.0, DT)
    with pytest.raises(TransferInputError, match="coordinate 'twist'"):
        erring_rubber("damping", "twist", 10.0, DT)
    with pytest.raises(TransferInputError, match="given twice"):
        pivot_table([ErrorTerm("lower_left", "axial", "damping", 5.0)] * 2, DT)


def test_the_single_car_is_halfcar_v0s_model_car_bit_for_bit():
    m = standard_manoeuvres(DT, 0, ["pothole"], duration_s=1.0)[0]
    table = pivot_table([ErrorTerm("upper_left", "rotation", "hysteresis", 10.0)], DT)
    env_run = run_car(m, table, REFERENCE, "x", env_overrides([m]))
    own = single_car_run(m, table, env_overrides([m]))
    assert own.steps == env_run.steps == m.samples and own.end == ""
    for name, values in env_run.model.items():
        np.testing.assert_array_equal(own.outputs[name], values)
    np.testing.assert_array_equal(own.deflection, env_run.deflection)


def test_the_gram_form_is_the_rms_of_the_superposed_histories():
    rng = np.random.default_rng(1)
    hist = [rng.standard_normal((50, 2)) for _ in range(3)]
    g = gram_matrix(hist)
    w = np.array([0.5, -1.5, 2.0])
    direct = np.sqrt(np.mean(sum(wj * h for wj, h in zip(w, hist, strict=True)) ** 2) * 2)
    assert np.sqrt(w @ g @ w) == pytest.approx(direct, rel=1e-12)


@pytest.fixture(scope="module")
def campaign():
    config = TransferConfig(DT, 10.0, ("pothole",), 0.6, 0, 2, (2.0,))
    return config, run_transfer(config)


def test_the_predictor_gives_back_its_own_singles_and_superposes_the_others(campaign, tmp_path):
    config, (report, pred) = campaign
    pct, minus = np.asarray(report["map_pct"]), np.asarray(report["map_minus_pct"])
    g = pred.gram  # basis: odd parts, then even parts; a + run is their sum
    plus_gram = g[:, :, :48, :48] + g[:, :, 48:, 48:] + g[:, :, :48, 48:] + g[:, :, 48:, :48]
    first = TransferPredictor(pred.manoeuvres, pred.outputs, pred.components, 10.0, plus_gram,
                              pred.baseline_rms, pred.floors)  # fmt: skip
    assert pred.order == 2 and g.shape[2:] == (96, 96)
    for j, c in enumerate(COMPONENTS):
        for size, want in ((10.0, pct[j]), (-10.0, minus[j])):  # exact at the built sizes
            np.testing.assert_allclose(pred.predict_pct([ErrorTerm(*c, size)]), want,
                                       rtol=1e-9, atol=1e-12)  # fmt: skip
        np.testing.assert_allclose(first.predict_pct([ErrorTerm(*c, -20.0)]), 2 * pct[j],
                                   rtol=1e-9)  # fmt: skip
    assert np.all(pred.predict_rms([]) == 0)
    path = tmp_path / "p.npz"
    pred.save(path)
    again = TransferPredictor.load(path)
    terms = report["checks"]["combinations"][1]["terms"]
    terms = [ErrorTerm(**t) for t in terms]
    np.testing.assert_array_equal(again.predict_pct(terms), pred.predict_pct(terms))
    assert pct.shape == (len(COMPONENTS), 1, len(MAP_OUTPUTS))


def test_a_campaign_repeats_to_the_last_bit_and_its_cars_ran_to_the_end(campaign):
    config, (report, pred) = campaign
    again, pred2 = run_transfer(config)
    np.testing.assert_array_equal(pred.gram, pred2.gram)
    for a, b in zip(report["checks"]["combinations"], again["checks"]["combinations"],
                    strict=True):  # fmt: skip
        np.testing.assert_array_equal(a["measured_pct"], b["measured_pct"])
    assert report["ended"] == [] and report["cars"] == 1 + 3 * len(COMPONENTS) + 2


def test_a_symmetric_error_on_a_symmetric_bump_rolls_nothing_and_a_one_sided_one_does():
    bump = standard_manoeuvres(DT, 0, ["bump"], duration_s=1.2)[0]
    ov = env_overrides([bump])
    base = single_car_run(bump, REFERENCE, ov)
    both = [ErrorTerm(p, "axial", "stiffness", 10.0) for p in ("lower_left", "lower_right")]
    roll_both = single_car_run(bump, pivot_table(both, DT), ov).outputs["roll"]
    roll_left = single_car_run(bump, pivot_table(both[:1], DT), ov).outputs["roll"]
    assert np.abs(base.outputs["roll"]).max() < 1e-9
    assert np.abs(roll_both).max() < 1e-9 < 1e-6 < np.abs(roll_left).max()


def test_combinations_are_drawn_from_the_seed_within_the_stated_sizes():
    a, b = combinations(6, 10.0, 3), combinations(6, 10.0, 3)
    assert a == b and a != combinations(6, 10.0, 4)
    assert [t.pivot for t in a[0]] == list(POSITIONS)
    sizes = np.array([abs(t.size_pct) for c in a for t in c])
    assert np.all((sizes >= 5.0) & (sizes <= 15.0))


def test_the_command_writes_its_report_and_refuses_a_bad_size(tmp_path, capsys):
    out = tmp_path / "t"
    args = ["vehicle-transfer", "--out", str(out), "--manoeuvres", "pothole",
            "--duration-s", "0.8", "--combinations", "1", "--quiet"]  # fmt: skip
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "**Predictor, second order**" in text
    assert "Never reach" in text or "Every component" in text
    for name in ("transfer.md", "transfer.json", "transfer_map.csv", "transfer_predictor.npz",
                 "transfer_map.png", "transfer_check.png"):  # fmt: skip
        assert (out / name).stat().st_size > 0
    report = json.loads((out / "transfer.json").read_text())
    rows = (out / "transfer_map.csv").read_text().splitlines()
    assert len(rows) == 1 + len(COMPONENTS) * len(MAP_OUTPUTS)
    assert report["findings"]["size_pct"] == 10.0
    assert main(["vehicle-transfer", "--out", str(out), "--size-pct", "40"]) == 2
    assert "--size-pct must be in (0, 15] %, got 40.0" in capsys.readouterr().err
    assert main(["vehicle-transfer", "--out", str(out), "--held=0"]) == 2
    assert "--held 0.0: non-zero" in capsys.readouterr().err
    assert main(["vehicle-transfer", "--out", str(out), "--held=-1"]) == 2
    assert "--held -1.0: the predictor is built on it" in capsys.readouterr().err
    assert main(["vehicle-transfer", "--out", str(out), "--combinations", "-1"]) == 2
    assert "--combinations must be >= 0, got -1" in capsys.readouterr().err


def test_findings_name_the_errors_below_a_tenth_and_above_the_size():
    from bushenv.vehicle.transfer_report import findings

    comps = [["lower_left", "radial", "damping"], ["upper_left", "rotation", "stiffness"],
             ["lower_right", "axial", "hysteresis"]]  # fmt: skip
    pct = np.array([[[0.5, 0.9]], [[12.0, np.nan]], [[3.0, 9.0]]])  # (J, M, O): 1 manoeuvre
    report = {
        "settings": {"size_pct": 10.0}, "components": comps, "map_pct": pct,
        "map_rms": pct / 100, "manoeuvres": [{"name": "bump"}],
        "outputs": [{"name": "roll", "unit": "rad"}, {"name": "camber", "unit": "rad"}],
        "in_car_component_pct": [[5.0], [10.0], [np.nan]],
        "checks": {"predictors": ["second_order"],
                   "singles": {"+2": {"second_order": {"influence": {"overall": 0.95}}}},
                   "combinations": [],
                   "combined": {"second_order": {"median_relative_error": 0.25, "cells": 3}}},
    }  # fmt: skip
    found = findings(report)
    assert [r["component"] for r in found["never_reach"]] == [comps[0]]
    assert [r["component"] for r in found["amplified"]] == [comps[1]]
    assert found["amplified"][0]["where"] == ("bump", "roll")
    assert found["amplified"][0]["change"] == "0.12 rad"
    assert found["predictor"]["meets_rank"] and not found["predictor"]["meets_median"]
    assert found["in_car_component_by_kind"]["hysteresis"] is None
