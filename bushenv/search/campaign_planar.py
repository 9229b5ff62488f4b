"""``bushenv attack --env rig3``: the attack on a planar (three-coordinate) model.

A short pipeline through the one-axis search contracts, as the one-axis attack does it:

1. **resolve** (``campaign_resolve.resolve``, the one stage for any number of coordinates
   -> ``Resolved``): the planar model and the reference (the coupled planar reference unless
   ``--reference``), each with the card beside its file; the **limits** the search drives
   (``Rig3Limits``: for a user's reference, from its card's training records -- else the
   model's card -- 1.5 x their peak |q| and |dq/dt| per coordinate, the one-axis rule;
   ``--stroke-mm`` and ``--max-velocity`` then set the axial and radial ones, the rotation
   keeps its own; for the built-in reference, BushRig3-v0's); the reference vetted within
   them; the **control** (``--control``; for a user's reference a linear model fitted to it
   on its card's records, saved in ``models/control-linear.npz``; else the planar Table-1
   linear preset) and ``--hybrid`` when given;
2. **search**: each searcher on a ``BatchEvaluator`` of the ``rig3`` target, its failing
   profiles (and its worst) saved in ``failures/<model>-<searcher>.npz`` (``load_profiles``
   reads them: (T, 3) each), its coverage per coordinate in its unit;
   then the **hold stage** (``campaign_holds``, over C coordinates): the held vectors a
   network's fixed points mark as suspect, each stepped to and held, judged, filed as a search;
3. **recheck**: the control (which must stay clean) and the hybrid on every saved failure;
4. **shrink**: the first ``max_shrink`` failures shrunk per axis and written as cases
   (``case_file.py``; ``--save`` adds them to the corpus);
5. **report** (``campaign_planar_report``): ``report.json`` (rewritten after every step, so
   ``--resume`` continues an interrupted attack where it stopped: every step is seeded) and
   ``report.md`` in ``--out``.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bushenv.persist import load_profiles, save_profiles, write_json
from bushenv.progress import Progress
from bushenv.search.base import Searcher, SearchError
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_holds import GRID_POINTS, CertificateHolds, listed_vectors
from bushenv.search.campaign_holds import NAME as HOLDS
from bushenv.search.campaign_planar_report import format_planar_table, fresh_report, resumed
from bushenv.search.campaign_resolve import Resolved, resolve
from bushenv.search.campaign_search import MAX_SAVED_FAILURES
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.limits import Rig3Limits, machine_limits
from bushenv.search.planar_models import DEFAULT_REFERENCE
from bushenv.search.searchers import SEARCHERS
from bushenv.search.shrink import shrink
from bushenv.search.target_base import covered_search
from bushenv.search.targets import TARGETS


@dataclass
class PlanarAttack:
    report: dict
    report_path: Path
    control_flagged: bool


def tally(failures) -> dict:
    """Failures by family, by the axis that failed, by criterion; those in a coordinate at rest."""
    fam = Counter(c.family for c in failures)
    axis = Counter(str(c.verdict.get("axis")) for c in failures)
    crit = Counter(str(c.verdict.get("first_criterion")) for c in failures)
    pairs = Counter(f"{c.family}/{c.verdict.get('axis')}" for c in failures)
    coords = TARGETS["rig3"].coords
    at_rest = sum(  # failed in a coordinate the profile never moved: a cross-axis failure
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


FAMILY = "step_hold3"  # the hold stage's profiles, as the coverage names them

# How each of the rig3 target's searchers is held to one family.
HELD_TO = {"random": lambda f: {"families": (f,)}, "cma": lambda f: {"family": f}}


def held_to(searcher: str, family: str) -> dict:
    """The searcher's arguments that hold it to ``family``."""
    if searcher not in HELD_TO:
        raise SearchError(f"{searcher} cannot be held to one family; these can: {list(HELD_TO)}")
    return HELD_TO[searcher](family)


def _searcher(searcher: str | Searcher, family: str | None) -> Searcher:
    if isinstance(searcher, str):
        return SEARCHERS[searcher].make(**({} if family is None else held_to(searcher, family)))
    if family is None:
        return searcher
    raise SearchError("planar_search: family= holds a searcher given by name only")


def planar_search(
    model,
    reference,
    searcher: str | Searcher,
    budget: int,
    seed: int,
    threads: int = 1,
    progress: Callable[[str, int], None] | None = None,
    target: str = "rig3",
    family: str | None = None,
    limits: Rig3Limits | None = None,
    coverage: bool = False,
):
    """One search of the planar attack on the ``rig3`` target within ``limits`` (None:
    BushRig3-v0's); ``progress`` gets each line of the searcher's with the evaluations made
    so far (the population study runs it as it is). ``family``: the searcher held to that
    one family (``one_axis``: the single-axis check). Returns the ``SearchResult``; with
    ``coverage``, (result, coverage per family and coordinate)."""
    s = _searcher(searcher, family)
    with BatchEvaluator(
        model, reference, TARGETS[target], threads=threads, scales=limits or machine_limits()
    ) as ev:
        said = None if progress is None else (lambda msg: progress(msg, ev.n_evaluations))
        result, covered = covered_search(s, ev, budget, seed, said)
    return (result, covered) if coverage else result


