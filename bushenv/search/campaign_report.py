"""A campaign's report: its layout, resuming it, and the table a person reads.

``report.json`` (docs/search.md describes every field)::

    {"format": "bushenv-attack-report", "version": 1, "arguments": {...}, "searchers": [...],
     "reference": {"spec", "file_sha256", "params_sha256"} (spec null: judged without one),
     "scales": {"stroke_m", "velocity_m_per_s", "force_floor_n", "force_limit_n", ...},
     "criteria": {"run": [...], "why": "..."}, "notes": [...],
     "models": {key: {"role", "spec", "class", "file", "sha256", "params_sha256",
                      "searchers": {name: SearchResult.summary() + first_failure, worst,
                                    profiles_file}}},
     "control": {"label", "how", "spec", "file"} (how the control was made; null: none),
     "recheck": {"profiles": n, key: {"diverged", "failures", ...}},
     "shrunk": [...], "corpus": [...], "complete": bool, "seconds": float}

Over C > 1 coordinates the same layout: ``scales`` are the limits searched, per coordinate with
its unit in the key (``search.limits.CoordinateLimits.to_json``); ``judged`` the force floors per
coordinate and the stroke the reference was vetted within; each search's ``coverage`` is per
family and coordinate and its ``failures`` tallied by family, coordinate and criterion; the
recheck counts failures ``by_axis``; ``failure_reach`` says how far beyond the records' peak the
failures sit; a shrunk failure names the coordinates it ``moving`` and the one that failed.
"""

from __future__ import annotations

import json
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.errors import BadInput
from bushenv.models import params_sha
from bushenv.resolved import ResolvedModel
from bushenv.search.campaign_config import CampaignConfig
from bushenv.search.campaign_resolve import Resolved

REPORT_FORMAT = "bushenv-attack-report"
REPORT_VERSION = 1


class ReportError(BadInput):
    """A report that cannot be resumed; the message says why and what to do."""


def model_identity(model: ResolvedModel) -> dict[str, Any]:
    """Which model a report row is: its spec, class, file and hashes."""
    return {
        "spec": model.spec,
        "class": type(model.model).__name__,
        "file": str(model.file) if model.file else None,
        "sha256": model.sha256,
        "params_sha256": params_sha(model.model),
    }


def criteria_json(resolved: Resolved) -> dict[str, Any]:
    """Which criteria the verdicts used, and why some did not run (the judge's)."""
    judge = resolved.judge
    why = judge.why
    if judge.reference is not None:
        why = f"{why} {judge.reference_spec!r}"
    return {"run": list(judge.criteria), "why": why}


def fresh_report(resolved: Resolved, config: CampaignConfig) -> dict[str, Any]:
    """The report of a campaign that has run nothing yet."""
    return {
        "format": REPORT_FORMAT,
        "version": REPORT_VERSION,
        "arguments": config.arguments(),
        "searchers": list(config.searchers),
        "reference": resolved.reference_identity(),
        "scales": resolved.judge.scales.to_json(),
        "judge": resolved.judge.describe(),
        "criteria": criteria_json(resolved),
        "notes": list(resolved.notes),
        "models": {
            key: {"role": resolved.roles[key], **model_identity(m), "searchers": {}}
            for key, m in resolved.models.items()
        },
        "control": None if resolved.control is None else dict(resolved.control),
        **({} if resolved.judged is None else {"judged": dict(resolved.judged)}),
        "recheck": {},
        "shrunk": [],
        "corpus": [],
        "complete": False,
        "seconds": 0.0,
    }


def control_flagged(report: dict[str, Any], control_key: str | None) -> bool:
    """Whether any search made the control diverge (the criteria are then at fault)."""
    control = report["models"].get(control_key, {}).get("searchers", {})
    return any(s["diverged"] for s in control.values())


