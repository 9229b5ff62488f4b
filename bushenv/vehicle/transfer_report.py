"""The error-transfer campaign's report: which component errors reach the car and which are
amplified (``findings``), the map as markdown and CSV, the heat map and the predictor's check
as figures. Everything is read from a ``run_transfer`` report and its predictor."""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.persist import write_figure
from bushenv.vehicle.transfer import LEAST_SHARE

# a component error does not reach the car when every change it makes is below this share of
# its own size (1 % of an output's RMS at a 10 % error): a tenth of what went in
NEGLIGIBLE_SHARE = 0.1
PIVOT_SHORT = {"lower_left": "LL", "upper_left": "UL", "lower_right": "LR", "upper_right": "UR"}
MAN_SHORT = {"bump": "bump", "pothole": "hole", "iso8608": "8608", "pulse_steer": "pulse",
             "step_steer": "step", "fishhook": "hook", "lane_change": "lane"}  # fmt: skip
TARGET_MEDIAN = 0.20  # the predictor's targets: median relative error, rank correlation
TARGET_RANK = 0.9


def _name(c: list[str] | tuple[str, ...]) -> str:
    return f"{c[0]} {c[1]} {c[2]}"


def _cells(report: dict[str, Any]) -> list[tuple[str, str]]:
    return [(m["name"], o["name"]) for m in report["manoeuvres"] for o in report["outputs"]]


def findings(report: dict[str, Any]) -> dict[str, Any]:
    """Per component its largest change (% of the reference's RMS) and where; the components
    that never reach the car (every change below ``NEGLIGIBLE_SHARE`` x size) and those
    amplified (some change above the size); the same by kind and coordinate; the predictor's
    figures against the targets."""
    s0 = report["settings"]["size_pct"]
    pct = np.asarray(report["map_pct"], dtype=float)  # (J, M, O)
    cells = _cells(report)
    rows = []
    rms = np.asarray(report["map_rms"], dtype=float)
    units = [o["unit"] for o in report["outputs"]]
    for j, c in enumerate(report["components"]):
        flat = pct[j].ravel()
        if not np.any(np.isfinite(flat)):  # no output moved in the reference car
            rows.append({"component": c, "max_pct": None, "where": None, "change": None,
                         "amplified_cells": 0})  # fmt: skip
            continue
        k = int(np.nanargmax(flat))
        rows.append({"component": c, "max_pct": float(flat[k]), "where": cells[k],
                     "change": f"{rms[j].ravel()[k]:.3g} {units[k % len(units)]}",
                     "amplified_cells": int(np.sum(flat > s0))})  # fmt: skip
    stated = [r for r in rows if r["max_pct"] is not None]
    never = [r for r in stated if r["max_pct"] < NEGLIGIBLE_SHARE * s0]
    amplified = sorted((r for r in stated if r["max_pct"] > s0), key=lambda r: -r["max_pct"])
    groups: dict[str, dict[str, float]] = {}
    for axis, at in (("kind", 2), ("coordinate", 1), ("pivot", 0)):
        names = dict.fromkeys(c[at] for c in report["components"])
        groups[axis] = {
            n: float(np.median(v))
            if (v := [r["max_pct"] for r in stated if r["component"][at] == n])
            else None
            for n in names
        }
    in_car = np.asarray(report["in_car_component_pct"], dtype=float)  # (J, M)
    kinds = dict.fromkeys(c[2] for c in report["components"])
    in_car_by_kind = {}
    for kind in kinds:
        v = in_car[[j for j, c in enumerate(report["components"]) if c[2] == kind]]
        v = v[np.isfinite(v)]
        in_car_by_kind[kind] = (
            [float(np.percentile(v, q)) for q in (10, 50, 90)] if v.size else None
        )
    checks = report["checks"]
    names = checks["predictors"]
    summaries = {n: _predictor_summary(checks, n) for n in names}
    return {
        "size_pct": s0, "components": rows, "never_reach": never, "amplified": amplified,
        "median_of_largest_by": groups, "in_car_component_by_kind": in_car_by_kind,
        "predictor": summaries[names[0]], "predictors": summaries,
    }  # fmt: skip


