"""``bushenv attack --env rig3``: the attack on a planar (three-coordinate) model.

The one-axis pipeline (``campaign.py``) resolves one-axis models and judges (vetting, static
curve, fitted control); none of that exists for planar models yet, so a planar attack has its
own short pipeline through the same search contracts: the planar model and the coupled planar
reference resolved as BushRig3-v0 resolves them, each searcher run on a ``BatchEvaluator`` of
the ``rig3`` target, the failures rechecked on the control (the planar Table-1 linear model,
which must stay clean) and on ``--hybrid`` when given, the first ``max_shrink`` shrunk per axis
and written as cases (``case_file.py``; ``--save`` adds them to the corpus). ``report.json``
and ``report.md`` in ``--out`` tally the failures by family and by the axis that failed.
"""

from __future__ import annotations

import json
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bushenv.persist import write_json
from bushenv.progress import Progress
from bushenv.search.base import Searcher, SearchError, SearchResult
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.planar_models import resolve_planar_spec, resolved_planar
from bushenv.search.searchers import SEARCHERS
from bushenv.search.shrink import shrink
from bushenv.search.targets import TARGETS

DEFAULT_REFERENCE = "reference"
DEFAULT_CONTROL = "linear"


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


# How each of the rig3 target's searchers is held to one family.
HELD_TO = {"random": lambda f: {"families": (f,)}, "cma": lambda f: {"family": f}}


def held_to(searcher: str, family: str) -> dict:
    """The searcher's arguments that hold it to ``family``."""
    if searcher not in HELD_TO:
        raise SearchError(f"{searcher} cannot be held to one family; these can: {list(HELD_TO)}")
    return HELD_TO[searcher](family)


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
) -> SearchResult:
    """One search of the planar attack on the ``rig3`` target; ``progress`` gets each line of
    the searcher's with the evaluations made so far (the population study runs it as it is).
    ``family``: the searcher held to that one family (``one_axis``: the single-axis check)."""
    if isinstance(searcher, str):
        s = SEARCHERS[searcher].make(**({} if family is None else held_to(searcher, family)))
    elif family is None:
        s = searcher
    else:
        raise SearchError("planar_search: family= holds a searcher given by name only")
    with BatchEvaluator(model, reference, TARGETS[target], threads=threads) as ev:
        said = None if progress is None else (lambda msg: progress(msg, ev.n_evaluations))
        return s.run(ev, budget, seed=seed, progress=said)


def _recheck(model, reference, profiles, target, threads) -> dict:
    if not profiles:
        return {"profiles": 0, "diverged": 0}
    with BatchEvaluator(model, reference, target, threads=threads) as ev:
        v = ev.evaluate(profiles).verdict
    axes = Counter(str(a) for a, d in zip(v.first_axis, v.diverged, strict=True) if d)
    return {"profiles": len(profiles), "diverged": int(v.diverged.sum()), "by_axis": dict(axes)}


