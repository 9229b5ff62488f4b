"""A fitted network's card says what its holds do over its own training range."""

import json

import numpy as np

from bushenv.certify.range_holds import describe, range_holds
from bushenv.identify import FitResult
from bushenv.identify.card import save_fit
from bushenv.identify.mimo_options import MimoOptions
from bushenv.models.base import PAPER_DT
from bushenv.models.planar_linear import PlanarLinear
from bushenv.motions import random_independent
from bushenv.records import Record

from .conftest import bistable


def _record(seed=0):
    q = random_independent(1.0, 4.0, PAPER_DT, seed)
    t = np.arange(q.shape[0]) * PAPER_DT
    return Record(t, q, PlanarLinear.preset().simulate(q), "")


def test_a_bistable_network_is_warned_of_on_its_card(tmp_path):
    net, rec = bistable(), _record()
    result = FitResult(net, "nn-axis", MimoOptions(), [rec], None, 0, 0.1)
    card = save_fit(result, tmp_path / "b.npz", plots=False)
    holds = card["holds"]
    peaks = np.abs(rec.q).max(axis=0)
    assert holds["range"] == peaks.tolist() and holds["holds"] == 125
    assert holds["holds_with_more_than_one"] > 0 and holds["fixed_points_per_hold"][1] == 27
    lines = describe(holds, PlanarLinear.units)
    assert len(lines) == 2 and lines[1].startswith("warning:")
    md = (tmp_path / "b.card.md").read_text()
    assert "## Holds over the training range" in md and "warning:" in md
    assert json.loads((tmp_path / "b.card.json").read_text())["holds"]["holds"] == 125


def test_a_unique_stable_hold_everywhere_gets_no_warning_and_a_linear_model_no_entry():
    weak = bistable(out=0.3)  # y = 0.3 tanh(2 y + c): one root, stable, at every hold
    holds = range_holds(weak, np.array([2e-3, 2e-3, 0.05]))
    assert holds["fixed_points_per_hold"] == [1, 1] and holds["fold_crossings"] == 0
    assert holds["largest_spectral_radius"] < 1.0 and len(describe(holds, PlanarLinear.units)) == 1
    assert range_holds(PlanarLinear.preset(), np.array([2e-3, 2e-3, 0.05])) is None
