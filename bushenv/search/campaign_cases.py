"""Stage 4 of an attack, shrink: a campaign's failures, shrunk and kept as regression cases.

The worst failure per family of the target (up to ``max_shrink``) and, always, any failure of
the hybrid or the control are shrunk (``shrink.py``) to the simplest profile that still fails,
judged on every model of the campaign and written as corpus cases (``corpus.py``) in
``DIR/cases``; with ``save`` they also go to the regression corpus.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv import excitation as ex
from bushenv.progress import Progress
from bushenv.scales import MACHINE, BushingScales
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_recheck import Rechecked
from bushenv.search.campaign_resolve import Resolved
from bushenv.search.campaign_search import Searched
from bushenv.search.corpus import Case, make_case, save_case
from bushenv.search.shrink import shrink


@dataclass(frozen=True)
class Shrunk:
    """The shrunk failures as the report lists them (``shrunk``) and the corpus files added
    (``corpus``: those of a resumed report first)."""

    entries: tuple[Mapping[str, Any], ...]
    corpus: tuple[str, ...] = ()


def near(a: np.ndarray, b: np.ndarray) -> bool:
    """Same length and within 5 % of the larger peak everywhere: one case is enough."""
    if a.size != b.size:
        return False
    peak = max(float(np.max(np.abs(a))), float(np.max(np.abs(b))), 1e-9)
    return float(np.max(np.abs(a - b))) <= 0.05 * peak


def _verdicts(case: Case) -> str:
    return ", ".join(
        f"{m} {'DIVERGES' if e['diverged'] else 'bounded'}" for m, e in case.expect.items()
    )


def shrink_choices(
    resolved: Resolved, searched: Searched, rechecked: Rechecked, max_shrink: int
) -> list[tuple[str, np.ndarray, dict]]:
    """Worst failure per family of the target (up to max_shrink) + any hybrid/control."""
    target = resolved.target_key
    profiles, meta = searched.failures(target)
    best: dict[str, int] = {}
    for i, m in enumerate(meta):
        fam = m["family"]
        if fam not in best or m["verdict"]["robustness"] < meta[best[fam]]["verdict"]["robustness"]:
            best[fam] = i
    order = sorted(best.values(), key=lambda i: meta[i]["verdict"]["robustness"])
    picks = [(target, profiles[i], meta[i]) for i in order[:max_shrink]]
    for key in resolved.models:
        if key == target:
            continue
        ps, ms = searched.failures(key)
        if ps:  # honesty: a hybrid or control failure is always shrunk and reported
            i = int(np.argmin([m["verdict"]["robustness"] for m in ms]))
            picks.append((key, ps[i], ms[i]))
        rc = rechecked.models.get(key, {})
        if rc.get("failures"):
            j = rc["failures"][0]["index"]
            picks.append((key, profiles[j], {**meta[j], "found_on": target}))
    return picks


def _case(resolved: Resolved, config: CampaignConfig, profile, family, params, found_by,
          **extra) -> Case:  # fmt: skip
    """``profile`` judged on every model of the campaign, as a corpus case."""
    judge = resolved.judge
    # a case's scales are one coordinate's (over several the reference's floors judge each)
    scales = judge.scales if isinstance(judge.scales, BushingScales) else MACHINE
    return make_case(
        profile,
        env=config.target,
        axis=resolved.case_axis,
        family=family,
        params=params,
        found_by=found_by,
        models={m.spec: m.model for m in resolved.models.values()},
        reference=judge.reference,
        reference_spec=judge.reference_spec,
        scales=scales,
        static=judge.static,
        judge=judge.describe(),
        shas={m.spec: m.sha256 for m in resolved.models.values()},
        reference_record=resolved.reference_identity(),
        **extra,
    )


class _Keeper:
    """Adds cases to the regression corpus when the campaign saves; lists what it added."""

    def __init__(self, config: CampaignConfig, say, before: tuple[str, ...]) -> None:
        self.config = config
        self.say = say
        self.added: list[str] = list(before)

    def keep(self, case: Case, failed_spec: str | None) -> None:
        """Add ``case`` to the corpus (when saving, and while it still fails)."""
        c, say = self.config, self.say
        if not c.save:
            return
        if failed_spec is not None and not case.expect[failed_spec]["diverged"]:
            say(f"corpus: {case.name} not saved: {failed_spec} no longer fails once stored")
            return
        saved = save_case(case, c.corpus, force=c.force)
        if saved is None:
            if failed_spec is not None:
                say(f"corpus: {case.name} already there (kept; --force to overwrite)")
            return
        say(f"corpus: added {saved}")
        self.added.append(str(saved))


def _moving(resolved: Resolved, profile: np.ndarray) -> list[str] | None:
    """The coordinates a profile over several moves (None over one)."""
    coords = resolved.target.coords
    if not coords:
        return None
    return [a for i, a in enumerate(coords) if np.any(profile[:, i] != 0.0)]


def _shrunk_case(
    resolved: Resolved,
    config: CampaignConfig,
    threads: int,
    progress: Progress,
    keeper: _Keeper,
    key: str,
    profile,
    meta: dict,
    seen: list,
) -> dict | None:
    c, say, out = config, progress.say, config.out
    start = progress.done
    with resolved.evaluator(key, threads) as ev:
        try:
            res = shrink(profile, ev, budget=c.shrink_budget)
        except ValueError as exc:
            say(f"shrink: {key}/{meta['family']}: {exc}")
            return None
    progress.update(start + res.evaluations, f"shrink: {key}/{meta['family']}")
    if any(near(res.profile, other) for other in seen):
        # two failures shrank to (nearly) the same simplest profile: keep one
        say(f"shrink: {key}/{meta['family']} shrank to a profile already kept")
        return None
    seen.append(res.profile)
    model = resolved.models[key]
    found_by = {
        "searcher": meta.get("searcher"),
        "seed": c.seed,
        "model": model.spec,
        "model_sha256": model.sha256,
        "campaign_budget": c.budget,
    }
    moving = _moving(resolved, res.profile)
    notes = (
        ""
        if moving is None
        else f"moving: {', '.join(moving)}; failed in {res.verdict.get('axis')}"
    )
    case = _case(
        resolved, c, res.profile, meta["family"], meta.get("params"), found_by,
        shrink=res.summary(), notes=notes,
    )  # fmt: skip
    path = save_case(case, out / "cases", force=True)
    say(
        f"shrink: {key}/{meta['family']} {res.original} -> {res.final} "
        f"(segments, samples, peak um) in {res.evaluations} evaluations: {_verdicts(case)}"
    )
    keeper.keep(case, model.spec)
    extra = {} if moving is None else {"axis": res.verdict.get("axis"), "moving": moving}
    return {
        "failed_model": key,
        "family": meta["family"],
        **extra,
        "searcher": meta.get("searcher"),
        "shrink": res.summary(),
        "verdicts": case.expect,
        "case_file": str(path.relative_to(out)),
        "name": case.name,
    }


def paper_step_case(
    resolved: Resolved, config: CampaignConfig, progress: Progress, keeper: _Keeper
) -> dict[str, Any]:
    """The papers' own case: a 4 mm step held 10 s, NN said to diverge after 7.3 s."""
    x = ex.step_hold(4e-3, 10.0, resolved.dt, pre_s=0.5)
    target = resolved.models[resolved.target_key]
    found_by = {
        "searcher": "paper (seed 000 §5.2)",
        "seed": None,
        "model": target.spec,
        "model_sha256": target.sha256,
    }
    params = {"size_m": 4e-3, "hold_s": 10.0, "pre_s": 0.5, "rise_s": 0.0}
    notes = (
        "seed 000 §5.2: the papers' NN diverges after 7.3 s of this step; the "
        "verdicts recorded here are what the shipped models do"
    )
    case = _case(resolved, config, x, "step", params, found_by, notes=notes)
    path = save_case(case, config.out / "cases", force=True)
    progress.say(f"paper step (4 mm, 10 s hold): {_verdicts(case)}")
    keeper.keep(case, None)
    return {
        "failed_model": None,
        "family": "step",
        "searcher": "paper",
        "shrink": None,
        "verdicts": case.expect,
        "case_file": str(path.relative_to(config.out)),
        "name": case.name,
    }


def shrink_failures(
    resolved: Resolved,
    searched: Searched,
    rechecked: Rechecked,
    config: CampaignConfig,
    threads: int,
    progress: Progress,
    corpus_before: tuple[str, ...] = (),
) -> Shrunk:
    """Shrink the chosen failures, write their cases; the papers' step when asked for."""
    keeper = _Keeper(config, progress.say, corpus_before)
    shrunk: list[dict] = []
    seen: list[np.ndarray] = []
    for key, profile, meta in shrink_choices(resolved, searched, rechecked, config.max_shrink):
        entry = _shrunk_case(resolved, config, threads, progress, keeper, key, profile, meta, seen)
        if entry is not None:
            shrunk.append(entry)
    if config.paper_step and resolved.target.paper_step:
        shrunk.append(paper_step_case(resolved, config, progress, keeper))
    return Shrunk(tuple(shrunk), tuple(keeper.added))