def run_planar_attack(config: CampaignConfig, progress: Progress) -> PlanarAttack:
    """The planar attack the config describes (see the module doc)."""
    c = config.checked()
    target = TARGETS[c.target]
    out = Path(c.out)
    report_path = out / "report.json"
    if c.resume:
        raise SearchError("--resume: a planar attack is not resumable yet; run it with --force")
    if report_path.exists() and not c.force:
        raise SearchError(f"{report_path} exists: pass --force to overwrite it")
    for s in c.searchers:
        if s not in target.default_searchers:
            known = ", ".join(target.default_searchers)
            raise SearchError(f"--searchers {s}: the {c.target} target takes {known}")
    model = resolve_planar_spec(c.model, None, "--model")
    reference = resolve_planar_spec(c.reference or DEFAULT_REFERENCE, model.dt, "--reference")
    others = {"control": resolve_planar_spec(c.control or DEFAULT_CONTROL, model.dt, "--control")}
    if c.hybrid and c.hybrid != "none":
        others["hybrid"] = resolve_planar_spec(c.hybrid, model.dt, "--hybrid")
    judge = vetted_judge(
        reference,
        str(c.reference or DEFAULT_REFERENCE),
        target,
        progress,
        model=model,
        model_file=c.model if str(c.model).endswith(".npz") else None,
        trust=c.trust_reference,
    )
    threads = max(1, int(c.threads or 1))
    t0 = time.perf_counter()
    searches, failing = [], []
    total = c.budget * len(c.searchers)
    progress.total = total
    done = 0
    for name in c.searchers:
        progress.say(f"[{c.model}] {name}: budget {c.budget} evaluations on {c.target} ...")

        def said(msg: str, evaluations: int, start=done) -> None:
            progress.update(start + evaluations, f"  {msg}")

        result = planar_search(model, reference, name, c.budget, c.seed, threads, said, c.target)
        done += c.budget
        progress.update(done, f"[{c.model}] {name}: {result.n_failures} failures", force=True)
        summary = result.summary()
        summary["failures"] = tally(result.failures)
        if result.first_failure is not None:
            summary["first_failure"] = {
                "family": result.first_failure.family,
                **result.first_failure.verdict,
            }
        searches.append(summary)
        failing += [(name, f) for f in result.failures]
    profiles = [f.profile for _, f in failing]
    rechecks = {
        role: _recheck(m, reference, profiles, target, threads) for role, m in others.items()
    }
    shrunk, shown = _shrink_some(model, reference, target, failing, c, progress, out)
    plots = []
    if c.plots and shown:
        from bushenv.search.campaign_planar_plots import plot_shrunk

        plots = [str(p) for p in plot_shrunk(model, reference, shown, out / "plots")]
    report = {
        "env": c.target,
        "model": c.model,
        "reference": c.reference or DEFAULT_REFERENCE,
        "judge": judge,
        "budget": c.budget,
        "seed": c.seed,
        "searchers": searches,
        "recheck": rechecks,
        "shrunk": shrunk,
        "plots": plots,
        "seconds": round(time.perf_counter() - t0, 2),
    }
    out.mkdir(parents=True, exist_ok=True)
    write_json(report_path, report)
    (out / "report.md").write_text(format_planar_table(report) + "\n")
    flagged = rechecks.get("control", {}).get("diverged", 0) > 0
    return PlanarAttack(report, report_path, flagged)


def vetted_judge(
    reference,
    ref_spec: str,
    target,
    progress: Progress,
    model=None,
    model_file=None,
    trust: bool = False,
    error: type[Exception] = SearchError,
) -> dict:
    """The reference checked before it judges (``planar.vetting``): ``error`` when it fails,
    unless ``trust``; what judged (the vetting, floors, stroke) for a report."""
    from bushenv.planar.vetting import vet_planar_reference
    from bushenv.search.target_rig3 import reference_floors

    stroke, _ = target.profile_bounds()
    floors, floors_source = reference_floors(reference)
    vetting = vet_planar_reference(
        reference,
        ref_spec,
        stroke,
        floors,
        reference_file=ref_spec if ref_spec.endswith(".npz") else None,
        model=model,
        model_file=model_file,
    )
    for line in vetting.lines():
        progress.say(f"reference {ref_spec}: {line}")
    if not vetting.passed and not trust:
        raise error(
            f"the reference {ref_spec} failed its vetting ({vetting.summary()}): it cannot judge; "
            "give another --reference, or pass --trust-reference to judge with it anyway "
            "(every verdict is then marked)"
        )
    return {
        "vetting": vetting.describe(),
        "trusted_despite_failed_vetting": bool(not vetting.passed),
        "force_floors": dict(zip(target.coords, floors.tolist(), strict=True)),
        "force_floors_source": floors_source,
        "stroke": dict(zip(target.coords, np.asarray(stroke).tolist(), strict=True)),
    }