def resumed_report(path: Path, fresh: dict[str, Any]) -> dict[str, Any]:
    """``fresh`` with what the interrupted run at ``path`` finished; refuses another campaign's
    report, a corrupt one, or one whose model files changed since."""
    try:
        old = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ReportError(
            f"{path}: corrupt or half-written report ({exc}); use --force to start again"
        ) from None
    if not isinstance(old, dict) or old.get("format") != REPORT_FORMAT:
        raise ReportError(f"{path}: not a bushenv attack report")
    was = {**(old.get("arguments") or {}), "searchers": old.get("searchers")}
    now = {**fresh["arguments"], "searchers": fresh["searchers"]}
    differ = [k for k in now if was.get(k) != now[k]]
    if differ:
        k = differ[0]
        raise ReportError(
            f"{path} was made with {k}={was.get(k)!r}, not {now[k]!r}; use another --out or --force"
        )
    for key, entry in old.get("models", {}).items():
        if key in fresh["models"]:
            if entry.get("sha256") != fresh["models"][key]["sha256"]:
                raise ReportError(
                    f"{path}: model {key} changed since the interrupted run (sha256 differs); "
                    "use --force"
                )
            fresh["models"][key]["searchers"] = entry.get("searchers", {})
    for key in ("recheck", "shrunk", "corpus"):
        fresh[key] = old.get(key, fresh[key])
    for key in ("hold_stage", "failure_reach"):  # written by the stage that makes them
        if key in old:
            fresh[key] = old[key]
    fresh["seconds"] = old.get("seconds", 0.0)
    return fresh


def _verdicts(verdicts: dict[str, Any]) -> str:
    return ", ".join(
        f"{m}: {'DIVERGES' if x['diverged'] else 'bounded'}" for m, x in verdicts.items()
    )


def _search_row(key: str, role: str, name: str, s: dict[str, Any]) -> str:
    ff = s.get("first_failure") or {}
    fam = (
        f"{ff.get('family')} ({ff.get('verdict', {}).get('first_criterion')})"
        if s["diverged"]
        else "-"
    )
    if s["diverged"] and ff.get("reference_in_envelope") is False:
        fam += " [reference outside its envelope]"
    if s["diverged"] and ff.get("reference_unvetted_here"):
        fam += " [UNVETTED: the reference failed its vetting here]"
    wd = s.get("worst_deviation")
    stf = f"{s['seconds_to_failure']:.2f}" if s["diverged"] else "-"
    wds = f"{wd:.3g}" if wd is not None else "-"
    return (
        f"{key:<12} {role:<8} {name:<11} {s['evaluations']:>6} "
        f"{'YES' if s['diverged'] else 'no':>8} "
        f"{s['evaluations_to_failure'] or '-':>11} "
        f"{stf:>8} {wds:>9} {s['worst_robustness']:>10.3g} {fam}"
    )


@dataclass(frozen=True)
class Column:
    """One column of the attack table: its header, width, alignment and meaning."""

    name: str
    width: int
    align: str  # "<" or ">"
    meaning: str


# The table's columns in order: the header, the legend under the table and report.md's column
# table are all made from this (docs may reuse ``legend_lines``).
COLUMNS = (
    Column("model", 12, "<", "the model's report key (a registered name or a file's stem)"),
    Column(
        "role",
        8,
        "<",
        "target: under attack; hybrid: rechecked on the target's failures, then attacked; "
        "control: must stay clean (if flagged, the criteria are at fault); also: rechecked",
    ),
    Column("searcher", 11, "<", "the search that made the row (cert-holds: the hold stage)"),
    Column("evals", 6, ">", "profiles simulated by that search (an RL episode is one)"),
    Column("diverged", 8, ">", "YES when at least one profile made the model diverge"),
    Column("evals->fail", 11, ">", "evaluations spent until the first failing profile"),
    Column("s->fail", 8, ">", "wall-clock seconds until the first failure (this machine and load)"),
    Column(
        "worst dev",
        9,
        ">",
        "on the row's worst profile (lowest robustness): max over time of |F_model - "
        "F_reference|, over the reference's peak force on it (or the force floor, if larger); "
        "1 = an error as large as the whole force; '-' or nan without a reference",
    ),
    Column(
        "robustness",
        10,
        ">",
        "STL margin of that worst profile to the nearest divergence criterion, in units of "
        "the criterion's own scale: below 0 diverged, near 0 nearly",
    ),
    Column(
        "failing family (criterion)",
        0,
        "<",
        "the excitation family of the first failure and the criterion that fired "
        "(bushenv/divergence.py); [reference outside its envelope]: on that profile the "
        "reference left the range its card's records cover; [UNVETTED ...]: the profile dwells "
        "(0.5 s) where the reference, trusted by --trust-reference, failed its vetting",
    ),
)

