"""The population study's summary: failure rates with 95 % intervals, the papers' step, static
force errors, accuracy beside robustness; tables (JSON, markdown) and plots.

Rates are counts of cells (one trained model each) out of the cells of a group, with Wilson's
95 % score interval: with 10 seeds per group a rate of 0/10 still allows up to 28 %.
"""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.persist import write_figure, write_json, write_text

Z95 = 1.959963984540054
STEP_AT_S = 1.0  # the papers' step starts 1 s into its profile (cell.py)


def wilson(k: int, n: int) -> tuple[float, float]:
    """Wilson score 95 % interval of a rate k / n (0, 1 for n = 0)."""
    if n == 0:
        return 0.0, 1.0
    p = k / n
    centre = (p + Z95**2 / (2 * n)) / (1 + Z95**2 / n)
    half = Z95 * math.sqrt(p * (1 - p) / n + Z95**2 / (4 * n * n)) / (1 + Z95**2 / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def rate(k: int, n: int) -> dict[str, Any]:
    lo, hi = wilson(k, n)
    return {"failed": k, "of": n, "rate": k / n if n else None, "ci95": [lo, hi]}


def shown_options(train_options: dict) -> list[str]:
    """The training switches that name a member's group: those on, and the planar structure
    and hybrid training when not the default (``certified``, ``mirror-rate``,
    ``noisy-feedback``)."""
    opts = sorted(train_options.items())
    return [k if v == "on" else v for k, v in opts if v == "on" or k in ("structure", "training")]


def recipe_label(row: dict) -> str:
    """The recipe with the training switches that are on (``free-run +certified``)."""
    return " +".join([row["recipe"], *shown_options(row.get("train_options", {}))])


def _groups(rows: list[dict]) -> dict[tuple[str, str], list[dict]]:
    out: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in rows:
        out[(recipe_label(r), r["model"])].append(r)
    return dict(out)


def _by(rows: list[dict], pick) -> dict[str, dict]:
    """Rate per key: the cells where ``pick(attack result)`` holds the key, any searcher."""
    keys = sorted({k for r in rows for a in r["attacks"].values() for k in pick(a)})
    return {
        k: rate(sum(any(k in pick(a) for a in r["attacks"].values()) for r in rows), len(rows))
        for k in keys
    }


def median_of(values) -> float | None:
    vals = [v for v in values if v is not None]
    return float(np.median(vals)) if vals else None


def group_summary(rows: list[dict]) -> dict[str, Any]:
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


def summarise(rows: list[dict]) -> dict[str, Any]:
    return {f"{rec}/{model}": group_summary(g) for (rec, model), g in _groups(rows).items()}


def pct(r: dict) -> str:
    lo, hi = r["ci95"]
    return f"{r['failed']}/{r['of']} ({100 * lo:.0f}-{100 * hi:.0f} %)"


def markdown(summary: dict[str, Any]) -> str:
    """The tables of studies/2026-11-training-recipes."""
    lines = ["| recipe / model | cells | any searcher | " + "by searcher |", "|---|---|---|---|"]
    for key, g in summary.items():
        per = "; ".join(
            f"{s} {pct(v)}, median {v['median_evaluations_to_failure']} evals"
            for s, v in g["by_searcher"].items()
        )
        lines.append(f"| {key} | {g['cells']} | {pct(g['diverged_any_searcher'])} | {per} |")
    lines += ["", "| recipe / model | by criterion | by family |", "|---|---|---|"]
    for key, g in summary.items():
        crit = "; ".join(f"{c} {pct(v)}" for c, v in g["by_criterion"].items()) or "-"
        fam = "; ".join(f"{c} {pct(v)}" for c, v in g["by_family"].items()) or "-"
        lines.append(f"| {key} | {crit} | {fam} |")
    lines += [
        "",
        "| recipe / model | papers' step bounded | departures (after the step) | "
        "wrong sign at +-4 mm | "
        "median static error at +-4 mm | hold certificate passes | folds | non-passive at rest "
        "| RMS ratio n = 1 / n = 1.5 (median) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for key, g in summary.items():
        st, ce, ac = g["papers_step"], g["certificate"], g["accuracy"]
        deps = st["departures_s"]
        dep = f"{len(deps)}, median {np.median(deps) - STEP_AT_S:.1f} s" if deps else "-"
        lines.append(
            f"| {key} | {pct(st['bounded'])} | {dep} | {pct(st['wrong_sign'])} | "
            f"{100 * (st['median_static_error_4mm'] or 0):.0f} % | {pct(ce['passes_holds'])} | "
            f"{pct(ce['with_folds'])} | {pct(ce['non_passive_at_rest'])} | "
            f"{100 * ac['rms_ratio_n1']['median']:.1f} / "
            f"{100 * ac['rms_ratio_n15']['median']:.1f} % |"
        )
    return "\n".join(lines) + "\n"


def _worst(row: dict) -> float:
    found = [a["worst_robustness"] for a in row["attacks"].values()]
    return min(r for r in found if r is not None)


def plot(rows: list[dict], path: Path) -> Path:
    """Accuracy (RMS ratio on the unseen n = 1.5 record) against robustness (the worst STL
    robustness any searcher reached), one colour per recipe, one marker per model."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    markers = {"nn": "o", "hybrid": "s"}
    for (recipe, model), g in sorted(_groups(rows).items()):
        acc = [100 * r["accuracy"]["rms_ratio_n15"] for r in g]
        rob = [
            min(
                a["worst_robustness"]
                for a in r["attacks"].values()
                if a["worst_robustness"] is not None
            )
            for r in g
        ]
        ax.scatter(acc, rob, marker=markers.get(model, "^"), label=f"{recipe}, {model}", alpha=0.8)
    ax.axhline(0.0, color="k", lw=0.8, ls="--", label="divergence (robustness 0)")
    ax.set_xlabel("RMS ratio on the unseen n = 1.5 record [%]")
    ax.set_ylabel("worst robustness found [-]")
    ax.set_title("accuracy against robustness, per recipe")
    ax.legend(fontsize=7)
    fig.tight_layout()
    write_figure(fig, path, dpi=110)
    return path


def write(out: Path, rows: list[dict]) -> dict[str, Any]:
    summary = summarise(rows)
    write_json(out / "summary.json", summary, indent=2)
    write_text(out / "summary.md", markdown(summary))
    plot(rows, out / "accuracy_vs_robustness.png")
    return summary