def _shrink_some(model, reference, target, failing, c, progress, out: Path):
    """The first ``max_shrink`` failures shrunk per axis and written as cases: their report
    rows and ``(title, shrunk profile)`` for the plots."""
    from bushenv.models import params_sha
    from bushenv.search.corpus import make_case, save_case

    control = resolved_planar(c.control or DEFAULT_CONTROL, model.dt, "--control")
    subject = resolved_planar(c.model, model.dt, "--model")
    ref_spec = c.reference or DEFAULT_REFERENCE
    ref_record = {"spec": ref_spec, "file_sha256": None, "params_sha256": params_sha(reference)}
    kept, shown = [], []
    for name, cand in failing[: c.max_shrink]:
        with BatchEvaluator(model, reference, target) as ev:
            res = shrink(cand.profile, ev, budget=c.shrink_budget)
        moving = [a for i, a in enumerate(target.coords) if np.any(res.profile[:, i] != 0.0)]
        progress.say(
            f"  shrunk a {cand.family} failure ({cand.verdict.get('axis')}): "
            f"{res.original} -> {res.final}, moving {', '.join(moving)}"
        )
        case = make_case(
            res.profile,
            env=c.target,
            axis="planar",
            family=cand.family,
            params=cand.params,
            found_by={
                "searcher": name,
                "seed": c.seed,
                "model": c.model,
                "model_sha256": subject.sha256,
            },
            models={c.model: model, control.spec: control.model},
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
                "family": cand.family,
                "axis": res.verdict.get("axis"),
                "criterion": res.verdict.get("first_criterion"),
                "moving": moving,
                **res.summary(),
                "cases": [str(p) for p in paths if p is not None],
            }
        )
        shown.append((f"{cand.family}, failed in {res.verdict.get('axis')}", res.profile))
    return kept, shown


def _judge_lines(judge: dict | None) -> list[str]:
    """What judged: the reference's vetting, the floors; marked when trusted despite failing."""
    if not judge:
        return []
    v = judge["vetting"]
    mark = {True: "ok", False: "FAILED", None: "undecided"}
    checks = "; ".join(f"{c['check']} {mark[c['passed']]}" for c in v["checks"])
    floors = ", ".join(f"{k} {x:.4g}" for k, x in judge["force_floors"].items())
    source = judge.get("force_floors_source")
    head = "JUDGED BY A REFERENCE THAT FAILED ITS VETTING (--trust-reference): " if (
        judge["trusted_despite_failed_vetting"]) else ""  # fmt: skip
    return [f"{head}judge: reference {v['reference']} vetted ({checks}); force floors {floors} "
            f"(N, N, N m){': ' + source if source else ''}", ""]  # fmt: skip


def format_planar_table(report: dict) -> str:
    """The attack's table: one line per searcher, then what broke it and the rechecks."""
    lines = [
        f"planar attack on {report['model']} ({report['env']}, vs {report['reference']}), "
        f"budget {report['budget']}, seed {report['seed']}",
        "",
        *_judge_lines(report.get("judge")),
        "| searcher | failures / evaluations | first failure at | first: family (axis) | "
        "worst robustness |",
        "|---|---|---|---|---|",
    ]
    for s in report["searchers"]:
        ff = s.get("first_failure")
        first = f"{ff['family']} ({ff.get('axis')})" if ff else "-"
        worst = s.get("worst_robustness")
        lines.append(
            f"| {s['searcher']} | {s['n_failures']} / {s['evaluations']} | "
            f"{s['evaluations_to_failure'] or '-'} | {first} | "
            f"{'-' if worst is None else f'{worst:.3g}'} |"
        )
    for s in report["searchers"]:
        f = s["failures"]
        if f["by_family"]:
            lines.append("")
            lines.append(f"{s['searcher']}: failures by family {json.dumps(f['by_family'])}")
            lines.append(f"{s['searcher']}: failures by axis {json.dumps(f['by_axis'])}")
    for role, r in report["recheck"].items():
        lines.append(f"recheck {role}: {r['diverged']} of {r['profiles']} failing profiles diverge")
    for k in report["shrunk"]:
        lines.append(
            f"shrunk {k['family']} ({k['axis']}, {k['criterion']}): moving {k['moving']}, "
            f"{k['original']['segments']} -> {k['final']['segments']} segments"
        )
    return "\n".join(lines)
