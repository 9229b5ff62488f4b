import numpy as np
import pytest

from bushenv.errors import ModelRefused
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.families import get_family
from bushenv.search.searchers import CMASearch, RandomSearch, SearchError, get_searcher

from .conftest import UnstableHoldBushing


@pytest.mark.parametrize("searcher", [RandomSearch(batch_size=32), CMASearch()])
def test_searcher_finds_the_held_step_divergence_of_an_unstable_model(
    searcher, unstable_model, reference_axial
):
    ev = BatchEvaluator(unstable_model, reference_axial)
    res = searcher.run(ev, budget=192, seed=0)
    assert res.diverged
    assert res.evaluations == ev.n_evaluations == 192
    assert 1 <= res.first_failure.evaluation <= 192
    assert res.worst.robustness < 0
    # the failure is the known mechanism: deflection held beyond 3 mm for more than 2 s
    f = res.first_failure
    assert f.verdict["first_criterion"] in ("self_sustained", "force_bound", "deviation")
    assert np.max(np.abs(f.profile)) > 3e-3


@pytest.mark.parametrize("name", ["random", "cma"])
def test_searchers_never_flag_the_linear_control(name, linear_axial, reference_axial):
    res = get_searcher(name).run(BatchEvaluator(linear_axial, reference_axial), 128, seed=1)
    assert not res.diverged and res.n_failures == 0
    assert res.worst.robustness > 0


@pytest.mark.parametrize("name", ["random", "cma"])
def test_search_is_deterministic_given_the_seed(name, unstable_model, reference_axial):
    runs = [
        get_searcher(name).run(BatchEvaluator(unstable_model, reference_axial), 64, seed=5)
        for _ in range(2)
    ]
    assert [r for _, r in runs[0].history] == [r for _, r in runs[1].history]
    assert np.array_equal(runs[0].worst.profile, runs[1].worst.profile)


def test_threaded_evaluation_equals_single_threaded_bit_for_bit(unstable_model, reference_axial):
    fam = get_family("any")
    rng = np.random.default_rng(3)
    profiles = [fam.profile(rng.random(fam.dim)) for _ in range(24)]
    one = BatchEvaluator(unstable_model, reference_axial, threads=1).evaluate(profiles)
    two = BatchEvaluator(unstable_model, reference_axial, threads=2).evaluate(profiles)
    assert np.array_equal(one.verdict.robustness, two.verdict.robustness)
    assert np.array_equal(one.f_model, two.f_model)


def test_reference_cache_gives_the_same_forces_as_a_fresh_run(linear_axial, reference_axial):
    fam = get_family("step")
    profiles = [fam.profile(np.full(4, 0.9)), fam.profile(np.full(4, 0.2))]
    ev = BatchEvaluator(linear_axial, reference_axial)
    first = ev.evaluate(profiles)
    again = ev.evaluate(profiles[::-1])
    n = first.lengths[0]
    assert np.array_equal(first.f_ref[:n, 0], again.f_ref[:n, 1])
    assert np.array_equal(first.f_ref[:n, 0], reference_axial.copy().simulate(profiles[0]))


def test_budget_and_searcher_names_are_checked(linear_axial, reference_axial):
    ev = BatchEvaluator(linear_axial, reference_axial)
    with pytest.raises(SearchError, match="budget"):
        RandomSearch().run(ev, 0)
    with pytest.raises(SearchError, match="unknown searcher 'nope'"):
        get_searcher("nope")


class _Refusing(UnstableHoldBushing):
    """Raises (like Bouc-Wen's step control) once |x| passed 10 mm."""

    def _advance(self, x, v, out):
        for t in range(x.shape[0]):
            if np.any(np.abs(x[t]) > 10e-3):
                raise ModelRefused("refused")
            super()._advance(x[t : t + 1], v[t : t + 1], out[t : t + 1])


def test_a_model_that_refuses_some_histories_gives_nan_there_and_diverges(reference_axial):
    fam = get_family("step")
    small = fam.profile(np.array([0.6, 0.0, 0.0, 0.1]))  # +2.5 mm
    large = fam.profile(np.array([1.0, 0.0, 0.0, 0.1]))  # +12.5 mm
    res = BatchEvaluator(_Refusing(), reference_axial).evaluate([small, large])
    assert list(res.verdict.diverged) == [False, True]
    assert res.verdict.first_criterion[1] == "non_finite"
    first_bad = int(np.argmax(np.abs(large) > 10e-3))
    assert np.all(np.isfinite(res.f_model[:first_bad, 1]))
    assert np.isnan(res.f_model[first_bad, 1])
