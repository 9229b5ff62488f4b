"""The adversary's report: the finding per bushing kind in a few lines, the tables, the figures
(what every search tried against the worst standard manoeuvre; the found manoeuvre replayed)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bushenv.persist import write_figure
from bushenv.vehicle import adversary_space as space
from bushenv.vehicle.compare import run_car
from bushenv.vehicle.report import plot_manoeuvre


def _f(v: float | None, digits: int = 1) -> str:
    return "n/a" if v is None else f"{v:.{digits}f}"


def _params(p: dict[str, Any]) -> str:
    skip = {"family", "unit_point", "clipped", "ay_scaled_by", "fade_in_s", "duration_s"}
    out = []
    for k, v in p.items():
        if k in skip or isinstance(v, list | dict):
            continue
        out.append(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}")
    return ", ".join(out)


def kind_lines(k: dict[str, Any]) -> list[str]:
    """The finding for one kind in a few lines."""
    w, f = k["worst_standard"], k["found"]
    lines = [f"### {k['kind']} bushings in all four pivots"]
    if w is not None:
        lines.append(f"- worst standard manoeuvre that ran to the end: **{w['kind']}**, wheel-load "
                     f"difference {_f(w['d_pct'])} % of the reference car's peak "
                     f"({_f(w['difference_peak_n'], 0)} N of "
                     f"{_f(w['reference_peak_n'], 0)} N)")  # fmt: skip
    if k["standard_terminated"]:
        lines.append(f"- standard manoeuvres that ended the model car: "
                     f"{', '.join(k['standard_terminated'])}")  # fmt: skip
    if f is not None:
        amp = f" = **{k['amplification']:.2f}x** the worst standard" if k["amplification"] else ""
        lines.append(f"- found by {f['searcher']} (evaluation {f['evaluation']}): "
                     f"**{f['params']['family']}** ({_params(f['params'])}): {_f(f['d_pct'])} % "
                     f"({_f(f['difference_peak_n'], 0)} N of {_f(f['reference_peak_n'], 0)} N)"
                     f"{amp}")  # fmt: skip
        o = f["outputs_peak_pct"]
        lines.append("- the same run's other outputs (peak difference, % of the reference "
                     "car's peak): " + ", ".join(f"{n} {_f(v)}" for n, v in o.items()))  # fmt: skip
    else:
        lines.append("- no searched manoeuvre ran to the end in both cars")
    b = k.get("blame")
    if b:
        c = b["carried_by"]
        lines.append(
            f"- re-measured in the pymunk env (HalfCar-v0 itself): {_f(b['d_pct_all_four'])} %"
        )
        lines.append(f"- carried by the **{c['pivot']}** pivot (the reference bushing there "
                     f"takes D from {_f(b['d_pct_all_four'])} % to "
                     f"{_f(b['swap'][c['pivot']]['d_pct_reference_here'])} %), largest in-car "
                     f"force difference there in **{c['coordinate']}**")  # fmt: skip
    ended = {n: t for n, t in k["terminations"].items() if t["ended"]}
    for n, t in ended.items():
        lines.append(f"- {n}: {t['ended']} of {t['tried']} searched profiles ended the model car; "
                     f"earliest at {_f(t['earliest_s'], 2)} s ({t['earliest_reason']}; "
                     f"{_params(t['earliest_params'])}); smallest input that ended it "
                     f"{_f(t['smallest_input_ended'], 2)} {t['input_unit']}, largest that ran "
                     f"to the end {_f(t['largest_input_ran'], 2)} {t['input_unit']}")  # fmt: skip
    return lines


def markdown(report: dict[str, Any], figures: list[str] | None = None) -> str:
    lines = ["# The adversary in HalfCar-v0", "",
             f"Objective: {report['objective']}. Judge: the {report['judge']['reference']} "
             f"bushing in the twin; a profile fails when {report['judge']['criteria']} "
             f"({report['judge']['tolerance_pct']:g} %). Searchers "
             f"{', '.join(report['config']['searchers'])}, {report['config']['budget']} car "
             f"runs each per kind, seed {report['config']['seed']}; "
             f"{report['seconds']:.0f} s.", ""]  # fmt: skip
    for k in report["kinds"].values():
        lines += [*kind_lines(k), ""]
    lines += [
        "## Standard manoeuvres (the same judge)",
        "",
        "| kind | manoeuvre | D % | D N | reference peak N | end |",
        "|---|---|---|---|---|---|",
    ]
    for k in report["kinds"].values():
        for e in k["standard"]:
            lines.append(f"| {k['kind']} | {e['kind']} | {_f(e['d_pct'])} | "
                         f"{_f(e['difference_peak_n'], 0)} | {_f(e['reference_peak_n'], 0)} | "
                         f"{e['end'] or 'ran'} |")  # fmt: skip
    lines += ["", "## Where the found difference sits (per pivot)", ""]
    for k in report["kinds"].values():
        b = k.get("blame")
        if not b:
            continue
        lines += [f"{k['kind']}: D with the model in all four pivots {_f(b['d_pct_all_four'])} %",
                  "", "| pivot | D %, reference here | D %, model here only | in-car RMS axial N, "
                  "radial N, moment N m (% of twin's) |", "|---|---|---|---|"]  # fmt: skip
        for pivot, s in b["swap"].items():
            fs = b["forces"][pivot]
            cells = ", ".join(f"{_f(fs[c]['in_car_rms'])} ({_f(fs[c]['in_car_pct'], 0)} %)"
                              for c in ("axial", "radial", "rotation"))  # fmt: skip
            lines.append(f"| {pivot} | {_f(s['d_pct_reference_here'])} | "
                         f"{_f(s['d_pct_model_here_only'])} | {cells} |")  # fmt: skip
        lines.append("")
    if figures:
        lines += ["## Figures", "", *[f"![{Path(p).stem}]({Path(p).name})" for p in figures]]
    return "\n".join(lines) + "\n"


def plot_search(report: dict[str, Any], kept: dict[str, Any], path: str | Path) -> Path:
    """Every profile a search kept (its failures and its worst): D against the evaluation, per
    kind and family; dashed the worst standard manoeuvre, x where the model car ended."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kinds = list(report["kinds"])
    fig, ax = plt.subplots(len(kinds), 1, figsize=(8, 2.8 * len(kinds)), squeeze=False)
    families = list(space.BUILDERS)
    colours = {f: plt.cm.tab10(i) for i, f in enumerate(families)}
    for a, kind in zip(ax[:, 0], kinds, strict=True):
        offset = 0
        for r in kept[kind]["results"]:
            es = [e for e in kept[kind]["entries"] if e["searcher"] == r.searcher]
            for fam in families:
                sel = [e for e in es if e["params"].get("family") == fam]
                for ended in (False, True):
                    pts = [e for e in sel if (e["criterion"] == "terminated") == ended]
                    if pts:
                        a.plot([offset + e["evaluation"] for e in pts],
                               [e["d_pct"] for e in pts], "x" if ended else "o", ms=4,
                               color=colours[fam], label=fam)  # fmt: skip
            a.axvline(offset + r.evaluations + 0.5, color="0.6", lw=0.8)
            a.text(offset + 1, 0, r.searcher, fontsize=7, va="bottom")
            offset += r.evaluations
        w = report["kinds"][kind]["worst_standard"]
        if w is not None:
            a.axhline(w["d_pct"], ls="--", color="k", label=f"worst standard ({w['kind']})")
        a.set_ylabel("wheel-load difference D\n[% of reference peak]")
        a.set_title(f"{kind} bushings: profiles the search kept (x: the model car ended)",
                    fontsize=9)  # fmt: skip
        a.grid(alpha=0.3)
        handles, labels = a.get_legend_handles_labels()
        uniq: dict = {}
        for label, handle in zip(labels, handles, strict=True):
            uniq.setdefault(label, handle)  # a family's dots before its crosses
        a.legend(uniq.values(), uniq.keys(), fontsize=6, loc="upper right", ncol=2)
    ax[-1, 0].set_xlabel("evaluation (searchers one after another)")
    fig.tight_layout()
    return write_figure(fig, path)


def plot_found(kind: str, kept: dict[str, Any], model, reference, path: str | Path) -> Path:
    """The found manoeuvre replayed: its input, roll and wheel loads, model car against the
    reference car."""
    f = kept["found"]
    m = space.as_manoeuvre(f["profile"], model.dt, "found", f["params"])
    kwargs = {"max_lateral_accel_step_m_per_s2": space.AY_STEP_M_PER_S2}
    run = run_car(m, model, reference, kind, kwargs)
    m = type(m)(m.name, f"found for {kind}: {f['params']['family']}", m.source, m.dt_s,
                m.road_m, m.lateral_accel_m_per_s2, m.params)  # fmt: skip
    return plot_manoeuvre(m, {kind: run}, path)
