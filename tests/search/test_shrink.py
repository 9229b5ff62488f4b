import numpy as np

from bushenv import excitation as ex
from bushenv.models.base import PAPER_DT as DT
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.families import get_family
from bushenv.search.shrink import complexity, n_segments, shrink


def test_segments_count_holds_rises_and_falls():
    assert n_segments(np.array([0.0, 0.0, 1.0, 2.0, 2.0, 1.0])) == 4
    assert n_segments(ex.step_hold(4e-3, 1.0, DT, rise_s=0.05)) == 3


def test_a_noisy_failure_shrinks_to_a_short_simple_step_that_still_fails(
    unstable_model, reference_axial
):
    fam = get_family("random_ood")
    # a large off-centre random drive: beyond the 3 mm trigger for seconds
    x = fam.profile(np.array([0.2, 0.3, 0.5, 0.95, 1.0, 0.4, 1.0]))
    ev = BatchEvaluator(unstable_model, reference_axial)
    assert ev.evaluate([x]).verdict.diverged[0]
    res = shrink(x, ev, budget=300)
    assert res.verdict["diverged"]
    assert res.evaluations <= 300
    assert res.final < res.original
    assert res.final[1] < x.size and res.final[0] <= 8  # shorter and a handful of segments
    ok, why = ex.within_limits(res.profile, DT)
    assert ok, why
    assert res.profile[0] == 0.0
    # the known mechanism: 2 s held beyond 3 mm, then growth; not much less can fail
    assert np.max(np.abs(res.profile)) > 3e-3
    assert res.profile.size * DT > 2.0
    again = BatchEvaluator(unstable_model, reference_axial).evaluate([res.profile])
    assert again.verdict.diverged[0]


def test_shrinking_is_deterministic(unstable_model, reference_axial):
    x = get_family("step").profile(np.array([0.95, 0.5, 0.5, 1.0]))
    a = shrink(x, BatchEvaluator(unstable_model, reference_axial), budget=120)
    b = shrink(x, BatchEvaluator(unstable_model, reference_axial), budget=120)
    assert np.array_equal(a.profile, b.profile)
    assert complexity(a.profile) == a.final


def test_shrink_refuses_a_profile_that_does_not_fail(linear_axial, reference_axial):
    import pytest

    x = get_family("step").profile(np.full(4, 0.5))
    with pytest.raises(ValueError, match="does not fail"):
        shrink(x, BatchEvaluator(linear_axial, reference_axial))