def _predictor_summary(checks: dict[str, Any], name: str) -> dict[str, Any]:
    """A predictor's figures on the held-out cases, against the targets."""
    combined = checks.get("combined", {}).get(name, {})
    ranks = {k: v[name]["influence"]["overall"] for k, v in checks["singles"].items()}
    med = combined.get("median_relative_error")
    return {
        "name": name, "median_relative_error": med, "p90_relative_error":
        combined.get("p90_relative_error"), "combinations": len(checks["combinations"]),
        "cells": combined.get("cells"), "spearman_cells": combined.get("spearman"),
        "influence_rank": ranks,
        "meets_median": med is not None and med <= TARGET_MEDIAN,
        "meets_rank": bool(ranks)
        and all(r is not None and r >= TARGET_RANK for r in ranks.values()),
    }  # fmt: skip


def _csv(v: float) -> str:
    return f"{v:.4g}" if v is not None and np.isfinite(v) else ""


def _span(values: list[float]) -> str:
    v = [x for x in values if x is not None and np.isfinite(x)]
    return f"{_f(min(v))}-{_f(max(v))}" if v else "n/a"


def _f(v: float | None, digits: int = 3) -> str:
    if v is None or not np.isfinite(v):
        return "n/a"
    return f"{v:.{digits}g}"


def markdown(report: dict[str, Any], found: dict[str, Any], figures: list[str]) -> str:
    """The report: the findings first, then the map (largest per output, then per manoeuvre),
    the predictor's check, what was run."""
    s0 = found["size_pct"]
    p = found["predictor"]
    lines = [f"# Error-transfer map: HalfCar-v0 with one bushing error of {s0:g} % RMS force",
             "", "## Findings", ""]  # fmt: skip
    if found["never_reach"]:
        lines.append(f"- **Never reach the car** (every change below {NEGLIGIBLE_SHARE * s0:g} % "
                     "of the output's RMS, in every manoeuvre and output): "
                     + ", ".join(f"{_name(r['component'])} ({_f(r['max_pct'], 2)} %)"
                                 for r in found["never_reach"]) + ".")  # fmt: skip
    else:
        lines.append(f"- Every component error changes some output by at least "
                     f"{NEGLIGIBLE_SHARE * s0:g} %.")  # fmt: skip
    lines.append(f"- **Amplified** (a change above the component's {s0:g} % somewhere): "
                 f"{len(found['amplified'])} of {len(found['components'])}: "
                 + ", ".join(f"{_name(r['component'])} {_f(r['max_pct'])} % = {r['change']} "
                             f"RMS ({r['where'][1]}, {r['where'][0]}; {r['amplified_cells']} of "
                             f"{len(_cells(report))} cells)"
                             for r in found["amplified"]) + ".")  # fmt: skip
    for axis, vals in found["median_of_largest_by"].items():
        lines.append(f"- Median over components of the largest change, by {axis}: "
                     + ", ".join(f"{k} {_f(v)} %" for k, v in vals.items()) + ".")  # fmt: skip
    lines.append(
        f"- The same {s0:g} % on the bench is another error in the car (the erring law driven "
        "by the reference car's pivot motion; 10th / 50th / 90th percentile over pivots, "
        "coordinates and manoeuvres): "
        + ", ".join(f"{k} {'/'.join(_f(x, 2) for x in v)} %" if v else f"{k} n/a"
                    for k, v in found["in_car_component_by_kind"].items()) + "."
    )  # fmt: skip
    for p in found["predictors"].values():
        lines.append(_predictor_line(p, s0))
    lines.append("")
    lines += [f"![{Path(f).stem}]({Path(f).name})" for f in figures] + [""]
    lines += _map_tables(report) + _check_tables(report) + _run_lines(report)
    return "\n".join(lines) + "\n"


