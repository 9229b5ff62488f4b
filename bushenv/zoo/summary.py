"""The population study's summary, its members grouped by recipe x model, failure rates with
Wilson 95 % intervals (``rates.py``); the tables and the plot are ``tables.py``'s.

With one coordinate: each group's rates of failing any searcher, per searcher, criterion and
family, the papers' step (bounded, departures, wrong sign, static error at +-4 mm), the hold
certificate and accuracy on the unseen records.

With several: how many members pass every single-axis check and how many of those the attack
across axes breaks; the MIMO networks pooled against the target of 90 %. Members trained with
``--certified on`` (``identify/mimo_certified.py``) are grouped apart (``free-run +certified /
hybrid``) and kept out of the pool: the pool is the plain MIMO networks the target is about.
The certified hybrids get their own rates (``certified_hybrids``): passing the single-axis
check, broken across axes among those passing (any coordinate, and in a moving one), per
searcher, with the certified training's own admission and every member's hold check. Without
certified hybrid members the summary says so rather than counting plain ones.
"""

from __future__ import annotations

from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

from bushenv.persist import write_json, write_text
from bushenv.zoo.rates import median_of, rate, recipe_label
from bushenv.zoo.tables import markdown, plot

MIMO_MODELS = ("nn", "hybrid")  # "nn-axis" is three single-axis networks, not MIMO
TARGET_RATE = 0.9  # share of MIMO networks that pass the attack across axes
NO_CERTIFIED = "none in this study (train them with --certified on)"


def groups(rows: list[dict]) -> dict[str, list[dict]]:
    """Members by ``recipe label/model``, in the order first seen."""
    out: dict[str, list[dict]] = defaultdict(list)
    for r in rows:
        out[f"{recipe_label(r)}/{r['model']}"].append(r)
    return dict(out)


def _by(rows: list[dict], pick) -> dict[str, dict]:
    """Rate per key: the cells where ``pick(attack result)`` holds the key, any searcher."""
    keys = sorted({k for r in rows for a in r["attacks"].values() for k in pick(a)})
    return {
        k: rate(sum(any(k in pick(a) for a in r["attacks"].values()) for r in rows), len(rows))
        for k in keys
    }


def one_axis_group(rows: list[dict]) -> dict[str, Any]:
    """A group of one-coordinate members (module docstring)."""
    searchers = sorted({s for r in rows for s in r["attacks"]})
    steps = [v for r in rows for v in r["step"].values()]
    return {
        "cells": len(rows),
        "diverged_any_searcher": rate(sum(r["diverged"] for r in rows), len(rows)),
        "by_searcher": {
            s: {
                **rate(sum(r["attacks"][s]["diverged"] for r in rows), len(rows)),
                "median_evaluations_to_failure": median_of(
                    r["attacks"][s]["evaluations_to_failure"] for r in rows
                ),
            }
            for s in searchers
        },
        "by_criterion": _by(rows, lambda a: a["criteria"]),
        "by_family": _by(rows, lambda a: a["families"]),
        "papers_step": {
            "bounded": rate(sum(s["bounded"] for s in steps), len(steps)),
            "departures_s": sorted(s["departure_s"] for s in steps if s["departure_s"] is not None),
            "wrong_sign": rate(sum(s["wrong_sign"] for s in steps), len(steps)),
            "median_static_error_4mm": median_of(r["static_error_4mm"] for r in rows),
        },
        "certificate": {
            "passes_holds": rate(sum(r["certificate"]["passes_holds"] for r in rows), len(rows)),
            "with_folds": rate(sum(r["certificate"]["folds"] > 0 for r in rows), len(rows)),
            "wrong_sign_somewhere": rate(
                sum(r["certificate"]["wrong_sign_holds"] > 0 for r in rows), len(rows)
            ),
            "non_passive_at_rest": rate(
                sum(bool(r["certificate"]["non_passive_bands_hz_at_rest"]) for r in rows),
                len(rows),
            ),
        },
        "accuracy": {
            k: {
                "median": median_of(r["accuracy"][k] for r in rows),
                "range": [
                    min(r["accuracy"][k] for r in rows),
                    max(r["accuracy"][k] for r in rows),
                ],
            }
            for k in ("rms_ratio_n1", "rms_ratio_n15")
        },
        "train_s": sum(r["train_s"] for r in rows),
        "judge_s": sum(r["judge_s"] for r in rows),
    }


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


def _coords(rows: list[dict], record: str) -> list[str]:
    """The coordinates the members' accuracy names, in their order."""
    return list(rows[0]["accuracy"][record]) if rows else []


def across_axes_group(rows: list[dict]) -> dict[str, Any]:
    """A group of members over several coordinates (module docstring)."""
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
            for c in _coords(rows, "correlated")
        },
        "holds": _holds(rows),
        # the network's part of a hybrid's force (RMS ratio, unseen correlated record)
        "median_network_share_correlated": {
            c: median_of((r.get("network_share") or {}).get(c) for r in rows)
            for c in _coords(rows, "correlated")
        },
        "train_s": sum(r["train_s"] for r in rows),
        "judge_s": sum(r["judge_s"] for r in rows),
    }


def certified_summary(rows: list[dict]) -> dict[str, Any] | str:
    """The certified MIMO hybrids' rates (module docstring), or ``NO_CERTIFIED``."""
    hyb = [r for r in rows if certified(r) and r["model"] == "hybrid"]
    if not hyb:
        return NO_CERTIFIED
    g = across_axes_group(hyb)
    admitted = [r.get("certified_admitted") for r in hyb]
    return {
        **g,
        "weights_admitted": rate(sum(a is True for a in admitted), len(hyb)),
        "bounded_of_passed": rate(
            g["broken_of_passed"]["of"] - g["broken_of_passed"]["failed"],
            g["broken_of_passed"]["of"],
        ),
    }


def summarise(rows: list[dict], coords: int | None = None) -> dict[str, Any]:
    """Per group; over several coordinates also the MIMO pool and the certified hybrids.
    ``coords``: the study's C (default: one when the rows name an axis, else as many as
    their accuracy names)."""
    if coords is None:
        coords = 1 if any("axis" in r for r in rows) else max(1, len(_coords(rows, "correlated")))
    if coords == 1:
        return {k: one_axis_group(g) for k, g in groups(rows).items()}
    mimo = [r for r in rows if r["model"] in MIMO_MODELS and not certified(r)]
    passed = [r for r in mimo if r["passed_single_axis"]]
    pooled = rate(len(_broken(passed)), len(passed))
    moving = rate(sum(r["diverged_moving"] for r in passed), len(passed))
    return {
        "groups": {k: across_axes_group(g) for k, g in groups(rows).items()},
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


def write(out: Path, rows: list[dict], coords: int, judge: dict | None = None) -> dict[str, Any]:
    """``summary.json`` and ``summary.md`` (with one coordinate also
    ``accuracy_vs_robustness.png``); ``judge``: what judged every member over several
    coordinates (the vetted reference, ``campaign_limits.vetted_within``)."""
    summary = summarise(rows, coords)
    if judge is not None:
        summary["judge"] = judge
    write_json(out / "summary.json", summary, indent=2)
    write_text(out / "summary.md", markdown(summary))
    if coords == 1:
        plot(groups(rows), out / "accuracy_vs_robustness.png")
    return summary
