"""``report.md`` of a diagnosis: the report.json content in tables and sentences."""

from __future__ import annotations

import math
from typing import Any


def _pct(v: float | None) -> str:
    return "n/a" if v is None else f"{100 * v:.2f} %"


def _value(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def _parameter_lines(params: dict[str, Any], indent: str = "") -> list[str]:
    lines = []
    for k, v in params.items():
        if isinstance(v, dict):
            lines.append(f"{indent}- {k}:")
            lines += _parameter_lines(v, indent + "  ")
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            lines.append(f"{indent}- {k}:")
            for item in v:
                lines.append(
                    f"{indent}  - " + ", ".join(f"{a} {_value(b)}" for a, b in item.items())
                )
        else:
            lines.append(f"{indent}- {k}: {_value(v)}")
    return lines


def _header(data: dict[str, Any]) -> list[str]:
    recs = data["records"]
    title = "# Sim-to-real gap diagnosis"
    if data.get("coordinate"):  # one coordinate of a diagnosis over several
        u = data["units"]
        title += f": coordinate {data['coordinate']} ({u['displacement']}, {u['force']})"
    lines = [title, "", f"- mode: {data['mode_text']}"]
    for t in recs["train"]:
        lines.append(f"- TRAIN: `{t['name']}` ({t['samples']} samples at {t['rate_hz']:.6g} Hz)")
    for t in recs["tests"]:
        lines.append(f"- TEST: `{t['name']}` ({t['samples']} samples at {t['rate_hz']:.6g} Hz)")
    for names in recs.get("sessions", []):
        lines.append(f"- run in one session, heat carried over: {' -> '.join(names)}")
    lines += [f"- judged: {', '.join(recs['judged'])}", f"- baseline: `{data['baseline']}`", ""]
    return lines


def _which(data: dict[str, Any]) -> list[str]:
    effect = data["effect"]
    if data.get("ambiguous_between"):
        effect += ": " + " or ".join(data["ambiguous_between"])
    lines = [
        f"## Which effect: **{effect}**",
        "",
        f"Gap (RMS ratio, seed 000 eq. 8, all judged records together): "
        f"{_pct(data['gap_before'])} with the baseline, {_pct(data['gap_after'])} with the "
        f"answer's model (shrink {100 * data['shrink']:.1f} %). Top two: "
        f"{', '.join(data['top_two'])}; runner-up (the best other candidate): "
        f"{data.get('runner_up') or '-'}.",
        "",
    ]
    if data.get("named_on_records"):  # named where the gap shows, not on all records
        lines += ["Named on: " + ", ".join(f"`{n}`" for n in data["named_on_records"]) + ".", ""]
    if data.get("telling_test"):
        lines += [data["telling_test"] + ".", ""]
    if data.get("delay_evidence"):
        lines += [f"Delay: {data['delay_evidence']['text']}.", ""]
    lines += [f"- {t}" for t in data["unexplained"]["text"]]
    if data["shift_warnings"]:
        lines += ["", "**Shift warning** -- regimes the judged records hold that TRAIN lacks:", ""]
        lines += [f"- {w['text']}" for w in data["shift_warnings"]]
    lines += ["", f"Rule: {data['rule']['text']}", ""]
    head = "| rank | effect | gap after | shrink | vs null | extra parameters | passes |"
    lines += [head, "|---|---|---|---|---|---|---|"]
    for i, r in enumerate(data["ranking"], 1):
        lines.append(
            f"| {i} | {r['effect']} | {_pct(r['gap_after'])} | {100 * r['shrink']:.1f} % | "
            f"{100 * r['shrink_vs_null']:.1f} % | {r['n_extra_parameters']} | {r['passes']} |"
        )
    if data.get("failed_to_fit"):
        lines += ["", "Failed to fit (the judged gap much worse than the null's; not ranked): "]
        lines[-1] += ", ".join(
            f"{r['effect']} ({_pct(r['gap_after'])})" for r in data["failed_to_fit"]
        )
    if data["pairs"]:
        lines += ["", "Pairs:", "", "| pair | gap after | shrink | each adds | passes |"]
        lines.append("|---|---|---|---|---|")
        for r in data["pairs"]:
            lines.append(
                f"| {r['effect']} | {_pct(r['gap_after'])} | {100 * r['shrink']:.1f} % | "
                f"{r.get('members_add')} | {r['passes']} |"
            )
    return lines + ["", "![ranking](ranking.png)", ""]


def _where(data: dict[str, Any]) -> list[str]:
    lines = ["## Where the gap lies (baseline)", ""]
    lines += [f"- {s}" for s in data["where"]["summary"]]
    lines += ["", "| regime | time share | gap energy (baseline) | (augmented) |"]
    lines.append("|---|---|---|---|")
    for k, v in data["where"]["regimes"].items():
        va = data["where_after"]["regimes"][k]
        lines.append(
            f"| {k} | {_pct(v['time_share'])} | {_pct(v['energy_share'])} | "
            f"{_pct(va['energy_share'])} |"
        )
    lines += ["", "| band | gap energy share |", "|---|---|"]
    for b in data["where"]["frequency"]["bands"]:
        hi = b["hi_hz"]
        hi = "Nyquist" if hi is None or not math.isfinite(hi) else f"{hi:g}"
        lines.append(f"| {b['lo_hz']:g} - {hi} Hz | {_pct(b['energy_share'])} |")
    lines += [
        "",
        f"Linearly coherent with the input: {_pct(data['where']['frequency']['coherent_share'])}.",
        "",
    ]
    for p in ("where_regimes.png", "where_spectrum.png", "where_time.png"):
        lines += [f"![{p}]({p})", ""]
    if data["records"].get("sessions"):
        lines += ["![where_session.png](where_session.png)", ""]
    return lines


def markdown(data: dict[str, Any]) -> str:
    lines = _header(data) + _which(data) + _where(data)
    lines += ["## Each judged record: force over time with residuals, and loops", ""]
    for p in data["plots"]:
        if p.startswith(("forces_", "loops_")):
            lines += [f"![{p}]({p})", ""]
    lines += ["## Model parameters (SI)", ""]
    lines += _parameter_lines(data["parameters"])
    lines += ["", "Predictions: " + ", ".join(f"`{p}`" for p in data["predictions"]), ""]
    for note in data.get("notes", []):
        lines.append(f"Note: {note}")
    return "\n".join(lines) + "\n"
