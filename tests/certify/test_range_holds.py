"""A network's fixed points on a grid over a range (the card's ``holds``, the search's suspect
holds), the same for one coordinate and for three."""

import numpy as np
import pytest

from bushenv.certify.range_holds import describe, range_holds, suspect_holds
from bushenv.models import MODELS

from .conftest import X_SCALE_M, bistable, fold_nn, fold_u, wrong_sign_hybrid

PEAKS3 = np.array([2e-3, 2e-3, 0.05])


def _bistable(coords):
    """Several fixed points inside the range: the fold network (C = 1), three bistable axes."""
    if coords == 1:
        return fold_nn(), np.array([0.9 * fold_u(2.0) * X_SCALE_M])
    return bistable(), PEAKS3


@pytest.mark.parametrize("coords", [1, 3])
def test_a_bistable_network_is_seen_on_every_hold_of_its_grid(coords):
    model, peaks = _bistable(coords)
    holds = range_holds(model, peaks)
    assert holds["holds"] == 5**coords and holds["range"] == peaks.tolist()
    assert holds["holds_with_more_than_one"] == 5**coords  # inside the folds everywhere
    lines = describe(holds, model.units)
    assert len(lines) == 2 and lines[1].startswith("warning:")
    assert ("mrad" in lines[0]) == (coords == 3)


@pytest.mark.parametrize("coords", [1, 3])
def test_a_fold_inside_the_range_is_counted_and_a_linear_model_has_no_entry(coords):
    model, peaks = _bistable(coords)
    holds = range_holds(model, 6.0 * peaks)  # beyond the folds on the outer holds
    assert holds["fold_crossings"] > 0
    assert holds["fixed_points_per_hold"][0] < holds["fixed_points_per_hold"][1]
    assert range_holds(MODELS["linear"].model_class(coords).preset(), peaks) is None


def test_a_unique_stable_hold_everywhere_gets_no_warning():
    weak = bistable(out=0.3)  # y = 0.3 tanh(2 y + c): one root, stable, at every hold
    holds = range_holds(weak, PEAKS3)
    assert holds["fixed_points_per_hold"] == [1, 1] and holds["fold_crossings"] == 0
    assert holds["largest_spectral_radius"] < 1.0 and len(describe(holds, weak.units)) == 1


@pytest.mark.parametrize("coords", [1, 3])
def test_suspect_holds_name_several_fixed_points_and_a_force_pushing_inward(coords):
    model, peaks = _bistable(coords)
    listed = suspect_holds(model, peaks, np.zeros(coords), 0.5)
    assert len(listed) == 5**coords
    assert all("several_fixed_points" in h["kinds"] for h in listed)
    # one coordinate: the hybrid whose network pulls against k x near rest (200 vs 100 N/mm)
    pulling = wrong_sign_hybrid() if coords == 1 else None
    if pulling is not None:
        listed = suspect_holds(pulling, np.array([1e-3]), np.array([10.0]), 0.5)
        assert [h["q"] for h in listed] == [[-1e-3], [-0.5e-3], [0.5e-3], [1e-3]]
        assert all(h["kinds"] == ["pushes_into_the_deflection"] for h in listed)
    assert suspect_holds(MODELS["linear"].model_class(coords).preset(), peaks, 0, 0.5) is None
