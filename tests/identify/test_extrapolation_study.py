"""studies/2026-11-planar-fit-unseen/planar_extrapolation.py: its judge reads the truth as
right and a model without the coupling as wrong, and its holds ramp and hold."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from bushenv.models.base import PAPER_DT
from bushenv.reference.planar import PlanarRubber


@pytest.fixture(scope="module")
def mod():
    study = Path(__file__).parents[2] / "studies" / "2026-11-planar-fit-unseen"
    path = study / "planar_extrapolation.py"
    spec = importlib.util.spec_from_file_location("planar_extrapolation", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_judge_reads_the_truth_as_right_and_a_missing_coupling_as_wrong(mod):
    truth = PlanarRubber.preset(measurement=False)
    rms, peak = mod.worst_on_sets(truth, 0, True, 1.5, PAPER_DT)
    assert rms < 0.005 and peak < 0.01  # the load cell's noise only
    uncoupled = truth.without_effects(["coupling"])
    rms, _ = mod.worst_on_sets(uncoupled, 0, True, 1.5, PAPER_DT)
    assert rms > 0.05  # the coupling is a large part of the sets' force
    rms, _ = mod.worst_on_sets(uncoupled, 0, False, 1.5, PAPER_DT)
    assert rms < 0.005  # ... and is what "without the coupling" leaves out


def test_a_hold_ramps_in_one_second_and_holds(mod):
    v = np.array([2e-3, 0.0, 0.05])
    q = mod.held(v, PAPER_DT)
    ramp = int(round(1.0 / PAPER_DT))
    assert q.shape == (int(round(21.0 / PAPER_DT)), 3)
    assert np.all(q[0] == 0) and np.all(q[ramp:] == v)
    assert np.all(np.diff(q[: ramp + 1, 0]) >= 0)  # a monotone ramp up to the hold
