"""The planar attack's report: its layout (``fresh_report``; ``resumed`` continues one made
with the same arguments) and its table (``format_planar_table``), as ``campaign_report`` is
the one-axis attack's.

``report.json`` holds ``env``, ``model``, ``reference``; ``judge`` (the vetting, the force
floors, the stroke it was vetted within); ``scales`` (the limits searched: per coordinate its
stroke and rate, keys naming the unit -- ``stroke_mm`` / ``stroke_mrad``, ``rate_m_per_s`` /
``rate_rad_per_s`` --, the records' peak when they come from records, and ``source``);
``control`` (``label``, ``how``, ``spec``, ``file``); ``budget``, ``seed``, ``arguments`` (what
a resume must share); ``searchers`` (each search's summary: ``coverage`` per family and
coordinate, ``failures`` tallied, ``profiles_file`` with every failing profile and the worst);
``hold_stage``; ``recheck`` (per role: profiles, diverged, by axis, ``model``);
``failure_reach`` (how far beyond the records' peak the failures sit); ``shrunk``; ``plots``;
``seconds``; ``complete``.
"""

from __future__ import annotations

import json
from pathlib import Path

from bushenv.search.base import SearchError
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_resolve import Resolved
from bushenv.search.limits import UNITS, limits_text
from bushenv.search.planar_models import DEFAULT_REFERENCE
from bushenv.search.targets import TARGETS

RESUMED = ("searchers", "hold_stage", "recheck", "shrunk", "plots", "seconds")  # kept by --resume


def arguments(c: CampaignConfig) -> dict:
    """The settings a resumed planar attack must share with the one it continues."""
    keep = ("stroke_mm", "max_velocity_m_per_s", "rotation_mrad")
    return {**c.arguments(), "searchers": list(c.searchers), **{k: getattr(c, k) for k in keep}}


def fresh_report(c: CampaignConfig, p: Resolved) -> dict:
    """The report before any search."""
    return {
        "env": c.target,
        "model": c.model,
        "reference": c.reference or DEFAULT_REFERENCE,
        "judge": p.judged,
        "scales": p.limits.to_json(),
        "control": p.control,
        "budget": c.budget,
        "seed": c.seed,
        "arguments": arguments(c),
        "searchers": [],
        "hold_stage": None,
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
        **{k: old[k] for k in RESUMED if k in old},
    }


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
    lim, ctl = report.get("scales"), report.get("control")
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
    hold = report.get("hold_stage")
    if hold and hold.get("run"):
        lines.append(
            f"hold stage: {hold['confirmed']} of {hold['listed']} suspect holds of the "
            f"network confirmed ({hold['grid_points']}^3 grid over the limits)"
        )
    elif hold:
        lines.append(f"hold stage: not run ({hold['why']})")
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
