import numpy as np
import pytest

from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.rl import RLSearch
from bushenv.search.searchers import SearchError

from .conftest import UnstableHoldBushing


@pytest.mark.parametrize("algo", ["ppo", "sac"])
def test_rl_searcher_spends_its_budget_in_episodes_and_is_deterministic(algo, reference_axial):
    model = UnstableHoldBushing(delay_s=0.2)
    runs = []
    for _ in range(2):
        ev = BatchEvaluator(model, reference_axial)
        res = RLSearch(algo, n_envs=8, episode_s=1.0).run(ev, budget=16, seed=3)
        assert res.evaluations == 16
        runs.append(res)
    assert [r for _, r in runs[0].history] == [r for _, r in runs[1].history]
    assert np.array_equal(runs[0].worst.profile, runs[1].worst.profile)
    # episodes are judged on the prescribed-motion path: each profile starts at rest
    assert runs[0].worst.profile[0] == 0.0 and runs[0].worst.family == f"agent-{algo}"


def test_rl_searcher_finds_an_easy_divergence(reference_axial):
    model = UnstableHoldBushing(delay_s=0.02, trigger_m=0.5e-3, growth=1.5)
    res = RLSearch("ppo", n_envs=8, episode_s=1.0).run(
        BatchEvaluator(model, reference_axial), budget=16, seed=0
    )
    assert res.diverged and 1 <= res.first_failure.evaluation <= 16
    assert res.first_failure.family == "agent-ppo"


def test_rl_refuses_unknown_algorithms():
    with pytest.raises(SearchError, match="ppo' or 'sac"):
        RLSearch("dqn")


def test_rl_drives_the_quarter_car_and_judges_its_roads(linear_axial, reference_axial):
    runs = []
    for _ in range(2):
        ev = BatchEvaluator(linear_axial, reference_axial, env="quartercar")
        runs.append(RLSearch("ppo", n_envs=4, episode_s=0.5).run(ev, budget=8, seed=1))
    res = runs[0]
    assert res.evaluations == 8 and not res.diverged  # the linear control stays clean
    assert res.worst.family == "agent-ppo" and res.worst.profile.size == 102
    assert np.array_equal(res.worst.profile, runs[1].worst.profile)
