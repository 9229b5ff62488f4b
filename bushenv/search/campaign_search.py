"""Stage 2 of an attack, search: each searcher against each model, same budget (RL agents at
most ``rl_budget`` episodes); every search's failing profiles kept in
``failures/<model>-<searcher>.npz`` for the recheck and the shrink.

``run_search`` is one search on a ``Resolved`` model (a cell of ``bushenv campaign`` and a
member of the zoo call it as it is); ``search`` runs an attack's searches and returns
``Searched``.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from bushenv.persist import load_profiles, save_profiles
from bushenv.progress import Progress
from bushenv.scales import MACHINE
from bushenv.search.base import Searcher, SearchError, SearchResult
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_resolve import Resolved
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.limits import machine_limits
from bushenv.search.searchers import SEARCHERS, get_searcher
from bushenv.search.target_base import covered_search
from bushenv.search.targets import TARGETS

MAX_SAVED_FAILURES = 256  # profiles per search written to failures/*.npz for the recheck

Summary = Mapping[str, Any]  # SearchResult.summary() with first_failure, worst, profiles_file


@dataclass(frozen=True)
class Searched:
    """Every search's summary by model key and searcher (those a resumed report held, as it
    held them); the profiles are in the files the summaries name, under ``out``."""

    out: Path
    runs: Mapping[str, Mapping[str, Summary]]

    def of(self, key: str) -> Mapping[str, Summary]:
        return self.runs.get(key, MappingProxyType({}))

    def failures(self, key: str) -> tuple[list[np.ndarray], list[dict]]:
        """Every failing profile the searches against ``key`` kept, with its metadata (a
        search's worst is saved beside its failures: when it failed, it is one of them)."""
        profiles, meta = [], []
        for name, summary in self.of(key).items():
            f = summary.get("profiles_file")
            if not f:
                continue
            ps, ms = load_profiles(self.out / f)
            for p, m in zip(ps, ms, strict=True):
                if m.get("diverged") and not m.get("worst"):
                    profiles.append(p)
                    meta.append({**m, "searcher": name})
        return profiles, meta

    def worst(self, key: str) -> list[tuple[str, np.ndarray, dict]]:
        """(searcher, profile, metadata) of each search's worst profile on ``key``."""
        rows = []
        for name, summary in self.of(key).items():
            f = summary.get("profiles_file")
            if f:
                ps, ms = load_profiles(self.out / f)
                worst = [(p, m) for p, m in zip(ps, ms, strict=True) if m.get("worst")]
                if worst:
                    rows.append((name, *worst[0]))
        return rows

    def merged(self, other: Searched) -> Searched:
        """These runs and ``other``'s (per model, ``other`` after these)."""
        runs = {k: dict(v) for k, v in self.runs.items()}
        for k, v in other.runs.items():
            runs.setdefault(k, {}).update(v)
        return Searched(self.out, _frozen(runs))


def _frozen(runs: dict[str, dict[str, Summary]]) -> Mapping[str, Mapping[str, Summary]]:
    return MappingProxyType({k: MappingProxyType(dict(v)) for k, v in runs.items()})


def run_search(
    resolved: Resolved,
    key: str,
    searcher: str | Searcher,
    budget: int,
    seed: int,
    threads: int = 1,
    progress: Callable[[str, int], None] | None = None,
) -> SearchResult:
    """One search against model ``key`` with ``budget`` evaluations; ``progress`` gets each
    line of the searcher's with the evaluations made so far."""
    s = get_searcher(searcher) if isinstance(searcher, str) else searcher
    with resolved.evaluator(key, threads) as ev:
        said = None if progress is None else (lambda msg: progress(msg, ev.n_evaluations))
        return s.run(ev, budget, seed=seed, progress=said)


def _covered(resolved: Resolved, key: str, searcher: str | Searcher, budget: int, seed: int,
             threads: int, progress: Callable[[str, int], None]):  # fmt: skip
    """``run_search`` and, over several coordinates, what it tried per family and coordinate
    (``covered_search``: the same seeding, the same result); (result, coverage or None)."""
    if not resolved.target.coords:
        return run_search(resolved, key, searcher, budget, seed, threads, progress), None
    s = get_searcher(searcher) if isinstance(searcher, str) else searcher
    with resolved.evaluator(key, threads) as ev:
        return covered_search(s, ev, budget, seed, lambda msg: progress(msg, ev.n_evaluations))


def tally(failures, coords: tuple[str, ...]) -> dict:
    """Failures by family, by the coordinate that failed, by criterion; and those that failed
    in a coordinate the profile never moved (a cross-coordinate failure)."""
    fam = Counter(c.family for c in failures)
    axis = Counter(str(c.verdict.get("axis")) for c in failures)
    crit = Counter(str(c.verdict.get("first_criterion")) for c in failures)
    pairs = Counter(f"{c.family}/{c.verdict.get('axis')}" for c in failures)
    at_rest = sum(
        1
        for c in failures
        if c.verdict.get("axis") in coords
        and not np.any(c.profile[:, coords.index(c.verdict["axis"])])
    )
    return {
        "in_a_coordinate_at_rest": at_rest,
        "by_family": dict(fam.most_common()),
        "by_axis": dict(axis.most_common()),
        "by_criterion": dict(crit.most_common()),
        "by_family_axis": dict(pairs.most_common()),
    }


def search_one(
    resolved: Resolved,
    key: str,
    name: str,
    config: CampaignConfig,
    threads: int,
    progress: Progress,
    searcher: Searcher | None = None,
    budget: int | None = None,
) -> dict[str, Any]:
    """One search of an attack, its failing profiles kept: its summary for the report."""
    out = config.out
    budget = config.budget_of(name) if budget is None else budget
    cost = SEARCHERS[name].cost if searcher is None else 1.0
    progress.say(f"[{key}] {name}: budget {budget} evaluations ...")
    start = progress.done

    def report(msg: str, evaluations: int) -> None:
        progress.update(start + cost * evaluations, f"[{key}]   {msg}")

    res, covered = _covered(resolved, key, searcher or name, max(1, budget), config.seed,
                            threads, report)  # fmt: skip
    progress.done = start + cost * budget
    summary = res.summary()
    if covered is not None:  # over C coordinates: per family and coordinate, in its unit
        summary["coverage"] = covered
        summary["failures"] = tally(res.failures, resolved.target.coords)
    judge, dt = resolved.judge, resolved.dt
    if res.first_failure is not None:
        summary["first_failure"] = res.first_failure.to_json()
        summary["first_failure"]["reference_in_envelope"] = judge.in_envelope(
            res.first_failure.profile, dt
        )
    outside = [judge.in_envelope(c.profile, dt) is False for c in res.failures]
    summary["failures_reference_outside_envelope"] = int(sum(outside))
    if judge.has_unvetted_regions:  # trusted despite failing there: verdicts there unvetted
        if res.first_failure is not None:
            summary["first_failure"]["reference_unvetted_here"] = judge.in_unvetted_range(
                res.first_failure.profile, dt
            )
        unvetted = [bool(judge.in_unvetted_range(c.profile, dt)) for c in res.failures]
        summary["failures_in_unvetted_range"] = int(sum(unvetted))
    if res.worst is not None:
        summary["worst"] = res.worst.to_json()
    kept = res.failures[:MAX_SAVED_FAILURES]
    profiles = [c.profile for c in kept]
    meta = [c.to_json() for c in kept]
    if res.worst is not None:
        profiles.append(res.worst.profile)
        meta.append({**res.worst.to_json(), "worst": True})
    path = out / "failures" / f"{key}-{name}.npz"
    save_profiles(path, profiles, meta)
    summary["profiles_file"] = str(path.relative_to(out))
    outcome = (
        f"DIVERGED after {summary['evaluations_to_failure']} evaluations "
        f"({summary['seconds_to_failure']:.2f} s), {res.n_failures} failing profiles"
        if res.diverged
        else f"no divergence in {res.evaluations} evaluations"
    )
    progress.say(
        f"[{key}] {name}: {outcome}; worst robustness {summary['worst_robustness']:.3g} "
        f"({res.seconds:.1f} s)"
    )
    return summary


def search(
    resolved: Resolved,
    keys: list[str],
    config: CampaignConfig,
    threads: int,
    progress: Progress,
    done: Mapping[str, Mapping[str, Summary]],
    on_search: Callable[[str, str, Summary], None] = lambda key, name, summary: None,
) -> Searched:
    """Every searcher of ``config`` against each of ``keys``; a search ``done`` holds (a
    resumed report's) is not run again. ``on_search`` gets each new summary as it is made."""
    runs: dict[str, dict[str, Summary]] = {}
    for key in keys:
        runs[key] = dict(done.get(key, {}))
        for name in config.searchers:
            if name in runs[key]:
                progress.say(f"[{key}] {name}: done earlier (resumed)")
                progress.done += config.budget_of(name) * SEARCHERS[name].cost
                continue
            runs[key][name] = search_one(resolved, key, name, config, threads, progress)
            on_search(key, name, runs[key][name])
    return Searched(config.out, _frozen(runs))


# How each searcher that can be is held to one family (the zoo's single-axis check).
HELD_TO = {"random": lambda f: {"families": (f,)}, "cma": lambda f: {"family": f}}


def held_to(searcher: str, family: str) -> dict:
    """The searcher's arguments that hold it to ``family``."""
    if searcher not in HELD_TO:
        raise SearchError(f"{searcher} cannot be held to one family; these can: {list(HELD_TO)}")
    return HELD_TO[searcher](family)


def family_search(
    model,
    reference,
    searcher: str | Searcher,
    budget: int,
    seed: int,
    *,
    target: str = "rig3",
    family: str | None = None,
    limits=None,
    threads: int = 1,
    progress: Callable[[str, int], None] | None = None,
) -> SearchResult:
    """One search of ``model`` against ``reference`` on ``target`` within ``limits`` (None: the
    machine's), outside an attack (the zoo runs it on every member); ``family``: the searcher
    (given by name) held to that one family. ``progress`` gets each line of the searcher's with
    the evaluations made so far."""
    if isinstance(searcher, str):
        s = get_searcher(searcher, **({} if family is None else held_to(searcher, family)))
    elif family is None:
        s = searcher
    else:
        raise SearchError("family_search: family= holds a searcher given by name only")
    scales = limits or (machine_limits() if TARGETS[target].coords else MACHINE)
    with BatchEvaluator(model, reference, TARGETS[target], threads=threads, scales=scales) as ev:
        said = None if progress is None else (lambda msg: progress(msg, ev.n_evaluations))
        return s.run(ev, budget, seed=seed, progress=said)
