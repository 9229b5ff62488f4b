import numpy as np
import pytest

from bushenv.models.linear import LinearBushing
from bushenv.reference.rubber import RubberBushing
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.families import get_family

from .conftest import bad_narx


def _roads(n, seed):
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        fam = get_family("bump" if i % 2 == 0 else "pothole")
        out.append(fam.profile(rng.random(fam.dim), max_s=4.0))
    return out


@pytest.mark.parametrize("axis", ["axial", "radial"])
def test_linear_control_in_the_quarter_car_is_never_flagged_on_roads(axis):
    ref = RubberBushing.preset(axis, measurement=False)
    roads = _roads(10, 1) + [
        get_family(f).profile(np.full(get_family(f).dim, c), max_s=4.0)
        for f in ("bump", "pothole")
        for c in (0.0, 1.0)
    ]
    ev = BatchEvaluator(LinearBushing.preset(axis), ref, target="quartercar", axis=axis)
    v = ev.evaluate(roads).verdict
    assert not v.diverged.any(), [v.row(b) for b in np.flatnonzero(v.diverged)][:2]


def test_quarter_car_batch_is_judged_per_road_and_threads_agree():
    ref = RubberBushing.preset("axial", measurement=False)
    roads = _roads(6, 2)
    one = BatchEvaluator(bad_narx(), ref, target="quartercar", threads=1).evaluate(roads)
    two = BatchEvaluator(bad_narx(), ref, target="quartercar", threads=2).evaluate(roads)
    assert np.array_equal(one.verdict.robustness, two.verdict.robustness)
    alone = BatchEvaluator(bad_narx(), ref, target="quartercar").evaluate(roads[3:4])
    assert alone.verdict.robustness[0] == one.verdict.robustness[3]
    assert np.array_equal(one.profile(3), roads[3])
