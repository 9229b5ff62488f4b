"""Searchers behind one interface: find profiles on which a model diverges.

Every searcher is ``searcher.run(evaluator, budget, seed) -> SearchResult``. The budget counts
model evaluations (profiles simulated, ``BatchEvaluator.n_evaluations``), the same unit for
every searcher; the result records how many evaluations and seconds it took to the first
failure, the worst profile found (lowest STL robustness, see ``divergence.py``) and every
failing profile (up to ``MAX_KEPT_FAILURES``). Given the seed, a run is deterministic.

| name     | what it does                                                                     |
|----------|----------------------------------------------------------------------------------|
| random   | the baseline: draws a family uniformly and its parameters uniformly in [0, 1]^d,  |
|          | in batches of ``batch_size``                                                      |
| cma      | CMA-ES (the ``cma`` package) minimising the robustness over one family's unit     |
|          | cube, by default the ``any`` family whose first coordinate picks the family; a    |
|          | generation is one batch; restarts from a new random mean when it stalls           |
| ppo, sac | stable-baselines3 agents acting sample by sample in BushRig-v0 / QuarterCar-v0   |
|          | (``bushenv.search.rl``)                                                           |
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from bushenv.search.evaluate import BatchEvaluator, BatchResult
from bushenv.search.families import RIG_FAMILIES, ROAD_FAMILIES, get_family

MAX_KEPT_FAILURES = 512
DEFAULT_RIG_FAMILIES = ("step", "ramp", "pulse", "sine", "chirp", "random_ood", "sequence")


class SearchError(ValueError):
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
    history: list[tuple[int, float]] = field(default_factory=list)  # (evals, best robustness)

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
        }


class Recorder:
    """Book-keeping shared by all searchers: counts, first failure, worst, kept failures."""

    def __init__(self, result: SearchResult, evaluator: BatchEvaluator) -> None:
        self.result = result
        self.evaluator = evaluator
        self.t0 = time.perf_counter()
        self.best = np.inf

    def record(
        self,
        batch: BatchResult,
        families: list[str],
        params: list[list[float] | None],
        limit: int | None = None,
    ) -> None:
        """Book the first ``limit`` (default: all) profiles of ``batch``."""
        v = batch.verdict
        res = self.result
        now = time.perf_counter() - self.t0
        n = len(families) if limit is None else min(len(families), int(limit))
        for b in range(n):
            res.evaluations += 1
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


ProgressFn = Callable[[str], None]


def _check_budget(budget: int) -> int:
    budget = int(budget)
    if budget < 1:
        raise SearchError(f"budget must be >= 1 model evaluation, got {budget}")
    return budget


class Searcher:
    """Base: subclasses implement ``_search(evaluator, budget, rng, recorder)``."""

    name = ""

    def run(
        self,
        evaluator: BatchEvaluator,
        budget: int,
        seed: int = 0,
        progress: ProgressFn | None = None,
    ) -> SearchResult:
        budget = _check_budget(budget)
        result = SearchResult(self.name, int(seed), budget, evaluator.env)
        recorder = Recorder(result, evaluator)
        rng = np.random.default_rng([int(seed), _stable_id(self.name)])
        self._search(evaluator, budget, rng, recorder, seed, progress or (lambda s: None))
        result.seconds = time.perf_counter() - recorder.t0
        return result

    def _search(self, evaluator, budget, rng, recorder, seed, progress) -> None:
        raise NotImplementedError


def _stable_id(name: str) -> int:
    return sum((i + 1) * ord(c) for i, c in enumerate(name))


def _default_families(env: str) -> tuple[str, ...]:
    return DEFAULT_RIG_FAMILIES if env == "rig" else ROAD_FAMILIES


class RandomSearch(Searcher):
    """Uniform random family and parameters; the baseline every other searcher must beat."""

    name = "random"

    def __init__(self, families: tuple[str, ...] | None = None, batch_size: int = 64) -> None:
        self.families = families
        self.batch_size = int(batch_size)

    def _search(self, evaluator, budget, rng, recorder, seed, progress) -> None:
        names = self.families or _default_families(evaluator.env)
        fams = [get_family(n) for n in names]
        for f in fams:
            if f.env != evaluator.env:
                raise SearchError(f"family {f.name!r} is for env {f.env!r}, not {evaluator.env!r}")
        done = 0
        while done < budget:
            n = min(self.batch_size, budget - done)
            picks = rng.integers(0, len(fams), size=n)
            us = [rng.random(fams[i].dim) for i in picks]
            profiles = [fams[i].profile(u, evaluator.dt) for i, u in zip(picks, us, strict=True)]
            batch = evaluator.evaluate(profiles)
            recorder.record(batch, [fams[i].name for i in picks], [u.tolist() for u in us])
            done += n
            progress(f"random {done}/{budget} evals, best robustness {recorder.best:.3g}")


class CMASearch(Searcher):
    """CMA-ES over one family's unit cube (default ``any``: the family is a coordinate too)."""

    name = "cma"

    def __init__(self, family: str | None = None, popsize: int = 16, sigma0: float = 0.3) -> None:
        self.family = family
        self.popsize = int(popsize)
        self.sigma0 = float(sigma0)

    def _search(self, evaluator, budget, rng, recorder, seed, progress) -> None:
        import cma

        name = self.family or ("any" if evaluator.env == "rig" else "bump")
        fam = get_family(name)
        if fam.env != evaluator.env:
            raise SearchError(f"family {name!r} is for env {fam.env!r}, not {evaluator.env!r}")
        done = 0
        restart = 0
        while done < budget:
            opts = {
                "bounds": [0.0, 1.0],
                "popsize": self.popsize,
                "seed": int(rng.integers(1, 2**31 - 1)),
                "verbose": -9,
                "tolfun": 1e-4,
                "tolx": 1e-4,
            }
            es = cma.CMAEvolutionStrategy(rng.random(fam.dim).tolist(), self.sigma0, opts)
            while done < budget and not es.stop():
                xs = es.ask()
                n = min(len(xs), budget - done)
                xs_eval = [np.clip(np.asarray(u), 0.0, 1.0) for u in xs[:n]]
                profiles = [fam.profile(u, evaluator.dt) for u in xs_eval]
                batch = evaluator.evaluate(profiles)
                fams = [_family_label(fam, u) for u in xs_eval]
                recorder.record(batch, fams, [u.tolist() for u in xs_eval])
                done += n
                if n < len(xs):
                    break
                es.tell(xs, [float(r) for r in batch.verdict.robustness])
                progress(
                    f"cma {done}/{budget} evals (restart {restart}), "
                    f"best robustness {recorder.best:.3g}"
                )
            restart += 1


def _family_label(fam, u) -> str:
    """'any' profiles are labelled with the family their first coordinate picked."""
    if fam.name == "any":
        return fam.describe(u)["family"]
    return fam.name


SEARCHERS: dict[str, Callable[..., Searcher]] = {
    "random": RandomSearch,
    "cma": CMASearch,
}


def get_searcher(name: str, **kwargs) -> Searcher:
    if name in ("ppo", "sac"):
        from bushenv.search.rl import RLSearch

        return RLSearch(name, **kwargs)
    if name not in SEARCHERS:
        raise SearchError(f"unknown searcher {name!r}; known: {sorted(SEARCHERS) + ['ppo', 'sac']}")
    return SEARCHERS[name](**kwargs)


__all__ = [
    "Candidate",
    "CMASearch",
    "RandomSearch",
    "RIG_FAMILIES",
    "SearchError",
    "SearchResult",
    "Searcher",
    "get_searcher",
]
