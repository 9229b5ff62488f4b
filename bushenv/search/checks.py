"""The searcher and target contracts as checks every registry entry gets (like scikit-learn's
``parametrize_with_checks`` and Gymnasium's env checker): ``tests/search/test_searcher_checks.py``
runs every searcher check over every ``SEARCHERS`` entry on every ``TARGETS`` entry, and
``tests/search/test_target_checks.py`` every target check over every target, so registering
one is the one step that tests it.

A searcher is checked on a cheap model that fails on some profiles and not others: a
Kelvin-Voigt bushing with negative damping (it gives back energy on every cycle, which the
energy criterion flags; steps and holds it passes) against the Table 1 Kelvin-Voigt. A
searcher that refuses a target (a ``SearchError``, e.g. ``certificate`` on the quarter car)
raises ``NotApplicable``. A target is checked with a passive Kelvin-Voigt, 20 % softer than
its reference. Each check raises ``AssertionError`` naming the entry and what broke.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from bushenv.models.base import PAPER_DT
from bushenv.scales import MACHINE
from bushenv.search.base import MAX_KEPT_FAILURES, Candidate, SearchError, SearchResult
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.searchers import SEARCHERS
from bushenv.search.shrink import moves
from bushenv.search.targets import TARGETS, Target

LIMIT_RTOL = 1e-9  # a bound met to rounding is met
FAMILY_POINTS = 6  # unit-cube points per family: both corners, the centre, 3 seeded draws


class NotApplicable(Exception):
    """The searcher refuses the target (it said why with a ``SearchError``)."""


# ----- searchers ---------------------------------------------------------------------------------
class LoggingEvaluator(BatchEvaluator):
    """A ``BatchEvaluator`` that keeps, in order, every judged profile's hash and verdict."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.hashes: list[str] = []
        self.robustness: list[float] = []
        self.diverged: list[bool] = []

    def evaluate(self, profiles):
        batch = super().evaluate(profiles)
        self.hashes += [
            hashlib.sha1(np.asarray(p, np.float64).tobytes()).hexdigest() for p in profiles
        ]
        self.robustness += batch.verdict.robustness.tolist()
        self.diverged += batch.verdict.diverged.tolist()
        return batch


@dataclass
class Run:
    """One search run and everything its evaluator judged, in order."""

    result: SearchResult
    hashes: list[str]
    robustness: np.ndarray
    diverged: np.ndarray


@dataclass
class SearcherTrial:
    """One registered searcher on one target at its ``check_budget``; the first run of each
    seed is kept, so the checks share runs."""

    name: str
    target: str = "rig"
    budget: int | None = None
    _kept: dict[int, Run] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self.entry = SEARCHERS[self.name]
        self.budget = int(self.budget or self.entry.check_budget)
        self.where = f"{self.name} on {self.target}"

    def run(self, seed: int = 0, fresh: bool = False) -> Run:
        if seed in self._kept and not fresh:
            return self._kept[seed]
        model, reference = TARGETS[self.target].check_models("active")
        with LoggingEvaluator(model, reference, self.target) as ev:
            try:
                result = self.entry.make().run(ev, self.budget, seed=seed)
            except SearchError as exc:
                raise NotApplicable(f"{self.name} refuses the {self.target} target: {exc}") from exc
        run = Run(result, ev.hashes, np.array(ev.robustness), np.array(ev.diverged, dtype=bool))
        self._kept.setdefault(seed, run)
        return run


def check_books_the_budget_exactly(trial: SearcherTrial) -> None:
    run = trial.run(0)
    booked, judged = run.result.evaluations, len(run.hashes)
    assert booked == trial.budget, (
        f"{trial.where}: booked {booked} evaluations of a budget of {trial.budget}"
    )
    # an agent's vector env ends episodes together: those past the budget are judged, not booked
    if trial.entry.episodes:
        assert judged >= booked, f"{trial.where}: booked {booked} episodes, judged {judged}"
    else:
        assert judged == booked, f"{trial.where}: judged {judged} profiles, booked {booked}"


