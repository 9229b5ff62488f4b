"""Every registered searcher, on every registered target, through every check of the searcher
contract (``bushenv.search.checks``): registering a searcher is the one step that tests it."""

import numpy as np
import pytest

from bushenv.search.base import SearchContext, Searcher
from bushenv.search.checks import SEARCHER_CHECKS, NotApplicable, SearcherTrial, searcher_cases
from bushenv.search.searchers import SEARCHERS, RandomSearch, SearcherEntry

CASES = searcher_cases()
_TRIALS: dict[tuple[str, str], SearcherTrial] = {}  # the checks of one case share its runs


@pytest.mark.parametrize("check", sorted(SEARCHER_CHECKS))
@pytest.mark.parametrize(("name", "target"), CASES, ids=[f"{s}-{t}" for s, t in CASES])
def test_every_registered_searcher_keeps_the_contract(name, target, check):
    trial = _TRIALS.setdefault((name, target), SearcherTrial(name, target))
    try:
        SEARCHER_CHECKS[check](trial)
    except NotApplicable as exc:
        pytest.skip(str(exc))


class Steps(RandomSearch):
    """A searcher a user adds: random steps only."""

    name = "steps"

    def __init__(self):
        super().__init__(families=("step",), batch_size=4)


class OneShort(RandomSearch):
    """Stops one evaluation before its budget."""

    name = "one_short"

    def search(self, ctx: SearchContext) -> None:
        super().search(SearchContext(**{**ctx.__dict__, "budget": ctx.budget - 1}))


class Unbooked(RandomSearch):
    """Judges one profile more than it books."""

    name = "unbooked"

    def search(self, ctx: SearchContext) -> None:
        fam = ctx.evaluator.target.family("step")
        ctx.evaluator.evaluate([fam.profile(ctx.rng.random(fam.dim), ctx.evaluator.dt)])
        super().search(ctx)


class Unseeded(RandomSearch):
    """Draws from a generator of its own, not the run's: every seed searches alike."""

    name = "unseeded"

    def search(self, ctx: SearchContext) -> None:
        super().search(SearchContext(**{**ctx.__dict__, "rng": np.random.default_rng(7)}))


def test_a_searcher_registered_at_run_time_is_checked_too():
    with SEARCHERS.temporarily("steps", SearcherEntry(Steps, "random steps")):
        assert ("steps", "rig") in searcher_cases()
        trial = SearcherTrial("steps", "rig")
        for check in SEARCHER_CHECKS.values():
            check(trial)
        assert trial.run(0).result.coverage.keys() == {"step"}


@pytest.mark.parametrize(
    ("cls", "check", "message"),
    [
        (OneShort, "books_the_budget_exactly", "one_short on rig: booked 12 evaluations of a "),
        (
            Unbooked,
            "records_every_evaluation",
            "unbooked on rig: first failure booked at 5, judged at \\[6\\]",
        ),
        (Unseeded, "different_seeds_differ", "unseeded on rig: seeds 0 and 1 judged the same"),
    ],
)
def test_the_checks_catch_a_searcher_that_breaks_the_contract(cls, check, message):
    with SEARCHERS.temporarily(cls.name, SearcherEntry(cls, "broken")):
        with pytest.raises(AssertionError, match=message):
            SEARCHER_CHECKS[check](SearcherTrial(cls.name, "rig"))


def test_a_searcher_without_the_hook_cannot_be_made():
    class NoHook(Searcher):
        name = "no_hook"

    with pytest.raises(TypeError, match="search"):
        NoHook()