def run_planar_attack(config: CampaignConfig, progress: Progress) -> PlanarAttack:
    """The planar attack the config describes (see the module doc)."""
    c = config.checked()
    target = TARGETS[c.target]
    out = Path(c.out)
    report_path = out / "report.json"
    if report_path.exists() and not (c.resume or c.force):
        raise SearchError(
            f"{report_path} exists; pass --resume to continue it or --force to start again"
        )
    for s in c.searchers:
        if s not in target.default_searchers:
            known = ", ".join(target.default_searchers)
            raise SearchError(f"--searchers {s}: the {c.target} target takes {known}")
    p = resolve(c, progress.say)
    model, reference = p.models[p.target_key].model, p.judge.reference
    report = fresh_report(c, p)
    if c.resume and report_path.exists():
        report = resumed(report_path, report)
        progress.say(f"resuming {report_path}")
    t0, before = time.perf_counter(), float(report["seconds"])

    def save() -> None:
        report["seconds"] = round(before + time.perf_counter() - t0, 2)
        out.mkdir(parents=True, exist_ok=True)
        write_json(report_path, report)

    threads = max(1, int(c.threads or 1))
    progress.total = c.budget * len(c.searchers)
    done = {s["searcher"]: s for s in report["searchers"]}
    report["searchers"] = []
    for i, name in enumerate(c.searchers):
        if name in done:
            progress.say(f"[{c.model}] {name}: done earlier (resumed)")
            report["searchers"].append(done[name])
            continue
        report["searchers"].append(_search_one(c, p, name, i * c.budget, threads, progress))
        save()
    if report["hold_stage"] is None:
        report["hold_stage"], summary = _hold_stage(c, p, threads, progress)
        if summary is not None:
            report["searchers"].append(summary)
        save()
    elif HOLDS in done:
        progress.say(f"[{c.model}] {HOLDS}: done earlier (resumed)")
        report["searchers"].append(done[HOLDS])
    failing = _failing(out, report["searchers"])
    profiles = [q for _, q, _ in failing]
    if not report["recheck"]:
        report["recheck"] = {
            role: _recheck(p, key, profiles, threads)
            for role, key in (("control", p.control_key), ("hybrid", p.hybrid_key))
            if key is not None
        }
        for role, r in report["recheck"].items():
            r["model"] = p.control["label"] if role == "control" else p.models[p.hybrid_key].spec
        save()
    reach = failure_reach(profiles, p.limits)
    if reach is not None:
        report["failure_reach"] = reach
    if report["shrunk"] is None:
        report["shrunk"], shown = _shrink_some(p, target, failing, c, progress, out)
    else:
        progress.say("shrink: done earlier (resumed)")
        shown = []
    plots = []
    if c.plots and shown:
        from bushenv.search.campaign_plots import plot_shrunk_coordinates

        shrunk_plots = plot_shrunk_coordinates(model, reference, shown, out / "plots")
        plots = [str(q) for q in shrunk_plots]
    report["plots"] = plots or report["plots"]
    report["complete"] = True
    save()
    (out / "report.md").write_text(format_planar_table(report) + "\n")
    flagged = report["recheck"].get("control", {}).get("diverged", 0) > 0
    return PlanarAttack(report, report_path, flagged)


def _hold_stage(c, p: Resolved, threads: int, progress: Progress) -> tuple[dict, dict | None]:
    """The hold stage (``campaign_holds`` over C coordinates): its report entry and its
    search's."""
    floors = np.array(list(p.judged["force_floors"].values()))
    holds = listed_vectors(p.models[p.target_key].model, p.limits.stroke, floors)
    if holds is None:
        return {"run": False, "why": "not a planar network (no fixed points)"}, None
    stage = CertificateHolds(holds, p.limits.rate, FAMILY)
    if not holds:
        progress.say(f"[{c.model}] {HOLDS}: the fixed points mark no hold")
        return stage.entry(grid_points=GRID_POINTS), None
    progress.total += len(holds)
    summary = _search_one(c, p, HOLDS, progress.total - len(holds), threads, progress, stage,
                          len(holds))  # fmt: skip
    return stage.entry(grid_points=GRID_POINTS), summary


