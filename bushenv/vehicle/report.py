"""``bushenv vehicle``'s report: the markdown tables and the finding from a ``run_vehicle``
report, and the time-history figures (roll and wheel loads, model cars against the reference)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from bushenv.models.planar_base import COORDS
from bushenv.persist import write_figure
from bushenv.vehicle.compare import OUTPUTS, CarRun
from bushenv.vehicle.manoeuvres import Manoeuvre
from bushenv.vehicle.study import REFERENCE_CAR

SHORT = {"wheel_load": "wheel load", "roll": "roll", "roll_rate": "roll rate",
         "camber": "camber", "track_change": "track", "vertical_accel": "a_z",
         "lateral_accel": "a_y"}  # fmt: skip
COORD_SHORT = {"axial": "F_ax", "radial": "F_rad", "rotation": "M"}
AT_REST_N = 5.0  # a model car's wheel load RMS before any input worth a line


def _pct(v: float | None) -> str:
    return "n/a" if v is None else (f"{v:.1f}" if v < 1000 else f"{v:.3g}")


def _end(row: dict[str, Any]) -> str:
    end = row["end"]
    if not end.get("reason"):
        return "ran"
    what = ("model error" if end["model_error"] else "twin left bounds"
            if end["reference_left_bounds"] else "TERMINATED")  # fmt: skip
    return f"{what} at {end['time_s']:.2f} s"


def _verdict_text(f: dict[str, Any], car: str) -> str:
    w = f["worst"]
    return (
        f"{car}: the {f['kind']} car differs from the linear car by up to **{w['peak_pct']:.1f} "
        f"%** of the linear car's peak ({SHORT.get(w['output'], w['output'])}, {w['manoeuvre']}"
        f"; median {f['median_peak_pct']:.1f} %, {f['within_threshold']} figures within "
        f"{f['threshold_pct']:g} %); worst per output: "
        + ", ".join(f"{SHORT.get(k, k)} {v['peak_pct']:.1f} % ({v['manoeuvre']})"
                    for k, v in f["worst_by_output"].items())
    )  # fmt: skip


def finding_lines(report: dict[str, Any]) -> list[str]:
    """The report's first lines: seed 000's finding reproduced or refuted, with numbers."""
    f, up = report["finding"], report.get("finding_upper_only", {"status": "not judged"})
    if f["status"] == "not judged":
        return [f'Seed 000\'s "almost identical" finding: not judged ({f["why"]}).']
    ref = f["against_reference"]
    judged = ", ".join(SHORT.get(k, k) for k in f["judged"])
    lines = [
        f"**Seed 000's finding (§5.3, §6: a hybrid bushing gives vehicle responses \"almost "
        f"identical\" to the linear one's): {f['status'].upper()} with the hybrid in all four "
        f"arm pivots"
        + (f", {up['status'].upper()} with it in the upper arm pivots only (seed 000's car)**."
           if up["status"] != "not judged" else "**.")
        + f" \"Almost identical\" taken as within {f['threshold_pct']:g} % of the linear car's "
        f"peak in every judged output ({judged}) of every manoeuvre.",
        "",
        f"- {_verdict_text(f, 'All four pivots')}.",
    ]  # fmt: skip
    if up["status"] != "not judged":
        lines.append(f"- {_verdict_text(up, 'Upper pivots only')}.")
    lines.append(
        f"- Against the reference bushing (the coupled rubber): linear car median "
        f"{_pct(ref['linear']['median_peak_pct'])} % (max {_pct(ref['linear']['max_peak_pct'])} "
        f"%), hybrid car median {_pct(ref['hybrid']['median_peak_pct'])} % (max "
        f"{_pct(ref['hybrid']['max_peak_pct'])} %) of the reference car's peak, same outputs."
    )
    return lines


def at_rest_lines(report: dict[str, Any]) -> list[str]:
    """Model cars that moved before any input (self-excited, or pushed by an invented force)."""
    found = {}
    for r in report["rows"]:
        rest = r["at_rest"]
        if (rest["wheel_load_rms_n"] or 0.0) >= AT_REST_N:
            found.setdefault(r["kind"], []).append(r)
    lines = []
    for kind, rows in found.items():
        worst_row = max(rows, key=lambda r: r["at_rest"]["wheel_load_rms_n"])
        rest = worst_row["at_rest"]
        freq = rest["frequency_hz"]
        lines.append(
            f"- **{kind}** car at rest, before any input, in {len(rows)} of "
            f"{sum(x['kind'] == kind for x in report['rows'])} manoeuvres: wheel load up to "
            f"{rest['wheel_load_rms_n']:.0f} N RMS ({worst_row['manoeuvre']}, first "
            f"{rest['seconds']:.2f} s"
            + (f", dominant {freq:.1f} Hz" if freq else "") + "); the reference car: 0 N."
        )  # fmt: skip
    return lines


def divergence_lines(report: dict[str, Any]) -> list[str]:
    ended = [r for r in report["rows"] if r["end"].get("reason")]
    if not ended:
        return ["No model car left its bounds or diverged in any manoeuvre (HalfCar-v0's "
                "termination never fired)."]  # fmt: skip
    return [
        "HalfCar-v0 ended these model cars' episodes before the manoeuvre's end (the twin with "
        "the reference bushing stayed within its bounds unless said):", "",
        *(f"- **{r['kind']}** in {r['manoeuvre']}: {_end(r)}: {r['end']['reason']}"
          for r in ended),
    ]  # fmt: skip


def _table(report: dict[str, Any], key: str) -> list[str]:
    names = [o.name for o in OUTPUTS]
    head = ["manoeuvre", "bushing", "run",
            *(f"{COORD_SHORT[c]} err" for c in COORDS),
            *(SHORT[n] for n in names), "a_w (Wk)", "transfer"]  # fmt: skip
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in report["rows"]:
        comp = r["component"]["open_loop"]
        veh = r["vehicle"]
        cells = [r["manoeuvre"], r["kind"], _end(r),
                 *(_pct(comp[c][key]) for c in COORDS),
                 *(_pct(veh[n][key]) for n in names),
                 _pct(veh["a_w_Wk"]["difference_pct"]),
                 "n/a" if r["transfer"] is None else f"{r['transfer']:.2f}"]  # fmt: skip
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _pair_table(report: dict[str, Any]) -> list[str]:
    names = [o.name for o in OUTPUTS]
    head = ["manoeuvre", "car", "against", *(SHORT[n] for n in names), "a_w (Wk)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for p in report["pairs"]:
        veh = p["vehicle"]
        cells = [p["manoeuvre"], p["kind"], p["baseline"],
                 *(_pct(veh[n]["peak_pct"]) for n in names),
                 _pct(veh["a_w_Wk"]["difference_pct"])]  # fmt: skip
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _params(m: dict[str, Any]) -> str:
    skip = {"name", "title", "source", "samples", "duration_s", "peak_road_m",
            "peak_lateral_accel_m_per_s2"}  # fmt: skip
    out = []
    for k, v in m.items():
        if k in skip:
            continue
        out.append(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}")
    return ", ".join(out)


def markdown(report: dict[str, Any], figures: list[str] | None = None) -> str:
    """``report.md``: the finding first, then what was judged, the tables, the definitions."""
    lines = ["# Bushing models in a car: the standard manoeuvres in HalfCar-v0", ""]
    lines += finding_lines(report) + [""] + divergence_lines(report) + [""]
    rest = at_rest_lines(report)
    if rest:
        lines += ["Model cars that moved standing on a flat road with no lateral load:", "",
                  *rest, ""]  # fmt: skip
    t = report.get("wall_time_s", report["run_seconds"])
    lines += [
        f"{len(report['manoeuvres'])} manoeuvres x {len(report['kinds'])} bushing kinds "
        f"({', '.join(report['kinds'])}); wall time {t:.0f} s (of which the car runs "
        f"{report['run_seconds']:.0f} s).", "",
        "## What was judged", "",
        f"- **Car**: `{report['env']}` (docs/envs.md), dt {report['dt_s']:.6g} s; spec "
        f"overrides {report['env_kwargs'] or 'none'} (the replay's input check only).",
        f"- **Reference**: `{report['reference']}` in all four pivots of the twin car (the "
        "coupled three-axis rubber, measurement effects off); every model car is compared with "
        "its twin, which drives the same inputs.",
        "- **Bushings** (one model in all four pivots: lower and upper arm, left and right):", "",
        "| kind | model | how it was made | file | sha256 |", "|---|---|---|---|---|",
    ]  # fmt: skip
    for b in report.get("bushings", {}).values():
        lines.append(f"| {b['kind']} | {b['model']} | {b['how']} | `{b['file']}` | "
                     f"{b['sha256'][:12]} |")  # fmt: skip
    lines += ["", "- **Manoeuvres** (HalfCar-v0 inputs: road heights per side; a lateral "
              "acceleration from the linear single-track model at the speed stated):", "",
              "| manoeuvre | source | s | peak road mm | peak a_y m/s^2 | parameters |",
              "|---|---|---|---|---|---|"]  # fmt: skip
    for m in report["manoeuvres"]:
        lines.append(f"| {m['name']} ({m['title']}) | {m['source']} | {m['duration_s']:.2f} | "
                     f"{1e3 * m['peak_road_m']:.1f} | {m['peak_lateral_accel_m_per_s2']:.2f} | "
                     f"{_params(m)} |")  # fmt: skip
    lines += [
        "", "## RMS differences, % of the reference car's own RMS", "",
        *_table(report, "rms_pct"),
        "", "## Peak differences, % of the reference car's own peak", "",
        *_table(report, "peak_pct"),
        "", "## Seed 000's comparison: each car against the linear car (peak, % of the linear "
        "car's peak)", "", *_pair_table(report), "",
        "## Definitions", "",
        "- Vehicle difference of an output y: `max|y_model - y_ref| / max|y_ref|` (peak) and "
        "`rms(y_model - y_ref) / rms(y_ref)` (RMS), over the steps both cars ran; wheel loads "
        "and cambers both sides together, wheel load less its static value. `n/a`: the "
        "reference's RMS is below the output's floor (the roll on a bump under both wheels).",
        "- a_w (Wk): `|a_w,model - a_w,ref| / a_w,ref` of the ISO 2631-1 Wk-weighted RMS body "
        "vertical acceleration.",
        "- Component error (`F_ax err`, `F_rad err`, `M err`): the model's and the reference's "
        "bushing laws driven open loop, from rest, by the same deflection history (the model "
        "car's four pivots in that manoeuvre): force difference over the reference law's "
        "force, the four pivots together. The in-car force difference (each car on its own "
        "motion) is in report.json (`component.in_car`).",
        "- Transfer: the largest RMS difference of the judged outputs (wheel load, roll, camber, "
        "track change) over the largest component RMS error of the row: how much of a "
        "component error reaches the car.",
        "- `run`: `ran` to the manoeuvre's end, or where HalfCar-v0 ended the episode: "
        "`TERMINATED` (the model car diverged or left its bounds: a force or moment beyond its "
        "limit or not finite, a bushing deflection beyond the rubber's 14.5 mm, travel, roll), "
        "`model error` (the model raised), `twin left bounds`; the differences are then over "
        "the steps before.",
    ]  # fmt: skip
    outside = [r for r in report["rows"] if r["reference_outside_range_steps"]]
    if outside:
        lines.append(f"- The reference twin's pivot rotation went beyond its calibrated range in "
                     f"{len(outside)} run(s) (steps counted in report.json): its forces there "
                     "are an extrapolation.")  # fmt: skip
    if figures:
        lines += ["", "## Figures", ""]
        lines += [f"![{Path(f).stem}]({Path(f).name})" for f in figures]
    return "\n".join(lines) + "\n"


def plot_manoeuvre(manoeuvre: Manoeuvre, runs: dict[str, CarRun], path: str | Path) -> Path:
    """Input, body roll and both wheel loads against time: the reference car (black) and each
    model car (``runs``: label -> run of this manoeuvre, ``REFERENCE_CAR`` a run of the
    reference alone); a car that ended early is marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    t_in = manoeuvre.dt_s * np.arange(1, manoeuvre.samples + 1)
    if np.any(manoeuvre.road_m):
        ax[0].plot(t_in, 1e3 * manoeuvre.road_m[:, 0], label="left")
        ax[0].plot(t_in, 1e3 * manoeuvre.road_m[:, 1], "--", label="right")
        ax[0].set_ylabel("road height [mm]")
    else:
        ax[0].plot(t_in, manoeuvre.lateral_accel_m_per_s2, label="a_y (single-track model)")
        ax[0].set_ylabel("lateral load a_y [m/s$^2$]")
    ref = max(runs.values(), key=lambda r: r.steps)
    runs = {k: r for k, r in runs.items() if k != REFERENCE_CAR}
    panels = [(1, "roll", 0, np.degrees, "body roll [deg]"),
              (2, "wheel_load", 0, lambda x: x / 1e3, "dynamic wheel load left [kN]"),
              (3, "wheel_load", 1, lambda x: x / 1e3, "dynamic wheel load right [kN]")]  # fmt: skip
    for i, name, col, conv, ylabel in panels:
        ax[i].plot(ref.time_s, conv(ref.reference[name][:, col]), "k", lw=2.2,
                   label="reference bushing (rubber)")  # fmt: skip
        for label, run in runs.items():
            y = conv(run.model[name][:, col])
            (line,) = ax[i].plot(run.time_s, y, lw=1.1, label=f"{label} bushing")
            if run.end.get("reason") and run.steps:
                ax[i].plot(run.time_s[-1], y[-1], "x", ms=10, color=line.get_color())
        ax[i].set_ylabel(ylabel)
    ax[-1].set_xlabel("time [s]")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=7, loc="best")
    ended = any(r.end.get("reason") for r in runs.values())
    note = "\n(x: HalfCar-v0 ended that car's episode there)" if ended else ""
    fig.suptitle(f"{manoeuvre.title} ({manoeuvre.source}): model cars against the reference "
                 f"car{note}", fontsize=10)  # fmt: skip
    fig.tight_layout()
    return write_figure(fig, path)
