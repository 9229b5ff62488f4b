"""The population study's tables (markdown) and, with one coordinate, its plot of accuracy
against robustness (``summary.py`` makes the numbers)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from bushenv.persist import write_figure
from bushenv.zoo.rates import pct

STEP_AT_S = 1.0  # the papers' step starts 1 s into its profile (holds.py)
SILENT_SHARE = 0.03  # a network below this part of the force is its backbone in practice


def markdown(summary: dict[str, Any]) -> str:
    """The tables of studies/2026-11-training-recipes (one coordinate) or of
    studies/2026-11-planar-attack (several: the summary has ``groups``)."""
    return _across_axes(summary) if "groups" in summary else _one_axis(summary)


def _one_axis(summary: dict[str, Any]) -> str:
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


def plot(groups: dict[str, list[dict]], path: Path) -> Path:
    """Accuracy (RMS ratio on the unseen n = 1.5 record) against robustness (the worst STL
    robustness any searcher reached), one colour per recipe, one marker per model."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    markers = {"nn": "o", "hybrid": "s"}
    for key, g in sorted(groups.items(), key=lambda kv: kv[0].rsplit("/", 1)):
        recipe, model = key.rsplit("/", 1)
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


def _pct(r: dict) -> str:
    """``summary.pct``, or "-" for a rate of nothing (no member passed)."""
    return pct(r) if r["of"] else "-"


def _judge_line(judge: dict | None) -> list[str]:
    if not judge:
        return []
    mark = {True: "ok", False: "FAILED", None: "undecided"}
    v = judge["vetting"]
    checks = "; ".join(f"{c['check']} {mark[c['passed']]}" for c in v["checks"])
    return [f"Judged by the reference {v['reference']}, vetted first ({checks}).", ""]


def _across_axes(summary: dict[str, Any]) -> str:
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


def _silent(c: dict) -> str:
    vals = [v for v in c["median_network_share_correlated"].values() if v is not None]
    return " (near 0: the backbone alone)" if vals and max(vals) < SILENT_SHARE else ""


def _share(share: dict) -> str:
    vals = [f"{100 * v:.1f}" if v is not None else "-" for v in share.values()]
    return " / ".join(vals) + " %"