WHAT = {
    "second_order": "second-order superposition: each error's odd and even parts from its +- runs",
    "first_order": "first-order superposition of the +size runs",
}


def _predictor_line(p: dict[str, Any], s0: float) -> str:
    med, p90 = p["median_relative_error"], p["p90_relative_error"]
    ranks = ", ".join(f"{_f(v)} at {float(k) * s0:+g} %" for k, v in p["influence_rank"].items())
    pct = "n/a" if med is None else _f(100 * med)
    tail = "n/a" if p90 is None else _f(100 * p90)
    return (
        f"- **Predictor, {p['name'].replace('_', ' ')}** ({WHAT.get(p['name'], p['name'])}): "
        f"median relative error **{pct} %** (90th percentile {tail} %) on {p['combinations']} "
        f"held-out combinations ({p['cells']} manoeuvre-output cells; target <= "
        f"{100 * TARGET_MEDIAN:g} %: {'met' if p['meets_median'] else 'NOT met'}); rank "
        f"correlation of the components' influence **{ranks or 'n/a'}** (target >= "
        f"{TARGET_RANK:g}: {'met' if p['meets_rank'] else 'NOT met'}); Spearman of predicted "
        f"and measured changes over the combinations' cells {_f(p['spearman_cells'])}."
    )


def _map_tables(report: dict[str, Any]) -> list[str]:
    pct = np.asarray(report["map_pct"], dtype=float)
    outs = [o["title"] for o in report["outputs"]]
    head = "| component | " + " | ".join(outs) + " | in-car component error |"
    rule = "|---" * (len(outs) + 2) + "|"
    lines = ["## The map: largest change over the manoeuvres (% of the reference car's RMS)", "",
             "In-car component error: the erring law's RMS force error on its coordinate when "
             "driven by the reference car's motion of that pivot, range over the manoeuvres "
             "(the size was set on the bench).", "", head, rule]  # fmt: skip
    for j, c in enumerate(report["components"]):
        ic = report["in_car_component_pct"][j]
        lines.append(f"| {_name(c)} | " + " | ".join(_f(np.nanmax(pct[j, :, o]) if np.any(
            np.isfinite(pct[j, :, o])) else None) for o in range(len(outs)))
            + f" | {_span(ic)} |")  # fmt: skip
    for m, man in enumerate(report["manoeuvres"]):
        lines += [
            "",
            f"### {man['name']}: change per output (%)",
            "",
            "| component | " + " | ".join(outs) + " |",
            "|---" * (len(outs) + 1) + "|",
        ]
        for j, c in enumerate(report["components"]):
            lines.append(f"| {_name(c)} | " + " | ".join(_f(v) for v in pct[j, m]) + " |")
        base = report["baseline_rms"][m]
        lines.append(
            "| *reference car's RMS* | "
            + " | ".join(
                f"{_f(b)} {o['unit']}" for b, o in zip(base, report["outputs"], strict=True)
            )
            + " |"
        )
    return [*lines, ""]


