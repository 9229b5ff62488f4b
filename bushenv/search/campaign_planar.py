"""``bushenv attack --env rig3``: the attack on a planar (three-coordinate) model.

A short pipeline through the one-axis search contracts, as the one-axis attack does it:

1. **resolve**: the planar model and the reference (the coupled planar reference unless
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
3. **recheck**: the control (which must stay clean) and the hybrid on every saved failure;
4. **shrink**: the first ``max_shrink`` failures shrunk per axis and written as cases
   (``case_file.py``; ``--save`` adds them to the corpus);
5. **report**: ``report.json`` (rewritten after every step, so ``--resume`` continues an
   interrupted attack where it stopped: every step is seeded) and ``report.md`` in ``--out``.
"""

from __future__ import annotations

import json
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bushenv.persist import atomic_write, json_default, load_profiles, write_json
from bushenv.progress import Progress
from bushenv.search.base import Searcher, SearchError
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_search import MAX_SAVED_FAILURES
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.families_planar import UNITS, Rig3Limits, limits_text, machine_limits
from bushenv.search.planar_models import (  # noqa: F401 (DEFAULT_REFERENCE, vetted_judge: the zoo's)
    DEFAULT_REFERENCE,
    Planar,
    resolve_planar_attack,
    vetted_judge,
)
from bushenv.search.searchers import SEARCHERS
from bushenv.search.shrink import shrink
from bushenv.search.target_rig3 import covered_search
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


def save_profiles3(path: Path, profiles: list[np.ndarray], meta: list[dict]) -> Path:
    """(T_i, 3) profiles in ``persist.save_profiles``'s format (``profiles`` padded to
    (T, B, 3), ``lengths``, ``count``, JSON ``meta``), so ``load_profiles`` reads them back
    (T_i, 3) each; atomic."""
    n = len(profiles)
    arr = np.zeros((max((p.shape[0] for p in profiles), default=1), max(n, 1), 3))
    lengths = np.zeros(max(n, 1), dtype=np.int64)
    for i, p in enumerate(profiles):
        arr[: p.shape[0], i] = p
        lengths[i] = p.shape[0]

    def write(fh) -> None:
        np.savez_compressed(
            fh,
            profiles=arr,
            lengths=lengths,
            count=np.array(n),
            meta=np.array(json.dumps(meta, default=json_default)),
        )

    return atomic_write(path, write)


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
    p = resolve_planar_attack(c, progress)
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
    failing = _failing(out, report["searchers"])
    profiles = [q for _, q, _ in failing]
    if not report["recheck"]:
        report["recheck"] = {
            role: _recheck(p.models[role].model, p.reference, profiles, target, threads, p.limits)
            for role in ("control", "hybrid")
            if role in p.models
        }
        for role, r in report["recheck"].items():
            r["model"] = p.control["label"] if role == "control" else p.models[role].spec
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
        from bushenv.search.campaign_planar_plots import plot_shrunk

        plots = [str(q) for q in plot_shrunk(p.model, p.reference, shown, out / "plots")]
    report["plots"] = plots or report["plots"]
    report["complete"] = True
    save()
    (out / "report.md").write_text(format_planar_table(report) + "\n")
    flagged = report["recheck"].get("control", {}).get("diverged", 0) > 0
    return PlanarAttack(report, report_path, flagged)


def arguments(c: CampaignConfig) -> dict:
    """The settings a resumed planar attack must share with the one it continues."""
    keep = ("stroke_mm", "max_velocity_m_per_s")
    return {**c.arguments(), "searchers": list(c.searchers), **{k: getattr(c, k) for k in keep}}


def fresh_report(c: CampaignConfig, p: Planar) -> dict:
    """The report before any search."""
    return {
        "env": c.target,
        "model": c.model,
        "reference": c.reference or DEFAULT_REFERENCE,
        "judge": p.judge,
        "limits": p.limits.to_json(),
        "control": p.control,
        "budget": c.budget,
        "seed": c.seed,
        "arguments": arguments(c),
        "searchers": [],
        "recheck": {},
        "shrunk": None,
        "plots": [],
        "seconds": 0.0,
        "complete": False,
    }


def resumed(path: Path, fresh: dict) -> dict:
    """The report at ``path`` when it was made with ``fresh``'s arguments; ``SearchError``
    naming the first argument that differs."""
    try:
        old = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise SearchError(f"{path}: cannot resume from it ({exc}); pass --force") from None
    for k, v in fresh["arguments"].items():
        if old.get("arguments", {}).get(k) != v:
            raise SearchError(
                f"--resume: {path} was made with {k}={old.get('arguments', {}).get(k)!r}"
                f", not {v!r}; pass --force to start again"
            )
    return {
        **fresh,
        **{k: old[k] for k in ("searchers", "recheck", "shrunk", "plots", "seconds") if k in old},
    }


