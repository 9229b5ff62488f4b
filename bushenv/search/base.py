"""What every searcher shares: the interface, the result and its book-keeping.

Callers run a searcher with ``searcher.run(evaluator, budget, seed) -> SearchResult``. A
searcher implements one hook, ``search(ctx)``: ``ctx`` is a ``SearchContext`` holding the
evaluator, the budget, the run's random generator (seeded by ``run``), the recorder, the seed
and a progress callback. The hook proposes profiles, judges them with
``ctx.evaluator.evaluate(profiles)``, books every one with ``ctx.recorder.record(batch,
families, params)`` and stops when ``ctx.budget`` evaluations are booked. ``run`` builds the
context, calls the hook and returns the result. ``bushenv/search/checks.py`` holds the contract
as checks every ``SEARCHERS`` entry passes.

The budget counts model evaluations (profiles simulated, ``BatchEvaluator.n_evaluations``), the
same unit for every searcher; the result records how many evaluations and seconds it took to
the first failure, the worst profile found (lowest STL robustness, see
``bushenv/divergence.py``) and every failing profile (up to ``MAX_KEPT_FAILURES``). Given the
seed, a run is deterministic.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from bushenv.errors import BadInput

MAX_KEPT_FAILURES = 512


class SearchError(BadInput):
    """Bad searcher name, budget or family."""


@dataclass
class Candidate:
    """One evaluated profile: where it came from and what the verdict said."""

    profile: np.ndarray  # (T,) rig displacement or road height, m
    family: str
    params: list[float] | None  # unit-cube coordinates (None for RL-made profiles)
    robustness: float
    diverged: bool
    verdict: dict  # divergence.Verdict.row
    evaluation: int  # 1-based index of the evaluation that produced it, within its search
    seconds: float  # wall time since the search started when it was evaluated

    def to_json(self) -> dict:
        return {
            "family": self.family,
            "params": self.params,
            "robustness": self.verdict["robustness"],
            "diverged": self.diverged,
            "verdict": self.verdict,
            "evaluation": self.evaluation,
            "seconds": self.seconds,
            "n_samples": int(self.profile.size),
        }


@dataclass
class SearchResult:
    searcher: str
    seed: int
    budget: int
    env: str
    evaluations: int = 0
    seconds: float = 0.0
    first_failure: Candidate | None = None
    worst: Candidate | None = None
    failures: list[Candidate] = field(default_factory=list)
    n_failures: int = 0
    n_reference_unusable: int = 0  # profiles the reference itself could not run
    history: list[tuple[int, float]] = field(default_factory=list)  # (evals, best robustness)
    # per family: [profiles, smallest peak |x|, largest peak |x|, largest |dx/dt|] (m, m/s)
    coverage: dict[str, list[float]] = field(default_factory=dict)

    def coverage_json(self) -> dict[str, dict[str, float]]:
        """What the search tried, per family: profiles, peak deflection range, fastest rate."""
        return {
            fam: {
                "profiles": int(c[0]),
                "peak_mm_min": round(c[1] * 1e3, 4),
                "peak_mm_max": round(c[2] * 1e3, 4),
                "max_rate_m_per_s": round(c[3], 4),
            }
            for fam, c in sorted(self.coverage.items())
        }

    @property
    def diverged(self) -> bool:
        return self.first_failure is not None

    def summary(self) -> dict:
        ff = self.first_failure
        w = self.worst
        return {
            "searcher": self.searcher,
            "seed": self.seed,
            "budget": self.budget,
            "env": self.env,
            "diverged": self.diverged,
            "evaluations": self.evaluations,
            "seconds": round(self.seconds, 3),
            "evaluations_to_failure": ff.evaluation if ff else None,
            "seconds_to_failure": round(ff.seconds, 3) if ff else None,
            "n_failures": self.n_failures,
            "worst_deviation": w.verdict["worst_deviation"] if w else None,
            "worst_robustness": w.verdict["robustness"] if w else None,
            "worst_family": w.family if w else None,
            "worst_criterion": w.verdict["first_criterion"] if w else None,
            "failing_families": sorted({c.family for c in self.failures}),
            "reference_unusable": self.n_reference_unusable,
            "coverage": self.coverage_json(),
        }


class Recorder:
    """Book-keeping shared by all searchers: counts, first failure, worst, kept failures."""

    def __init__(self, result: SearchResult, evaluator) -> None:
        self.result = result
        self.evaluator = evaluator
        self.t0 = time.perf_counter()
        self.best = np.inf

    def record(
        self,
        batch,
        families: list[str],
        params: list[list[float] | None],
        limit: int | None = None,
    ) -> None:
        """Book the first ``limit`` (default: all) profiles of ``batch``."""
        v = batch.verdict
        res = self.result
        now = time.perf_counter() - self.t0
        n = len(families) if limit is None else min(len(families), int(limit))
        unusable = v.reference_unusable
        self._cover(batch, families, n)
        for b in range(n):
            res.evaluations += 1
            if unusable is not None and unusable[b]:
                res.n_reference_unusable += 1
            rob = float(v.robustness[b])
            div = bool(v.diverged[b])
            worse = res.worst is None or rob < res.worst.robustness
            if not (div or worse):
                continue
            cand = Candidate(
                profile=batch.profile(b),
                family=families[b],
                params=params[b],
                robustness=rob,
                diverged=div,
                verdict=v.row(b),
                evaluation=res.evaluations,
                seconds=now,
            )
            if worse:
                res.worst = cand
            if div:
                res.n_failures += 1
                if res.first_failure is None:
                    res.first_failure = cand
                if len(res.failures) < MAX_KEPT_FAILURES:
                    res.failures.append(cand)
        self.best = min(self.best, float(np.min(v.robustness[:n])))
        res.history.append((res.evaluations, self.best))
        res.seconds = now

    def _cover(self, batch, families: list[str], n: int) -> None:
        """Add the first ``n`` profiles' peak deflection and rate to the coverage (of a
        (T, B, k) batch: the largest over its coordinates, m or rad)."""
        x = batch.x[:, :n]
        peak = np.max(np.abs(x), axis=0)
        dt = float(getattr(self.evaluator, "dt", 1.0))
        rate = np.max(np.abs(np.diff(x, axis=0)), axis=0) / dt if x.shape[0] > 1 else peak * 0
        if x.ndim == 3:
            peak, rate = peak.max(axis=-1), rate.max(axis=-1)
        cov = self.result.coverage
        for b in range(n):
            c = cov.setdefault(families[b], [0, np.inf, 0.0, 0.0])
            c[0] += 1
            c[1] = min(c[1], float(peak[b]))
            c[2] = max(c[2], float(peak[b]))
            c[3] = max(c[3], float(rate[b]))


ProgressFn = Callable[[str], None]


def _check_budget(budget: int) -> int:
    budget = int(budget)
    if budget < 1:
        raise SearchError(f"budget must be >= 1 model evaluation, got {budget}")
    return budget


class Evaluator(Protocol):
    """What a searcher may use of its evaluator (``bushenv.search.evaluate.BatchEvaluator``)."""

    target: Any  # bushenv.search.targets.Target: families, limits, RL env
    model: Any  # the BushingModel under attack
    reference: Any  # the BushingModel it is judged against, or None
    dt: float  # s
    axis: str
    scales: Any  # bushenv.scales.BushingScales: stroke, velocity, force floor
    n_evaluations: int

    def evaluate(self, profiles: list[np.ndarray]) -> Any: ...  # a BatchResult


@dataclass(frozen=True)
class SearchContext:
    """Everything one search run gets, fixed for the run (``Searcher.search``'s argument)."""

    evaluator: Evaluator
    budget: int  # evaluations (episodes for RL agents) to book, exactly
    rng: np.random.Generator  # seeded from (seed, searcher name): the run's only randomness
    recorder: Recorder  # book every evaluation here
    seed: int  # for libraries that take a seed of their own (SB3, CMA-ES)
    progress: ProgressFn  # one line of progress; never None


class Searcher(ABC):
    """Base of every searcher: subclasses set ``name`` (their ``SEARCHERS`` name) and
    implement ``search(ctx)``; callers use ``run``."""

    name = ""

    def run(
        self,
        evaluator: Evaluator,
        budget: int,
        seed: int = 0,
        progress: ProgressFn | None = None,
    ) -> SearchResult:
        """Search ``evaluator``'s model for at most ``budget`` evaluations, seeded by ``seed``."""
        budget = _check_budget(budget)
        result = SearchResult(self.name, int(seed), budget, evaluator.target.name)
        recorder = Recorder(result, evaluator)
        rng = np.random.default_rng([int(seed), _stable_id(self.name)])
        ctx = SearchContext(evaluator, budget, rng, recorder, int(seed), progress or _silent)
        self.search(ctx)
        result.seconds = time.perf_counter() - recorder.t0
        return result

    @abstractmethod
    def search(self, ctx: SearchContext) -> None:
        """Propose profiles, ``ctx.evaluator.evaluate`` them, ``ctx.recorder.record`` every
        evaluation, stop once ``ctx.budget`` are booked; draw randomness from ``ctx.rng``."""


def _silent(line: str) -> None:
    pass


def _stable_id(name: str) -> int:
    return sum((i + 1) * ord(c) for i, c in enumerate(name))
