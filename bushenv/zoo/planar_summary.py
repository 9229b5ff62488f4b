"""The MIMO population's summary: per recipe x model, how many members pass every single-axis
check and how many of those the attack across axes breaks, with Wilson 95 % intervals
(``summary.rate``); the MIMO networks pooled against the target of 90 %.

Members trained with ``--certified on`` (``identify/mimo_certified.py``) are grouped apart
(``free-run +certified / hybrid``) and kept out of the pool: the pool is the plain MIMO networks
the target is about. The certified hybrids get their own rates (``certified_hybrids``): passing
the single-axis check, broken across axes among those passing (any coordinate, and in a moving
one), per searcher, with the certified training's own admission and every member's hold check.
Without certified hybrid members the summary says so rather than counting plain ones.
"""

from __future__ import annotations

from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

from bushenv.persist import write_json, write_text
from bushenv.zoo.summary import median_of, pct, rate, recipe_label

MIMO_MODELS = ("nn", "hybrid")  # "nn-axis" is three single-axis networks, not MIMO
TARGET_RATE = 0.9  # share of MIMO networks that pass the attack across axes
NO_CERTIFIED = "none in this study (train them with --certified on)"


def _pct(r: dict) -> str:
    """``summary.pct``, or "-" for a rate of nothing (no member passed)."""
    return pct(r) if r["of"] else "-"


def _broken(rows: list[dict]) -> list[dict]:
    return [r for r in rows if r["diverged"]]


def _quiet_at_rest(row: dict) -> bool:
    """No single-axis profile failed the member in any coordinate, at rest ones included: what
    a single-axis rig reading all three load-cell channels would pass."""
    return all(v["passed"] and v["cross_axis_failures"] == 0 for v in row["single_axis"].values())


def certified(row: dict) -> bool:
    return row.get("train_options", {}).get("certified") == "on"


def _holds(rows: list[dict]) -> dict[str, Any]:
    """Members whose hold check (``planar_cell._certificate``) found an out-of-band, an
    unstable fixed point or a hold not settling; rows without a check are left out."""
    checked = [r["certificate"] for r in rows if r.get("certificate")]
    return {
        "out_of_band": rate(sum(c["out_of_band"] > 0 for c in checked), len(checked)),
        "unstable": rate(sum(c["unstable"] > 0 for c in checked), len(checked)),
        "unsettled": rate(sum(c["unsettled_holds"] > 0 for c in checked), len(checked)),
        "median_out_of_band_fixed_points": median_of(c["out_of_band"] for c in checked),
    }


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
        "holds": _holds(rows),
        # the network's part of a hybrid's force (RMS ratio, unseen correlated record)
        "median_network_share_correlated": {
            c: median_of((r.get("network_share") or {}).get(c) for r in rows)
            for c in ("axial", "radial", "rotation")
        },
        "train_s": sum(r["train_s"] for r in rows),
        "judge_s": sum(r["judge_s"] for r in rows),
    }


def certified_summary(rows: list[dict]) -> dict[str, Any] | str:
    """The certified MIMO hybrids' rates (module docstring), or ``NO_CERTIFIED``."""
    hyb = [r for r in rows if certified(r) and r["model"] == "hybrid"]
    if not hyb:
        return NO_CERTIFIED
    g = group_summary(hyb)
    admitted = [r.get("certified_admitted") for r in hyb]
    return {
        **g,
        "weights_admitted": rate(sum(a is True for a in admitted), len(hyb)),
        "bounded_of_passed": rate(
            g["broken_of_passed"]["of"] - g["broken_of_passed"]["failed"],
            g["broken_of_passed"]["of"],
        ),
    }


def summarise(rows: list[dict]) -> dict[str, Any]:
    groups: dict[str, list[dict]] = defaultdict(list)
    for r in rows:
        groups[f"{recipe_label(r)}/{r['model']}"].append(r)
    mimo = [r for r in rows if r["model"] in MIMO_MODELS and not certified(r)]
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
        "certified_hybrids": certified_summary(rows),
    }


def _judge_line(judge: dict | None) -> list[str]:
    if not judge:
        return []
    mark = {True: "ok", False: "FAILED", None: "undecided"}
    v = judge["vetting"]
    checks = "; ".join(f"{c['check']} {mark[c['passed']]}" for c in v["checks"])
    return [f"Judged by the reference {v['reference']}, vetted first ({checks}).", ""]


def markdown(summary: dict[str, Any]) -> str:
    lines = [
        *_judge_line(summary.get("judge")),
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
        f"MIMO networks (nn, hybrid; not certified) passing every single-axis check, broken "
        f"across axes: "
        f"{_pct(p['broken_of_passed'])}; target >= {100 * p['target']:.0f} % (lower end of the "
        f"interval): {verdict}. Broken in a coordinate the profile moves: "
        f"{_pct(p['broken_moving_of_passed'])} "
        f"({'met' if p['target_met_moving'] else 'not shown'}).",
    ]
    lines += _certified_lines(summary["certified_hybrids"])
    lines += ["", "| recipe / model | hold check: out-of-band | unstable | not settling |",
              "|---|---|---|---|"]  # fmt: skip
    for key, g in summary["groups"].items():
        h = g["holds"]
        lines.append(
            f"| {key} | {_pct(h['out_of_band'])} | {_pct(h['unstable'])} | {_pct(h['unsettled'])} |"
        )
    return "\n".join(lines) + "\n"


def _certified_lines(c: dict | str) -> list[str]:
    if isinstance(c, str):
        return [f"Certified MIMO hybrids: {c}."]
    per = "; ".join(f"{s} {_pct(v)}" for s, v in c["by_searcher"].items())
    return [
        f"Certified MIMO hybrids (--certified on): {c['members']} members, weights admitted by "
        f"their training's check {_pct(c['weights_admitted'])}; pass every single-axis check "
        f"{_pct(c['passed_single_axis'])}; of those, **bounded across axes "
        f"{_pct(c['bounded_of_passed'])}**, broken {_pct(c['broken_of_passed'])} (by searcher: "
        f"{per or '-'}), broken in a moving coordinate {_pct(c['broken_moving_of_passed'])}. "
        f"Their networks' part of the force (median RMS ratio a / r / rot, unseen correlated): "
        f"{_share(c['median_network_share_correlated'])}{_silent(c)}."
    ]


SILENT_SHARE = 0.03  # a network below this part of the force is its backbone in practice


def _silent(c: dict) -> str:
    vals = [v for v in c["median_network_share_correlated"].values() if v is not None]
    return " (near 0: the backbone alone)" if vals and max(vals) < SILENT_SHARE else ""


def _share(share: dict) -> str:
    vals = [f"{100 * v:.1f}" if v is not None else "-" for v in share.values()]
    return " / ".join(vals) + " %"


def write(out: Path, rows: list[dict], judge: dict | None = None) -> dict[str, Any]:
    """``summary.json`` and ``summary.md``; ``judge``: what judged every member (the vetted
    reference, ``campaign_planar.vetted_judge``)."""
    summary = summarise(rows)
    if judge is not None:
        summary["judge"] = judge
    write_json(out / "summary.json", summary, indent=2)
    write_text(out / "summary.md", markdown(summary))
    return summary