def _search_one(c, p: Planar, name: str, start: int, threads: int, progress: Progress) -> dict:
    """One search, its failures and worst saved under ``failures/``: its report entry."""
    progress.say(f"[{c.model}] {name}: budget {c.budget} evaluations on {c.target} ...")

    def said(msg: str, evaluations: int) -> None:
        progress.update(start + evaluations, f"  {msg}")

    result, covered = planar_search(
        p.model,
        p.reference,
        name,
        c.budget,
        c.seed,
        threads,
        said,
        c.target,
        limits=p.limits,
        coverage=True,
    )
    progress.update(
        start + c.budget, f"[{c.model}] {name}: {result.n_failures} failures", force=True
    )
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
    path = Path(c.out) / "failures" / f"{p.models['target'].key}-{name}.npz"
    save_profiles3(path, profiles, meta)
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


def _recheck(model, reference, profiles, target, threads, limits) -> dict:
    if not profiles:
        return {"profiles": 0, "diverged": 0}
    with BatchEvaluator(model, reference, target, threads=threads, scales=limits) as ev:
        v = ev.evaluate(profiles).verdict
    axes = Counter(str(a) for a, d in zip(v.first_axis, v.diverged, strict=True) if d)
    return {"profiles": len(profiles), "diverged": int(v.diverged.sum()), "by_axis": dict(axes)}


def _shrink_some(p: Planar, target, failing, c, progress, out: Path):
    """The first ``max_shrink`` failures shrunk per axis and written as cases: their report
    rows and ``(title, shrunk profile)`` for the plots."""
    from bushenv.models import params_sha
    from bushenv.search.corpus import make_case, save_case

    subject, control, reference = p.models["target"], p.models["control"], p.reference
    ref_spec = c.reference or DEFAULT_REFERENCE
    ref_record = {"spec": ref_spec, "file_sha256": None, "params_sha256": params_sha(reference)}
    kept, shown = [], []
    for name, profile, meta in failing[: c.max_shrink]:
        family = meta["family"]
        with BatchEvaluator(p.model, reference, target, scales=p.limits) as ev:
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
            models={c.model: p.model, control.spec: control.model},
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


def _judge_lines(judge: dict | None) -> list[str]:
    """What judged: the reference's vetting, the floors; marked when trusted despite failing."""
    if not judge:
        return []
    v = judge["vetting"]
    mark = {True: "ok", False: "FAILED", None: "undecided"}
    checks = "; ".join(f"{c['check']} {mark[c['passed']]}" for c in v["checks"])
    floors = ", ".join(f"{k} {x:.4g}" for k, x in judge["force_floors"].items())
    source = judge.get("force_floors_source")
    head = (
        "JUDGED BY A REFERENCE THAT FAILED ITS VETTING (--trust-reference): "
        if (judge["trusted_despite_failed_vetting"])
        else ""
    )
    return [
        f"{head}judge: reference {v['reference']} vetted ({checks}); force floors {floors} "
        f"(N, N, N m){': ' + source if source else ''}",
        "",
    ]


def _limits_lines(report: dict) -> list[str]:
    lim, ctl = report.get("limits"), report.get("control")
    lines = [f"searched within {limits_text(lim)}"] if lim else []
    if ctl:
        lines.append(f"control: {ctl['label']} ({ctl['how']})")
    return [*lines, ""] if lines else []


def _coverage_line(s: dict) -> str | None:
    cov = s.get("coverage") or {}
    coords = TARGETS["rig3"].coords
    if not cov or not all(c in row for row in cov.values() for c in coords):
        return None
    parts = []
    for c, u in zip(coords, UNITS, strict=True):
        top = max(row[c][f"peak_{u}_max"] for row in cov.values())
        parts.append(f"{c} {top:.4g} {u}")
    return f"{s['searcher']}: largest peak tried {', '.join(parts)}"


def format_planar_table(report: dict) -> str:
    """The attack's table: one line per searcher, then what broke it and the rechecks."""
    lines = [
        f"planar attack on {report['model']} ({report['env']}, vs {report['reference']}), "
        f"budget {report['budget']}, seed {report['seed']}",
        "",
        *_judge_lines(report.get("judge")),
        *_limits_lines(report),
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
        covered = _coverage_line(s)
        if f["by_family"] or covered:
            lines.append("")
        if covered:
            lines.append(covered)
        if f["by_family"]:
            lines.append(f"{s['searcher']}: failures by family {json.dumps(f['by_family'])}")
            lines.append(f"{s['searcher']}: failures by axis {json.dumps(f['by_axis'])}")
        if s.get("profiles_file"):
            lines.append(f"{s['searcher']}: failing profiles in {s['profiles_file']}")
    reach = report.get("failure_reach")
    if reach:
        lines.append(
            f"failures reach {reach['median']:.3g}x the records' peak (median; "
            f"{reach['min']:.3g}x to {reach['max']:.3g}x)"
        )
    for role, r in report["recheck"].items():
        who = f" ({r['model']})" if r.get("model") else ""
        lines.append(
            f"recheck {role}{who}: {r['diverged']} of {r['profiles']} failing profiles diverge"
        )
    for k in report["shrunk"] or []:
        lines.append(
            f"shrunk {k['family']} ({k['axis']}, {k['criterion']}): moving {k['moving']}, "
            f"{k['original']['segments']} -> {k['final']['segments']} segments"
        )
    return "\n".join(lines)