# What the lines around the table say, keyed by the words they start with.
SECTIONS = (
    ("reference", "the bushing the verdicts compare with, and the divergence criteria run"),
    (
        "judge",
        "the reference the verdicts compare with, its vetting (every check pass, FAILED or "
        "not checked) and its envelope (where it is known to hold)",
    ),
    ("note", "what the judge could not judge, or judged otherwise, and why"),
    (
        "certificate holds",
        "holds the target's certificate (bushenv certify) lists as oscillating, departing or "
        "wrong-sign, each stepped to and held 10 s; confirmed ones diverged and join the "
        "failures. A held force of the right sign but the wrong size is not listed: the "
        "static criterion judges it in the rows",
    ),
    (
        "covered on",
        "what the searches against the target tried, per excitation family: profiles, peak "
        "deflection range, fastest rate; a 'no' above means no divergence among these",
    ),
    ("recheck", "the profiles that broke the target, rerun on every other model"),
    (
        "shrunk failures",
        "failures cut to the fewest segments and samples that still diverge, and every "
        "model's verdict on the shrunk profile",
    ),
)


LEGEND_WIDTH = 100


def _header() -> str:
    return " ".join(f"{c.name:{c.align}{c.width}}" for c in COLUMNS)


def _has_section(printed: str, key: str) -> bool:
    return any(line.startswith(key) for line in printed.splitlines())


def legend_lines(printed: str | None = None) -> list[str]:
    """The legend printed under the table: every column, then every kind of line around the
    table that ``printed`` holds (all of them when None); wrapped at ``LEGEND_WIDTH``."""
    width = max(len(c.name) for c in COLUMNS[:-1])
    pad = " " * (width + 4)
    lines = ["", "what the columns say:"]
    for c in COLUMNS:
        first = f"  {c.name:<{width}}  "
        if len(c.name) > width:  # the last, long header: its meaning on the lines below
            lines.append(f"  {c.name}")
            first = pad
        lines += textwrap.wrap(c.meaning, LEGEND_WIDTH, initial_indent=first, subsequent_indent=pad)
    shown = [(k, t) for k, t in SECTIONS if printed is None or _has_section(printed, k)]
    if shown:
        lines.append("what the lines around it say:")
        for k, t in shown:
            lines += textwrap.wrap(f"{k}: {t}", LEGEND_WIDTH, initial_indent="  ",
                                   subsequent_indent="      ")  # fmt: skip
    return lines


def format_table(report: dict[str, Any], target_key: str, legend: bool = True) -> str:
    """The campaign as a plain-text table, the recheck and the shrunk failures; ``legend``:
    what every column and line means, under it all (``legend_lines``)."""
    head = _header()
    ref = report["reference"].get("spec")
    lines = [
        f"reference: {ref if ref is not None else 'none'}; criteria run: "
        f"{', '.join(report['criteria']['run'])}",
        *_judge_lines(report.get("judge")),
        *_limits_lines(report),
        *(f"note: {n}" for n in report.get("notes", [])),
        "",
        head,
        "-" * len(head),
    ]
    for key, entry in report["models"].items():
        for name, s in entry["searchers"].items():
            lines.append(_search_row(key, entry["role"], name, s))
    lines += _hold_stage_lines(report.get("hold_stage"))
    lines += _coverage_lines(report, target_key)
    lines += _reach_lines(report)
    rc = report.get("recheck", {})
    if rc:
        lines += ["", f"recheck on the {rc.get('profiles', 0)} profiles that broke {target_key}:"]
        roles = {k: e.get("role", "") for k, e in report["models"].items()}
        lines += [
            f"  {k:<12} {roles.get(k, ''):<8} diverged on {e['diverged']}"
            + (f" (by coordinate {json.dumps(e['by_axis'])})" if e.get("by_axis") else "")
            for k, e in rc.items()
            if k != "profiles"
        ]
    if report.get("shrunk"):
        lines += ["", "shrunk failures (segments, samples, peak um) and verdicts:"]
        for e in report["shrunk"]:
            if e["shrink"] is None:
                lines.append(f"  the papers' 4 mm step held 10 s: {_verdicts(e['verdicts'])}")
                continue
            fin = e["shrink"]["final"]
            where = ""
            if "moving" in e:
                where = f"moving {', '.join(e['moving'])}, failed in {e['axis']}; "
            lines.append(
                f"  {e['failed_model']}/{e['family']:<11} -> {fin['segments']} seg, "
                f"{fin['samples']} samples, {fin['peak_um'] / 1e3:.2f} mm peak; {where}"
                f"{_verdicts(e['verdicts'])}"
            )
    text = "\n".join(lines)
    return "\n".join([text, *legend_lines(text)]) if legend else text


