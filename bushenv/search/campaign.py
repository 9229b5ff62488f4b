"""An adversarial campaign against one bushing model (the library behind ``bushenv attack``):
a pipeline of typed stages, each in its own module with its inputs and output explicit.

1. **resolve** (``campaign_resolve``): the judge (vetted), the reference and the models, each
   resolved once, with their roles -> ``Resolved``;
2. **search** (``campaign_search``): each searcher looks for profiles on which the target
   diverges; then the certificate's holds (``campaign_holds``) -> ``Searched``;
3. **recheck** (``campaign_recheck``): the hybrid and the control run every profile that
   broke the target -> ``Rechecked``; then the same searches against them, same budget.
   Divergence thresholds are physical constants (``bushenv/divergence.py``); the control must
   come out clean, and if it does not, the report says so;
4. **shrink** (``campaign_cases``): the worst failures are shrunk to the simplest profile that
   still fails and kept as regression cases -> ``Shrunk``;
5. **report** (``campaign_report``, ``campaign_plots``): ``report.json``, ``report.md``, plots.

``report.json`` in the output folder is rewritten atomically after every step, so an
interrupted campaign resumes where it stopped (``resume=True``): a stage whose result the
report holds is not run again. Its layout is in ``campaign_report.py`` and docs/search.md.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from bushenv.execution import local_cores
from bushenv.persist import write_json, write_text
from bushenv.progress import Progress
from bushenv.search.campaign_cases import Shrunk, shrink_failures
from bushenv.search.campaign_config import CampaignConfig, CampaignError
from bushenv.search.campaign_holds import hold_stage
from bushenv.search.campaign_limits import failure_reach
from bushenv.search.campaign_plots import plot_campaign
from bushenv.search.campaign_recheck import Rechecked, recheck
from bushenv.search.campaign_report import (
    control_flagged,
    fresh_report,
    report_markdown,
    resumed_report,
)
from bushenv.search.campaign_resolve import Resolved, resolve
from bushenv.search.campaign_search import search
from bushenv.search.searchers import SEARCHERS

__all__ = ["Attacked", "CampaignConfig", "CampaignError", "run_attack"]


@dataclass(frozen=True)
class Attacked:
    """A finished attack: its report (as written to ``report_path``) and the keys of the
    target and the control."""

    report: dict[str, Any]
    report_path: Path
    target_key: str
    control_key: str | None

    @property
    def control_flagged(self) -> bool:
        return control_flagged(self.report, self.control_key)


class ReportFile:
    """``report.json`` of one attack: each stage's result goes in and is written at once."""

    def __init__(self, path: Path, data: dict[str, Any]) -> None:
        self.path = path
        self.data = data
        self.seconds_before = float(data["seconds"])
        self.t0 = time.perf_counter()

    def searches(self, key: str) -> dict[str, Any]:
        return self.data["models"][key]["searchers"]

    def save(self) -> None:
        self.data["seconds"] = round(self.seconds_before + time.perf_counter() - self.t0, 3)
        write_json(self.path, self.data)


def work_units(resolved: Resolved, config: CampaignConfig) -> float:
    """Work ahead in evaluation-equivalents (an RL episode costs ``cost`` evaluations)."""
    per_model = sum(config.budget_of(s) * SEARCHERS[s].cost for s in config.searchers)
    shrinks = (config.max_shrink + 2) * config.shrink_budget
    return len(resolved.searched_keys()) * per_model + shrinks


def open_report(resolved: Resolved, config: CampaignConfig, progress: Progress) -> ReportFile:
    """The report: fresh, or what an interrupted run finished (``resume``); written."""
    path = config.out / "report.json"
    data = fresh_report(resolved, config)
    if config.resume and path.exists():
        data = resumed_report(path, data)
        progress.say(f"resuming {path}")
    report = ReportFile(path, data)
    report.save()
    return report


def run_attack(config: CampaignConfig, progress: Progress | None = None) -> Attacked:
    """Every stage (skipping what a resumed report holds); the final report.

    Refuses an existing report unless ``resume`` or ``force`` (``CampaignError``)."""
    progress = progress or Progress(quiet=True)
    c = config.checked()
    path = c.out / "report.json"
    if path.exists() and not (c.resume or c.force):
        raise CampaignError(
            f"{path} exists; pass --resume to continue it or --force to start again"
        )
    resolved = resolve(c, progress.say)
    threads = c.threads or local_cores()
    report = open_report(resolved, c, progress)
    progress.total = work_units(resolved, c)
    for note in resolved.notes:
        progress.say(f"note: {note}")
    where = c.axis if not resolved.target.coords else ", ".join(resolved.target.coords)
    progress.say(
        f"attack: {c.model} ({where}; {c.target}), searchers {','.join(c.searchers)}, "
        f"budget {c.budget} (RL {min(c.budget, c.rl_budget)} episodes), seed {c.seed} "
        f"-> {c.out}"
    )
    done = {k: report.searches(k) for k in resolved.models}

    def filed(key: str, name: str, summary) -> None:
        report.searches(key)[name] = summary
        report.save()

    target = resolved.target_key
    searched = search(resolved, [target], c, threads, progress, done, filed)
    holds = hold_stage(resolved, c, threads, progress, searched)
    if holds.entry is not None:
        report.data["hold_stage"] = holds.entry
    if holds.summary is not None:
        filed(target, "cert-holds", holds.summary)
    searched = searched.merged(holds.searched(resolved, c.out))

    if report.data["recheck"]:
        progress.say("recheck: done earlier (resumed)")
        rechecked = Rechecked.from_json(report.data["recheck"])
    else:
        rechecked = recheck(resolved, searched, threads, progress)
        report.data["recheck"] = rechecked.to_json()
        reach = failure_reach(searched.failures(target)[0], resolved.limits)
        if reach is not None:
            report.data["failure_reach"] = reach
        report.save()

    others = [k for k in resolved.models if resolved.roles[k] in ("hybrid", "control")]
    searched = searched.merged(search(resolved, others, c, threads, progress, done, filed))

    if report.data["shrunk"]:
        progress.say("shrink: done earlier (resumed)")
        shrunk = Shrunk(tuple(report.data["shrunk"]), tuple(report.data["corpus"]))
    else:
        before = tuple(report.data["corpus"])
        shrunk = shrink_failures(resolved, searched, rechecked, c, threads, progress, before)
        report.data["shrunk"] = list(shrunk.entries)
        report.data["corpus"] = list(shrunk.corpus)
        report.save()

    plots = plot_campaign(resolved, searched, shrunk, c.out, threads) if c.plots else []
    report.data["complete"] = True
    report.save()
    write_text(c.out / "report.md", report_markdown(report.data, target, plots))
    return Attacked(report.data, report.path, target, resolved.control_key)