def _search_one(c, p: Resolved, name: str, start: int, threads: int, progress: Progress,
                searcher: Searcher | None = None, budget: int | None = None) -> dict:  # fmt: skip
    """One search (``searcher``, else ``name``'s), its failures and worst saved under
    ``failures/``: its report entry."""
    budget = c.budget if budget is None else budget
    progress.say(f"[{c.model}] {name}: budget {budget} evaluations on {c.target} ...")

    def said(msg: str, evaluations: int) -> None:
        progress.update(start + evaluations, f"  {msg}")

    with p.evaluator(p.target_key, threads) as ev:
        result, covered = covered_search(
            _searcher(searcher or name, None), ev, budget, c.seed,
            lambda msg: said(msg, ev.n_evaluations),
        )  # fmt: skip
    progress.update(start + budget, f"[{c.model}] {name}: {result.n_failures} failures", force=True)
    summary = result.summary()
    summary["coverage"] = covered
    summary["failures"] = tally(result.failures)
    if result.first_failure is not None:
        summary["first_failure"] = {
            "family": result.first_failure.family,
            **result.first_failure.verdict,
        }
    kept = result.failures[:MAX_SAVED_FAILURES]
    profiles, meta = [k.profile for k in kept], [k.to_json() for k in kept]
    if result.worst is not None:
        profiles.append(result.worst.profile)
        meta.append({**result.worst.to_json(), "worst": True})
    path = Path(c.out) / "failures" / f"{p.target_key}-{name}.npz"
    save_profiles(path, profiles, meta)
    summary["profiles_file"] = str(path.relative_to(c.out))
    return summary


def _failing(out: Path, searches: list[dict]) -> list[tuple[str, np.ndarray, dict]]:
    """(searcher, (T, 3) profile, metadata) of every failure the searches saved, in order
    (the worst is saved beside them; when it failed, it is one of them)."""
    rows = []
    for s in searches:
        profiles, meta = load_profiles(out / s["profiles_file"])
        rows += [
            (s["searcher"], q, m)
            for q, m in zip(profiles, meta, strict=True)
            if m.get("diverged") and not m.get("worst")
        ]
    return rows


def failure_reach(profiles: list[np.ndarray], limits: Rig3Limits) -> dict | None:
    """How far beyond the records the failures sit: per profile the largest over the
    coordinates of its peak |q| over the records' (``limits.records_peak``); its median,
    smallest and largest. None when the limits come from no records."""
    seen = None if limits.records_peak is None else np.array(limits.records_peak)
    if seen is None or not profiles or not np.any(seen > 0):
        return None
    moved = seen > 0
    ratio = [float(np.max(np.max(np.abs(q), axis=0)[moved] / seen[moved])) for q in profiles]
    return {
        "failures": len(ratio),
        "median": round(float(np.median(ratio)), 3),
        "min": round(min(ratio), 3),
        "max": round(max(ratio), 3),
        "of": "each failure's largest peak |q| over the records' peak, per coordinate",
    }


def _recheck(p: Resolved, key: str, profiles, threads: int) -> dict:
    if not profiles:
        return {"profiles": 0, "diverged": 0}
    with p.evaluator(key, threads) as ev:
        v = ev.evaluate(profiles).verdict
    axes = Counter(str(a) for a, d in zip(v.first_axis, v.diverged, strict=True) if d)
    return {"profiles": len(profiles), "diverged": int(v.diverged.sum()), "by_axis": dict(axes)}


def _shrink_some(p: Resolved, target, failing, c, progress, out: Path):
    """The first ``max_shrink`` failures shrunk per axis and written as cases: their report
    rows and ``(title, shrunk profile)`` for the plots."""
    from bushenv.models import params_sha
    from bushenv.search.corpus import make_case, save_case

    subject, control = p.models[p.target_key], p.models[p.control_key]
    reference = p.judge.reference
    ref_spec = c.reference or DEFAULT_REFERENCE
    ref_record = {"spec": ref_spec, "file_sha256": None, "params_sha256": params_sha(reference)}
    kept, shown = [], []
    for name, profile, meta in failing[: c.max_shrink]:
        family = meta["family"]
        with p.evaluator(p.target_key) as ev:
            res = shrink(profile, ev, budget=c.shrink_budget)
        moving = [a for i, a in enumerate(target.coords) if np.any(res.profile[:, i] != 0.0)]
        progress.say(
            f"  shrunk a {family} failure ({meta['verdict'].get('axis')}): "
            f"{res.original} -> {res.final}, moving {', '.join(moving)}"
        )
        case = make_case(
            res.profile,
            env=c.target,
            axis="planar",
            family=family,
            params=meta.get("params"),
            found_by={
                "searcher": name,
                "seed": c.seed,
                "model": c.model,
                "model_sha256": subject.sha256,
            },
            models={c.model: subject.model, control.spec: control.model},
            reference=reference,
            reference_spec=ref_spec,
            shas={c.model: subject.sha256, control.spec: control.sha256},
            shrink=res.summary(),
            reference_record=ref_record,
            notes=f"moving: {', '.join(moving)}; failed in {res.verdict.get('axis')}",
        )
        paths = [save_case(case, out / "cases", force=True)]
        if c.save:
            paths.append(save_case(case, c.corpus, force=c.force))
        kept.append(
            {
                "searcher": name,
                "family": family,
                "axis": res.verdict.get("axis"),
                "criterion": res.verdict.get("first_criterion"),
                "moving": moving,
                **res.summary(),
                "cases": [str(q) for q in paths if q is not None],
            }
        )
        shown.append((f"{family}, failed in {res.verdict.get('axis')}", res.profile))
    return kept, shown