def check_records_every_evaluation(trial: SearcherTrial) -> None:
    run = trial.run(0)
    res, n, w = run.result, run.result.evaluations, trial.where
    assert len(run.hashes) >= n, f"{w}: booked {n} evaluations, judged {len(run.hashes)}"
    rob, div = run.robustness[:n], run.diverged[:n]
    failing = (np.flatnonzero(div) + 1).tolist()  # 1-based, as Candidate.evaluation
    assert res.n_failures == len(failing), (
        f"{w}: {len(failing)} judged profiles diverged, the result counts {res.n_failures}"
    )
    first = res.first_failure.evaluation if res.first_failure else None
    assert first == (failing[0] if failing else None), (
        f"{w}: first failure booked at {first}, judged at {failing[:1]}"
    )
    kept = [c.evaluation for c in res.failures]
    assert kept == failing[:MAX_KEPT_FAILURES], f"{w}: kept failures {kept}, judged {failing}"
    assert res.worst is not None and res.worst.robustness == float(np.min(rob)), (
        f"{w}: worst booked {res.worst and res.worst.robustness}, judged {np.min(rob)}"
    )
    covered = sum(int(c[0]) for c in res.coverage.values())
    assert covered == n, f"{w}: coverage counts {covered} profiles of {n}"
    for evals, best in res.history:
        assert best == float(np.min(rob[:evals])), f"{w}: history's best at {evals} is wrong"
    assert res.history and res.history[-1][0] == n, f"{w}: history ends short of {n}"


def _fingerprint(run: Run) -> str:
    """The run without its timings: summary, history, judged profiles, kept profiles."""
    summary = {k: v for k, v in run.result.summary().items() if not k.startswith("seconds")}
    kept = [run.result.worst, *run.result.failures]
    profiles = [hashlib.sha1(c.profile.tobytes()).hexdigest() for c in kept if c is not None]
    text = json.dumps([summary, run.result.history, run.hashes, profiles], default=str)
    return hashlib.sha1(text.encode()).hexdigest()


def check_deterministic_given_a_seed(trial: SearcherTrial) -> None:
    first, again = trial.run(0), trial.run(0, fresh=True)
    assert _fingerprint(first) == _fingerprint(again), f"{trial.where}: two runs with seed 0 differ"


def check_different_seeds_differ(trial: SearcherTrial) -> None:
    a, b = trial.run(0), trial.run(1)
    assert a.hashes != b.hashes, (
        f"{trial.where}: seeds 0 and 1 judged the same {len(a.hashes)} profiles "
        "(raise the entry's check_budget if the seed only shows later)"
    )


def _check_candidate(c: Candidate, n: int, where: str, ndim: int = 1) -> None:
    p = c.profile
    assert isinstance(p, np.ndarray) and p.ndim == ndim and p.size >= 1, f"{where}: profile {p!r}"
    assert np.all(np.isfinite(p)), f"{where}: profile not finite"
    assert isinstance(c.family, str) and c.family, f"{where}: family {c.family!r}"
    assert 1 <= c.evaluation <= n, f"{where}: evaluation {c.evaluation} outside 1..{n}"
    if c.params is not None:
        u = np.asarray(c.params, dtype=np.float64)
        assert np.all((u >= 0) & (u <= 1)), f"{where}: params outside the unit cube: {u}"
    assert c.verdict["robustness"] is None or math.isclose(
        c.verdict["robustness"], c.robustness, rel_tol=1e-9, abs_tol=1e-12
    ), f"{where}: verdict and robustness disagree"
    json.dumps(c.to_json())


def check_returns_a_valid_result(trial: SearcherTrial) -> None:
    res, w = trial.run(0).result, trial.where
    assert isinstance(res, SearchResult), f"{w}: returned {type(res).__name__}"
    got = (res.searcher, res.seed, res.budget, res.env)
    want = (trial.name, 0, trial.budget, trial.target)
    assert got == want, f"{w}: result names (searcher, seed, budget, env) {got}, want {want}"
    assert res.worst is not None, f"{w}: no worst profile"
    n = res.evaluations
    ndim = 2 if TARGETS[trial.target].coords else 1  # (T, k) profiles on a planar target
    _check_candidate(res.worst, n, f"{w}: worst", ndim)
    for c in [res.first_failure, *res.failures]:
        if c is not None:
            _check_candidate(c, n, f"{w}: failure {c.evaluation}", ndim)
            assert c.diverged, f"{w}: kept failure {c.evaluation} did not diverge"
    assert res.n_failures >= len(res.failures), f"{w}: more kept failures than counted"
    evals = [e for e, _ in res.history]
    bests = [b for _, b in res.history]
    assert evals == sorted(evals), f"{w}: history's evaluations go back"
    assert bests == sorted(bests, reverse=True), f"{w}: history's best robustness rises"
    json.dumps(res.summary())


SearcherCheck = Callable[[SearcherTrial], None]
SEARCHER_CHECKS: dict[str, SearcherCheck] = {
    "books_the_budget_exactly": check_books_the_budget_exactly,
    "records_every_evaluation": check_records_every_evaluation,
    "deterministic_given_a_seed": check_deterministic_given_a_seed,
    "different_seeds_differ": check_different_seeds_differ,
    "returns_a_valid_result": check_returns_a_valid_result,
}


def searcher_cases() -> list[tuple[str, str]]:
    """(searcher, target) for every registered searcher on every registered target."""
    return [(s, t) for s in SEARCHERS.names() for t in TARGETS.names()]