def _check_tables(report: dict[str, Any]) -> list[str]:
    checks = report["checks"]
    lines = ["## The predictor's check on cases it was not built from", ""]
    held = [(f"{s['size_pct']:+g} % ({k}x)", s[n]["cells"], s[n]["influence"], n)
            for k, s in checks["singles"].items() for n in checks["predictors"]]  # fmt: skip
    if "first_order_sign" in checks:  # the -size runs, held out of the first order only
        s = checks["first_order_sign"]
        held.append(("-size (built into the second order)", s["cells"], s["influence"],
                     "first_order"))  # fmt: skip
    for label, c, influence, name in held:
        med, p90 = c["median_relative_error"], c["p90_relative_error"]
        lines.append(
            f"- every single error at {label}, {name.replace('_', ' ')}: median relative error "
            f"{_f(None if med is None else 100 * med)} %, 90th percentile "
            f"{_f(None if p90 is None else 100 * p90)} % over {c['cells']} cells; rank "
            f"correlation of the components' influence {_f(influence['overall'])}"
        )
    main = checks["predictors"][0]
    lines += ["", f"Per combination, the {main.replace('_', ' ')} predictor:"]
    lines += ["", "| combination | cells | median relative error % | worst cell: measured / "
              "predicted % |", "|---|---|---|---|"]  # fmt: skip
    least = LEAST_SHARE * report["settings"]["size_pct"]
    for c in checks["combinations"]:
        m, p = np.asarray(c["measured_pct"], float), np.asarray(c[f"{main}_pct"], float)
        ok = np.isfinite(m) & (m >= least)
        terms = ", ".join(f"{PIVOT_SHORT[t['pivot']]} {t['coord']} {t['kind']} {t['size_pct']:+g}"
                          for t in c["terms"])  # fmt: skip
        if not ok.any():
            lines.append(f"| {terms} | 0 | n/a | n/a |")
            continue
        rel = np.abs(p[ok] - m[ok]) / m[ok]
        w = int(np.argmax(rel))
        lines.append(f"| {terms} | {int(ok.sum())} | {_f(100 * np.median(rel))} | "
                     f"{_f(m[ok][w])} / {_f(p[ok][w])} |")  # fmt: skip
    return [*lines, ""]


def _run_lines(report: dict[str, Any]) -> list[str]:
    s = report["settings"]
    factors = ", ".join(f"{k} x{v:.4g}" for k, v in report["factors"].items())
    return [
        "## What was run", "",
        f"HalfCar-v0 (one car, no twin), manoeuvres {', '.join(s['manoeuvres'])} "
        f"(duration {s['duration_s'] or 'each its own'}), seed {s['seed']}; {report['cars']} "
        f"cars, {report['car_steps']} car steps in {report['run_seconds']:.0f} s. Each error: "
        f"the reference rubber with one parameter group scaled on one coordinate, the factor "
        f"set so its force on that coordinate errs by {s['size_pct']:g} % RMS on the bench's "
        f"random motion at n = 1: {factors}.",
        "Cars ended early: " + (", ".join(f"{e['case']} in {e['manoeuvre']} at step "
                                          f"{e['steps']} ({e['why']})" for e in report["ended"])
                                or "none") + ".",
    ]  # fmt: skip


def map_csv(report: dict[str, Any]) -> str:
    """One row per component, manoeuvre and output: the change in SI and in %, the transfer
    (change % over the component's size), the in-car component error."""
    s0 = report["settings"]["size_pct"]
    pct = np.asarray(report["map_pct"], dtype=float)
    rms = np.asarray(report["map_rms"], dtype=float)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["pivot", "coordinate", "kind", "size_pct", "manoeuvre", "output", "unit",
                "reference_rms", "change_rms", "change_pct", "transfer",
                "in_car_component_pct"])  # fmt: skip
    for j, c in enumerate(report["components"]):
        for m, man in enumerate(report["manoeuvres"]):
            for o, out in enumerate(report["outputs"]):
                v = pct[j, m, o]
                w.writerow([*c, s0, man["name"], out["name"], out["unit"],
                            f"{report['baseline_rms'][m][o]:.6g}", f"{rms[j, m, o]:.6g}",
                            _csv(v), _csv(v / s0),
                            _csv(report["in_car_component_pct"][j][m])])  # fmt: skip
    return buf.getvalue()


