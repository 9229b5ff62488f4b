"""A campaign's failures, shrunk and kept: which to shrink, shrinking, the regression cases.

The worst failure per family of the target (up to ``max_shrink``) and, always, any failure of
the hybrid or the control are shrunk (``shrink.py``) to the simplest profile that still fails,
judged on every model of the campaign and written as corpus cases (``corpus.py``) in
``DIR/cases``; with ``save`` they also go to the regression corpus.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv import excitation as ex
from bushenv.search.corpus import Case, make_case, model_sha, save_case
from bushenv.search.shrink import shrink


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


def shrink_choices(campaign) -> list[tuple[str, np.ndarray, dict]]:
    """Worst failure per family of the target (up to max_shrink) + any hybrid/control."""
    target = campaign.target_key
    profiles, meta = campaign.failures_of(target)
    best: dict[str, int] = {}
    for i, m in enumerate(meta):
        fam = m["family"]
        if fam not in best or m["verdict"]["robustness"] < meta[best[fam]]["verdict"]["robustness"]:
            best[fam] = i
    order = sorted(best.values(), key=lambda i: meta[i]["verdict"]["robustness"])
    picks = [(target, profiles[i], meta[i]) for i in order[: campaign.config.max_shrink]]
    for key in campaign.models:
        if key == target:
            continue
        ps, ms = campaign.failures_of(key)
        if ps:  # honesty: a hybrid or control failure is always shrunk and reported
            i = int(np.argmin([m["verdict"]["robustness"] for m in ms]))
            picks.append((key, ps[i], ms[i]))
        rc = campaign.report["recheck"].get(key, {})
        if rc.get("failures"):
            j = rc["failures"][0]["index"]
            picks.append((key, profiles[j], {**meta[j], "found_on": target}))
    return picks


def _case(campaign, profile, family, params, found_by, **extra) -> Case:
    """``profile`` judged on every model of the campaign, as a corpus case."""
    c = campaign.config
    shas = {k: model_sha(campaign.specs[k], c.axis) for k in campaign.models}
    return make_case(
        profile,
        env=c.target,
        axis=c.axis,
        family=family,
        params=params,
        found_by=found_by,
        models={campaign.specs[k]: m for k, m in campaign.models.items()},
        reference=campaign.reference,
        reference_spec=campaign.reference_spec,
        scales=campaign.scales,
        static=campaign.static,
        judge=campaign.judge.describe(),
        shas={campaign.specs[k]: shas[k] for k in campaign.models},
        **extra,
    )


def _keep(campaign, case: Case, failed_key: str | None) -> None:
    """Add ``case`` to the regression corpus when the campaign saves (and it still fails)."""
    c = campaign.config
    say = campaign.progress.say
    if not c.save:
        return
    if failed_key is not None and not case.expect[campaign.specs[failed_key]]["diverged"]:
        say(f"corpus: {case.name} not saved: {failed_key} no longer fails once stored")
        return
    saved = save_case(case, c.corpus, force=c.force)
    if saved is None:
        if failed_key is not None:
            say(f"corpus: {case.name} already there (kept; --force to overwrite)")
        return
    say(f"corpus: added {saved}")
    campaign.report["corpus"].append(str(saved))


def _shrunk_case(campaign, key: str, profile, meta: dict, seen: list) -> dict | None:
    c = campaign.config
    say = campaign.progress.say
    start = campaign.progress.done
    with campaign.evaluator(key) as ev:
        try:
            res = shrink(profile, ev, budget=c.shrink_budget)
        except ValueError as exc:
            say(f"shrink: {key}/{meta['family']}: {exc}")
            return None
    campaign.progress.update(start + res.evaluations, f"shrink: {key}/{meta['family']}")
    if any(near(res.profile, other) for other in seen):
        # two failures shrank to (nearly) the same simplest profile: keep one
        say(f"shrink: {key}/{meta['family']} shrank to a profile already kept")
        return None
    seen.append(res.profile)
    found_by = {
        "searcher": meta.get("searcher"),
        "seed": c.seed,
        "model": campaign.specs[key],
        "model_sha256": model_sha(campaign.specs[key], c.axis),
        "campaign_budget": c.budget,
    }
    case = _case(
        campaign, res.profile, meta["family"], meta.get("params"), found_by, shrink=res.summary()
    )
    path = save_case(case, campaign.out / "cases", force=True)
    say(
        f"shrink: {key}/{meta['family']} {res.original} -> {res.final} "
        f"(segments, samples, peak um) in {res.evaluations} evaluations: {_verdicts(case)}"
    )
    _keep(campaign, case, key)
    return {
        "failed_model": key,
        "family": meta["family"],
        "searcher": meta.get("searcher"),
        "shrink": res.summary(),
        "verdicts": case.expect,
        "case_file": str(path.relative_to(campaign.out)),
        "name": case.name,
    }


def paper_step_case(campaign) -> dict[str, Any]:
    """The papers' own case: a 4 mm step held 10 s, NN said to diverge after 7.3 s."""
    c = campaign.config
    x = ex.step_hold(4e-3, 10.0, campaign.dt, pre_s=0.5)
    found_by = {
        "searcher": "paper (seed 000 §5.2)",
        "seed": None,
        "model": campaign.specs[campaign.target_key],
        "model_sha256": model_sha(campaign.specs[campaign.target_key], c.axis),
    }
    params = {"size_m": 4e-3, "hold_s": 10.0, "pre_s": 0.5, "rise_s": 0.0}
    notes = (
        "seed 000 §5.2: the papers' NN diverges after 7.3 s of this step; the "
        "verdicts recorded here are what the shipped models do"
    )
    case = _case(campaign, x, "step", params, found_by, notes=notes)
    path = save_case(case, campaign.out / "cases", force=True)
    campaign.progress.say(f"paper step (4 mm, 10 s hold): {_verdicts(case)}")
    _keep(campaign, case, None)
    return {
        "failed_model": None,
        "family": "step",
        "searcher": "paper",
        "shrink": None,
        "verdicts": case.expect,
        "case_file": str(path.relative_to(campaign.out)),
        "name": case.name,
    }


def shrink_and_save(campaign) -> None:
    """Shrink the chosen failures, write their cases; the papers' step when asked for."""
    if campaign.report["shrunk"]:
        campaign.progress.say("shrink: done earlier (resumed)")
        return
    shrunk: list[dict] = []
    seen: list[np.ndarray] = []
    for key, profile, meta in shrink_choices(campaign):
        entry = _shrunk_case(campaign, key, profile, meta, seen)
        if entry is not None:
            shrunk.append(entry)
    if campaign.config.paper_step and campaign.target.paper_step:
        shrunk.append(paper_step_case(campaign))
    campaign.report["shrunk"] = shrunk
    campaign.save()