# ----- targets -----------------------------------------------------------------------------------
def family_profiles(target: Target, dt: float = PAPER_DT) -> list[tuple[str, np.ndarray]]:
    """(where, profile) for ``FAMILY_POINTS`` unit-cube points of every family of ``target``."""
    out = []
    for k, fam in enumerate(target.families()):
        rng = np.random.default_rng(k)
        points = [np.zeros(fam.dim), np.ones(fam.dim), np.full(fam.dim, 0.5)]
        points += [rng.random(fam.dim) for _ in range(FAMILY_POINTS - len(points))]
        for u in points:
            where = f"{target.name}: family {fam.name} at u = {np.round(u, 3).tolist()}"
            out.append((where, fam.profile(u, dt, limits=MACHINE)))
    return out


def _assert_within(target: Target, x: np.ndarray, dt: float, where: str) -> None:
    height, rate = target.profile_bounds(MACHINE)  # floats, or one per coordinate
    shape = (x.shape[0], len(target.coords)) if target.coords else x.shape[:1]
    assert x.shape == shape and x.shape[0] >= 2, f"{where}: profile of shape {x.shape}"
    assert np.all(np.isfinite(x)), f"{where}: profile not finite"
    assert np.all(x[0] == 0.0), f"{where}: starts at {x[0]!r}, not at rest"
    peak = np.max(np.abs(x), axis=0)
    assert np.all(peak <= np.multiply(height, 1 + LIMIT_RTOL)), (
        f"{where}: |x| reaches {np.round(peak, 9)} > {height}"
    )
    fastest = np.max(np.abs(np.diff(x, axis=0)), axis=0) / dt
    assert np.all(fastest <= np.multiply(rate, 1 + LIMIT_RTOL)), (
        f"{where}: rate {np.round(fastest, 6)} > {rate} m/s"
    )


def check_families_keep_the_env_limits(target: Target) -> None:
    dt = PAPER_DT
    profiles = family_profiles(target, dt)
    assert profiles, f"{target.name}: no excitation family names this target"
    for where, x in profiles:
        _assert_within(target, x, dt, where)
    fam = target.families()[0]
    u = np.full(fam.dim, 0.3)
    assert np.array_equal(fam.profile(u, dt), fam.profile(u, dt)), (
        f"{target.name}: family {fam.name} is not a function of its parameters"
    )


def check_shrink_moves_keep_profiles_valid(target: Target) -> None:
    dt = PAPER_DT
    for where, x in family_profiles(target, dt)[2::FAMILY_POINTS]:  # each family's centre
        for i, c in enumerate(moves(x, dt, target, MACHINE)):
            _assert_within(target, c, dt, f"{where}, shrinking move {i}")


def _judged(target: Target, profiles: list[np.ndarray]):
    model, reference = target.check_models("passive")
    with BatchEvaluator(model, reference, target) as ev:
        return ev.evaluate(profiles)


def check_batched_equals_looped(target: Target) -> None:
    profiles = [x for _, x in family_profiles(target)[3::FAMILY_POINTS]]  # a draw per family
    batch = _judged(target, profiles)
    for b, p in enumerate(profiles):
        one = _judged(target, [p])
        n = p.shape[0]
        for what in ("x", "f_model", "f_ref"):
            together, alone = getattr(batch, what)[:n, b], getattr(one, what)[:n, 0]
            assert np.array_equal(together, alone, equal_nan=True), (
                f"{target.name}: profile {b}'s {what} in a batch of {len(profiles)} differs "
                "from its run alone"
            )
        assert json.dumps(batch.verdict.row(b)) == json.dumps(one.verdict.row(0)), (
            f"{target.name}: profile {b}'s verdict in a batch differs from its verdict alone"
        )


def check_verdict_inputs_are_finite(target: Target) -> None:
    profiles = family_profiles(target)
    batch = _judged(target, [x for _, x in profiles])
    for b, (where, x) in enumerate(profiles):
        n = x.shape[0]
        for what in ("x", "f_model", "f_ref"):
            col = getattr(batch, what)[:n, b]
            assert np.all(np.isfinite(col)), f"{where}: {what} not finite for a passive model"
        rob = batch.verdict.robustness[b]
        assert np.isfinite(rob), f"{where}: robustness {rob} for a passive model"


TargetCheck = Callable[[Target], None]
TARGET_CHECKS: dict[str, TargetCheck] = {
    "families_keep_the_env_limits": check_families_keep_the_env_limits,
    "shrink_moves_keep_profiles_valid": check_shrink_moves_keep_profiles_valid,
    "batched_equals_looped": check_batched_equals_looped,
    "verdict_inputs_are_finite": check_verdict_inputs_are_finite,
}