def plot_map(report: dict[str, Any], path: str | Path) -> Path:
    """Heat map: rows the components, columns the manoeuvres grouped by output, colour the RMS
    change (% of the reference car's RMS, log scale, centred on the component's size: red is
    amplified, blue attenuated, grey not stated)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import TwoSlopeNorm

    s0 = report["settings"]["size_pct"]
    pct = np.asarray(report["map_pct"], dtype=float)  # (J, M, O)
    J, M, O = pct.shape
    grid = pct.transpose(0, 2, 1).reshape(J, O * M)
    finite = grid[np.isfinite(grid) & (grid > 0)]
    lo, hi = max(float(finite.min()), 1e-3), float(finite.max())
    lo, hi = min(lo, s0 / 10), max(hi, s0 * 10)
    fig, ax = plt.subplots(figsize=(15, 13))
    log = np.log10(np.where(grid > 0, grid, np.nan))
    norm = TwoSlopeNorm(vcenter=np.log10(s0), vmin=np.log10(lo), vmax=np.log10(hi))
    cmap = plt.get_cmap("RdBu_r").with_extremes(bad="0.85")
    im = ax.imshow(log, aspect="auto", cmap=cmap, norm=norm, interpolation="nearest")
    ax.set_yticks(range(J))
    ax.set_yticklabels([f"{PIVOT_SHORT[c[0]]} {c[1]} {c[2]}" for c in report["components"]],
                       fontsize=7)  # fmt: skip
    mans = [MAN_SHORT.get(m["name"], m["name"]) for m in report["manoeuvres"]]
    ax.set_xticks(range(O * M))
    ax.set_xticklabels(mans * O, rotation=90, fontsize=7)
    for o, out in enumerate(report["outputs"]):
        ax.axvline(o * M - 0.5, color="k", lw=1.2)
        ax.text(o * M + M / 2 - 0.5, -1.2, f"{out['title']}", ha="center", va="bottom", fontsize=9)
    for j in range(0, J, 12):
        ax.axhline(j - 0.5, color="k", lw=1.2)
    cb = fig.colorbar(im, ax=ax, fraction=0.03, pad=0.01)
    ticks = [t for t in (0.01, 0.1, 1, 10, 100, 1000) if lo <= t <= hi]
    cb.set_ticks(np.log10(ticks))
    cb.set_ticklabels([f"{t:g}" for t in ticks])
    cb.set_label(f"RMS change of the output, % of the reference car's RMS\n(component error "
                 f"{s0:g} % RMS force; above {s0:g} %: amplified; grey: output nil in the "
                 "reference car)")  # fmt: skip
    ax.set_title(f"Error-transfer map, HalfCar-v0: one bushing error of {s0:g} % RMS force "
                 "(pivot, coordinate, kind) per row", pad=30)  # fmt: skip
    fig.tight_layout()
    return write_figure(fig, path)


def plot_check(report: dict[str, Any], path: str | Path) -> Path:
    """Predicted against measured RMS change (%) on the held-out cases, log-log, with the
    +-20 % band."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 6))
    least = LEAST_SHARE * report["settings"]["size_pct"]
    main = report["checks"]["predictors"][0]
    sets = [(f"single errors at {s['size_pct']:+g} %", s["measured_pct"], s[main]["predicted_pct"])
            for s in report["checks"]["singles"].values()]  # fmt: skip
    combos = report["checks"]["combinations"]
    if combos:
        sets.append(("combinations", [c["measured_pct"] for c in combos],
                     [c[f"{main}_pct"] for c in combos]))  # fmt: skip
    for label, m, p in sets:
        m, p = np.ravel(np.asarray(m, float)), np.ravel(np.asarray(p, float))
        ok = np.isfinite(m) & np.isfinite(p) & (m > 0) & (p > 0)
        ax.loglog(m[ok], p[ok], ".", ms=3, alpha=0.6, label=label)
    lim = ax.get_xlim()
    x = np.geomspace(*lim, 10)
    ax.plot(x, x, "k-", lw=0.8)
    ax.fill_between(x, 0.8 * x, 1.2 * x, color="0.8", alpha=0.5, label="+-20 %")
    ax.axvline(least, color="0.5", ls=":", lw=0.8, label=f"judged from {least:g} %")
    ax.set_xlabel("measured RMS change, % of the reference car's RMS")
    ax.set_ylabel("predicted RMS change, %")
    ax.set_title(
        f"{main.replace('_', ' ')} predictor vs measured on held-out cases\n"
        "(every manoeuvre and output)"
    )
    ax.legend(fontsize=8)
    fig.tight_layout()
    return write_figure(fig, path)