def _judge_lines(judge: dict | None) -> list[str]:
    """Who judged: the reference's vetting (or why there is none) and its envelope."""
    if not judge:
        return []
    if judge["reference"] is None:
        return ["judge: no reference (only the criteria that need none)"]
    vet = judge.get("vetting")
    if vet is None:
        return [f"judge: reference {judge['reference']} NOT VETTED"]
    from bushenv.vetting import VERDICTS

    checks = vet["checks"]
    if not vet["passed"]:
        state = "FAILED (--trust-reference: verdicts UNVETTED)"
        ranges = judge.get("unvetted_ranges_m") or []
        boxes = vet.get("unvetted_boxes") or []  # over several coordinates, each in its unit
        if ranges:
            where = ", ".join(f"{a * 1e3:+.3g}..{b * 1e3:+.3g} mm" for a, b in ranges)
            state += f"; it failed at {where}"
        elif boxes:
            where = "; ".join(
                "(" + ", ".join(f"{a * 1e3:+.3g}..{b * 1e3:+.3g}" for a, b in box) + ")"
                for box in boxes[:4]
            )
            state += f"; it failed in {len(boxes)} box(es) of held vectors (mm, mm, mrad): {where}"
    elif all(c["passed"] is True for c in checks):
        state = "passed (every check)"
    else:
        todo = [c["check"] for c in checks if c["passed"] is None]
        n = sum(c["passed"] is True for c in checks)
        state = f"not fully checked: {n} of {len(checks)} passed, not checked: {', '.join(todo)}"
    env = judge.get("envelope") or {}
    lines = [f"judge: reference {judge['reference']} vetted, {state}"]
    lines += [f"  {c['check']}: {VERDICTS[c['passed']]} ({c['detail']})" for c in checks]
    if env:
        lines.append(
            f"  envelope: |x| <= {env['max_abs_displacement_m'] * 1e3:.4g} mm, |dx/dt| <= "
            f"{env['max_abs_velocity_m_per_s']:.4g} m/s ({env['source']})"
        )
    return lines


def _limits_lines(report: dict[str, Any]) -> list[str]:
    """Over several coordinates, the limits searched and the force floors; the control."""
    lines = []
    judged = report.get("judged")
    if judged:
        from bushenv.search.limits import limits_text

        scales = report["scales"]
        floors = ", ".join(
            f"{k} {x:.4g} {'N m' if 'stroke_mrad' in scales.get(k, {}) else 'N'}"
            for k, x in judged["force_floors"].items()
        )  # a rotation's floor is a moment
        lines.append(f"searched within {limits_text(scales)}")
        lines.append(f"  force floors {floors}: {judged['force_floors_source']}")
    ctl = report.get("control")
    if ctl:
        lines.append(f"control: {ctl['label']} ({ctl['how']})")
    return lines


def _reach_lines(report: dict[str, Any]) -> list[str]:
    reach = report.get("failure_reach")
    if not reach:
        return []
    return [
        f"failures reach {reach['median']:.3g}x the records' peak (median; {reach['min']:.3g}x "
        f"to {reach['max']:.3g}x, {reach['failures']} failures)"
    ]


def _held(h: dict[str, Any]) -> str:
    """A hold as listed: a deflection (mm) or a held vector (each coordinate in its unit)."""
    if "x_mm" in h:
        return f"{h['x_mm']:+.3g} mm"
    key = next(k for k in h if k.startswith("q_"))
    units = key[2:].split("_")
    return "(" + ", ".join(f"{v:+.3g} {u}" for v, u in zip(h[key], units, strict=True)) + ")"


