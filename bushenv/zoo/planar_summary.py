"""The MIMO population's summary: per recipe x model, how many members pass every single-axis
check and how many of those the attack across axes breaks, with Wilson 95 % intervals
(``summary.rate``); the MIMO networks pooled against issue 25's target (>= 90 %).

No planar training is certified yet, so there is no certified MIMO hybrid to show bounded: the
tables say so rather than counting the plain hybrids as certified.
"""

from __future__ import annotations

from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

from bushenv.persist import write_json, write_text
from bushenv.zoo.summary import median_of, pct, rate

MIMO_MODELS = ("nn", "hybrid")  # "nn-axis" is three single-axis networks, not MIMO
TARGET_RATE = 0.9  # issue 25 item 7
NO_CERTIFIED = "no certified MIMO hybrid exists (planar training has no certified mode yet)"


def _pct(r: dict) -> str:
    """``summary.pct``, or "-" for a rate of nothing (no member passed)."""
    return pct(r) if r["of"] else "-"


def _broken(rows: list[dict]) -> list[dict]:
    return [r for r in rows if r["diverged"]]


def _quiet_at_rest(row: dict) -> bool:
    """No single-axis profile failed the member in any coordinate, at rest ones included: what
    a single-axis rig reading all three load-cell channels would pass."""
    return all(v["passed"] and v["cross_axis_failures"] == 0 for v in row["single_axis"].values())


def group_summary(rows: list[dict]) -> dict[str, Any]:
    passed = [r for r in rows if r["passed_single_axis"]]
    searchers = sorted({s for r in rows for s in r["attacks"]})
    return {
        "members": len(rows),
        "passed_single_axis": rate(len(passed), len(rows)),
        "passed_single_axis_all_channels": rate(sum(map(_quiet_at_rest, rows)), len(rows)),
        "broken_of_passed": rate(len(_broken(passed)), len(passed)),
        "broken_moving_of_passed": rate(sum(r["diverged_moving"] for r in passed), len(passed)),
        "broken": rate(len(_broken(rows)), len(rows)),
        "by_searcher": {
            s: {
                **rate(sum(r["attacks"][s]["diverged"] for r in passed), len(passed)),
                "median_evaluations_to_failure": median_of(
                    r["attacks"][s]["evaluations_to_failure"] for r in passed
                ),
            }
            for s in searchers
        },
        # of those passing, failed somewhere in a coordinate the profile never moved
        "failed_in_a_coordinate_at_rest": rate(
            sum(any(a["in_a_coordinate_at_rest"] for a in r["attacks"].values()) for r in passed),
            len(passed),
        ),
        "failures_by_axis": dict(
            sum(
                (Counter(a["by_axis"]) for r in passed for a in r["attacks"].values()),
                Counter(),
            ).most_common()
        ),
        "median_single_axis_driven_failures": median_of(
            sum(v["driven_failures"] for v in r["single_axis"].values()) for r in rows
        ),
        "median_rms_ratio_correlated": {
            c: median_of(r["accuracy"]["correlated"][c] for r in rows)
            for c in ("axial", "radial", "rotation")
        },
        "train_s": sum(r["train_s"] for r in rows),
        "judge_s": sum(r["judge_s"] for r in rows),
    }


def summarise(rows: list[dict]) -> dict[str, Any]:
    groups: dict[str, list[dict]] = defaultdict(list)
    for r in rows:
        groups[f"{r['recipe']}/{r['model']}"].append(r)
    mimo = [r for r in rows if r["model"] in MIMO_MODELS]
    passed = [r for r in mimo if r["passed_single_axis"]]
    pooled = rate(len(_broken(passed)), len(passed))
    moving = rate(sum(r["diverged_moving"] for r in passed), len(passed))
    return {
        "groups": {k: group_summary(g) for k, g in groups.items()},
        "mimo_pooled": {
            "broken_of_passed": pooled,
            "target": TARGET_RATE,
            # met when the interval's lower end clears the target, not the point estimate
            "target_met": bool(passed) and pooled["ci95"][0] >= TARGET_RATE,
            "broken_moving_of_passed": moving,
            "target_met_moving": bool(passed) and moving["ci95"][0] >= TARGET_RATE,
        },
        "certified_hybrids": NO_CERTIFIED,
    }


def markdown(summary: dict[str, Any]) -> str:
    lines = [
        "| recipe / model | members | pass every single-axis check | of those, broken across "
        "axes | of those, broken in a moving coordinate | all broken across axes | by searcher "
        "(of those passing; median evals to failure) | pass single-axis in all three channels "
        "| RMS ratio, unseen correlated (median a / r / rot) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for key, g in summary["groups"].items():
        per = "; ".join(
            f"{s} {_pct(v)}, {v['median_evaluations_to_failure'] or '-'}"
            for s, v in g["by_searcher"].items()
        )
        acc = " / ".join(
            f"{100 * v:.1f}" if v is not None else "-"
            for v in g["median_rms_ratio_correlated"].values()
        )
        lines.append(
            f"| {key} | {g['members']} | {_pct(g['passed_single_axis'])} | "
            f"{_pct(g['broken_of_passed'])} | {_pct(g['broken_moving_of_passed'])} | "
            f"{_pct(g['broken'])} | {per or '-'} | {_pct(g['passed_single_axis_all_channels'])} "
            f"| {acc} % |"
        )
    p = summary["mimo_pooled"]
    verdict = "met" if p["target_met"] else "not shown"
    lines += [
        "",
        f"MIMO networks (nn, hybrid) passing every single-axis check, broken across axes: "
        f"{_pct(p['broken_of_passed'])}; target >= {100 * p['target']:.0f} % (lower end of the "
        f"interval): {verdict}. Broken in a coordinate the profile moves: "
        f"{_pct(p['broken_moving_of_passed'])} "
        f"({'met' if p['target_met_moving'] else 'not shown'}).",
        f"Certified MIMO hybrids: {summary['certified_hybrids']}.",
    ]
    return "\n".join(lines) + "\n"


def write(out: Path, rows: list[dict]) -> dict[str, Any]:
    summary = summarise(rows)
    write_json(out / "summary.json", summary, indent=2)
    write_text(out / "summary.md", markdown(summary))
    return summary
