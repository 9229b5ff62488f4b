"""The searchers, and ``SEARCHERS``: the one list of them.

| name     | what it does                                                                     |
|----------|----------------------------------------------------------------------------------|
| random   | the baseline: draws a family uniformly and its parameters uniformly in [0, 1]^d,  |
|          | in batches of ``batch_size``                                                      |
| cma      | CMA-ES (the ``cma`` package) minimising the robustness over one family's unit     |
|          | cube, by default the target's (the rig's ``any``, whose first coordinate picks    |
|          | the family); a generation is one batch; restarts from a new random mean when it   |
|          | stalls                                                                            |
| certificate | steps to the holds and sines in the bands the model's certificates find     |
|          | weakest (``bushenv.search.guided``; a sweep for models it cannot read)           |
| ppo, sac | stable-baselines3 agents acting sample by sample in the target's vector env      |
|          | (``bushenv.search.rl``)                                                           |

The interface and the result they share: ``bushenv/search/base.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bushenv.registry import Registry, load_entry_point
from bushenv.search.base import SearchContext, Searcher, SearchError


class RandomSearch(Searcher):
    """Uniform random family and parameters; the baseline every other searcher must beat."""

    name = "random"

    def __init__(self, families: tuple[str, ...] | None = None, batch_size: int = 64) -> None:
        self.families = families
        self.batch_size = int(batch_size)

    def search(self, ctx: SearchContext) -> None:
        evaluator, budget, rng, recorder = ctx.evaluator, ctx.budget, ctx.rng, ctx.recorder
        target = evaluator.target
        names = self.families or target.random_families()
        fams = [target.family(n) for n in names]
        done = 0
        while done < budget:
            n = min(self.batch_size, budget - done)
            picks = rng.integers(0, len(fams), size=n)
            us = [rng.random(fams[i].dim) for i in picks]
            lim = evaluator.scales
            profiles = [
                fams[i].profile(u, evaluator.dt, limits=lim) for i, u in zip(picks, us, strict=True)
            ]
            batch = evaluator.evaluate(profiles)
            recorder.record(batch, [fams[i].name for i in picks], [u.tolist() for u in us])
            done += n
            ctx.progress(f"random {done}/{budget} evals, best robustness {recorder.best:.3g}")


class CMASearch(Searcher):
    """CMA-ES over one family's unit cube (default ``any``: the family is a coordinate too)."""

    name = "cma"

    def __init__(self, family: str | None = None, popsize: int = 16, sigma0: float = 0.3) -> None:
        self.family = family
        self.popsize = int(popsize)
        self.sigma0 = float(sigma0)

    def search(self, ctx: SearchContext) -> None:
        evaluator, budget, rng, recorder = ctx.evaluator, ctx.budget, ctx.rng, ctx.recorder
        import cma

        fam = evaluator.target.family(self.family or evaluator.target.cma_family)
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
                profiles = [fam.profile(u, evaluator.dt, limits=evaluator.scales) for u in xs_eval]
                batch = evaluator.evaluate(profiles)
                fams = [_family_label(fam, u) for u in xs_eval]
                recorder.record(batch, fams, [u.tolist() for u in xs_eval])
                done += n
                if n < len(xs):
                    break
                es.tell(xs, [float(r) for r in batch.verdict.robustness])
                ctx.progress(
                    f"cma {done}/{budget} evals (restart {restart}), "
                    f"best robustness {recorder.best:.3g}"
                )
            restart += 1


def _family_label(fam, u) -> str:
    """Meta-family profiles ('any', 'any3') are labelled with the family their first
    coordinate picked."""
    if not fam.random:
        return fam.describe(u)["family"]
    return fam.name


@dataclass(frozen=True)
class SearcherEntry:
    """A registered searcher: how to make it and what its budget counts."""

    factory: Callable[..., Searcher] | str  # or "module:attribute"
    summary: str
    episodes: bool = False  # RL agents: the budget counts episodes, capped by --rl-budget
    cost: float = 1.0  # wall time per evaluation relative to a batched search (progress only)
    # the budget the contract checks (``checks.py``) run it at: small, yet past any proposals
    # it makes before it draws on its seed
    check_budget: int = 13

    def make(self, **kwargs) -> Searcher:
        f = self.factory
        return (load_entry_point(f) if isinstance(f, str) else f)(**kwargs)


SEARCHERS: Registry[SearcherEntry] = Registry("searcher", SearchError)
SEARCHERS.add("random", SearcherEntry(RandomSearch, "uniform random families and parameters"))
SEARCHERS.add("cma", SearcherEntry(CMASearch, "CMA-ES over the target's search family"))
SEARCHERS.add(
    "certificate",
    SearcherEntry(
        "bushenv.search.guided:CertificateSearch",
        "steps to the holds and sines in the bands the model's certificates find weakest",
        check_budget=64,  # its sweep (57 profiles for a model it cannot read) comes first
    ),
)
SEARCHERS.add(
    "ppo",
    SearcherEntry(
        "bushenv.search.rl:PPOSearch", "PPO agent (SB3)", episodes=True, cost=8.0, check_budget=3
    ),
)
SEARCHERS.add(
    "sac",
    SearcherEntry(
        "bushenv.search.rl:SACSearch", "SAC agent (SB3)", episodes=True, cost=8.0, check_budget=3
    ),
)


def get_searcher(name: str, **kwargs) -> Searcher:
    """A fresh searcher registered as ``name`` (``SEARCHERS``)."""
    return SEARCHERS[name].make(**kwargs)


__all__ = ["CMASearch", "RandomSearch", "SEARCHERS", "SearcherEntry", "get_searcher"]