def _hold_stage_lines(stage: dict | None) -> list[str]:
    if not stage:
        return []
    if not stage.get("run"):
        return ["", f"certificate holds: not run ({stage.get('why')})"]
    head = (
        f"certificate holds: {stage['listed']} listed as oscillating, departing or wrong-sign, "
        f"{stage['confirmed']} confirmed by the judge, {stage['listed'] - stage['confirmed']} "
        "refuted"
    )
    shown = [h for h in stage["holds"] if h["confirmed"]][:6]
    return ["", head] + [
        f"  {_held(h)} ({', '.join(h['listed_as'])}): confirmed ({h['criterion']})" for h in shown
    ]


def _coverage_lines(report: dict[str, Any], target_key: str) -> list[str]:
    """What the searches against the target tried: the scope of a "no divergence". One
    coordinate: per family, profiles, peak range (mm) and fastest rate; several: the same per
    coordinate, each in its unit."""
    entry = report["models"].get(target_key, {})
    counts: dict[str, int] = {}
    fams: dict[str, dict[str, list]] = {}
    for s in entry.get("searchers", {}).values():
        for fam, row in (s.get("coverage") or {}).items():
            counts[fam] = counts.get(fam, 0) + int(row["profiles"])
            per = {k: v for k, v in row.items() if isinstance(v, dict)} or {"": row}
            for coord, c in per.items():
                peak = sorted(k for k in c if k.startswith("peak_"))  # *_max, *_min
                rate = next(k for k in c if k.startswith("max_rate_"))
                f = fams.setdefault(fam, {}).setdefault(coord, [np.inf, 0.0, 0.0, "", ""])
                f[0], f[1] = min(f[0], c[peak[1]]), max(f[1], c[peak[0]])
                f[2] = max(f[2], c[rate])
                f[3] = peak[0][5:].rsplit("_", 1)[0]  # mm or mrad
                f[4] = rate[9:].replace("_per_s", "/s")
    if not fams:
        return []
    seed = report.get("arguments", {}).get("seed")
    lines = ["", f"covered on {target_key} (seed {seed}): family, profiles, peak range, max rate"]
    for fam, per in sorted(fams.items()):
        parts = [
            f"{coord + ' ' if coord else ''}{lo:.3g}-{hi:.3g} {u}  {r:.3g} {ru}"
            for coord, (lo, hi, r, u, ru) in per.items()
        ]
        lines.append(f"  {fam:<12} {counts[fam]:>5}  " + "; ".join(parts))
    return lines


def _md_cell(text: str) -> str:
    """``text`` inside a markdown table cell (|F| would end the cell)."""
    return text.replace("|", "\\|")


def legend_markdown(printed: str | None = None) -> str:
    """The legend as two markdown tables (report.md; the docs' page, ``scripts/gen_docs.py``):
    every column, then the lines around the table ``printed`` holds (all when None)."""
    lines = ["| column | meaning |", "|---|---|"]
    lines += [f"| {c.name} | {_md_cell(c.meaning)} |" for c in COLUMNS]
    lines += ["", "| lines starting | meaning |", "|---|---|"]
    shown = [(k, t) for k, t in SECTIONS if printed is None or _has_section(printed, k)]
    lines += [f"| {k} | {_md_cell(t)} |" for k, t in shown]
    return "\n".join(lines)


def report_markdown(report: dict[str, Any], target_key: str, plots: list[str]) -> str:
    """``report.md``: the table, what each column means with its unit, the scales, the plots."""
    table = format_table(report, target_key, legend=False)
    lines = ["# Adversarial campaign", "", "```", table, "```", ""]
    lines += ["## The columns", "", legend_markdown(table)]
    lines += ["", "## Criteria", "", report["criteria"]["why"], ""]
    sc = report["scales"]
    if "stroke_m" in sc:
        scales = (
            f"stroke {sc['stroke_m'] * 1e3:.4g} mm, velocity {sc['velocity_m_per_s']:.4g} m/s, "
            f"force floor {sc['force_floor_n']:.4g} N, force limit {sc['force_limit_n']:.4g} N "
            f"({sc['source']})"
        )
    else:  # several coordinates: the limits searched, each in its unit
        from bushenv.search.limits import limits_text

        scales = limits_text(sc)
    lines += ["## Scales", "", scales, ""]
    lines += [f"![{p}](plots/{p})\n" for p in plots]
    return "\n".join(lines)
