"""The files of a diagnosis over C coordinates: ``DIR/report.json``, ``report.md``,
``coordinates.png``, ``predictions/<stem>.csv`` (every coordinate) and, per coordinate,
``DIR/<coordinate>/`` holding that coordinate's one-axis report (``report.write_report``)."""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.persist import write_figure, write_text

KEYS = ("force_measured", "force_baseline", "force_augmented")


def write_coordinate_predictions(pred: dict[str, Any], coords: list[str], path: Path) -> None:
    """``time`` then, per coordinate c, ``force_measured_c,force_baseline_c,force_augmented_c``."""
    cols, head = [np.asarray(pred["time"], float)], ["time"]
    for i, c in enumerate(coords):
        for key in KEYS:
            cols.append(np.asarray(pred[key], float)[:, i])
            head.append(f"{key}_{c}")
    text = io.StringIO()
    np.savetxt(text, np.column_stack(cols), delimiter=",", header=",".join(head), comments="",
               fmt="%.10g")  # fmt: skip
    write_text(path, text.getvalue())


def coordinates_plot(result: dict[str, Any], out: Path) -> str:
    """Bars per coordinate: the gap with the baseline, with the answer's model, the noise."""
    from bushenv.diagnose.plots import _plt

    plt = _plt()
    rows = result["coordinates"]
    x = np.arange(len(rows))
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for off, key, label in (
        (-0.27, "gap_before", "baseline"),
        (0.0, "gap_after", "with the effect named"),
        (0.27, "gap_noise", "force noise"),
    ):
        ax.bar(x + off, [100 * (r[key] or 0.0) for r in rows], 0.27, label=label)
    ax.set_xticks(x, [f"{r['coordinate']}\n{r['effect']}" for r in rows], fontsize=8)
    ax.set_ylabel("gap, % of the coordinate's RMS force")
    ax.legend(fontsize=8)
    ax.set_title(f"which coordinate: {result['answer']}")
    fig.tight_layout()
    write_figure(fig, out / "coordinates.png", dpi=100)
    return "coordinates.png"


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:.2f} %"


def coordinates_markdown(data: dict[str, Any]) -> str:
    recs = data["records"]
    lines = [
        f"# Sim-to-real gap diagnosis over {len(data['coords'])} coordinates",
        "",
        f"- mode: {data['mode_text']}",
    ]
    for t in recs["train"]:
        lines.append(f"- TRAIN: `{t['name']}` ({t['samples']} samples at {t['rate_hz']:.6g} Hz)")
    for t in recs["tests"]:
        lines.append(f"- TEST: `{t['name']}` ({t['samples']} samples at {t['rate_hz']:.6g} Hz)")
    lines += [
        f"- baseline: `linear` over the coordinates: {data['baseline_model']['text']}",
        "",
        f"## Which coordinate, which effect: **{data['answer']}**",
        "",
    ]
    if data["coordinate"]:
        lines += [
            f"Gap on {data['coordinate']} (RMS ratio, seed 000 eq. 8, all judged records "
            f"together): {_pct(data['gap_before'])} with the baseline, "
            f"{_pct(data['gap_after'])} with {data['effect']} added (shrink "
            f"{100 * data['shrink']:.1f} %).",
            "",
        ]
    lines += [
        f"Rule: {data['rule']}.",
        "",
        "| coordinate | units | gap (baseline) | gap after | shrink | noise | share above noise "
        "| effect | top two | report |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in data["coordinates"]:
        lines.append(
            f"| {r['coordinate']} | {r['unit']}, {r['force_unit']} | {_pct(r['gap_before'])} | "
            f"{_pct(r['gap_after'])} | {100 * r['shrink']:.1f} % | {_pct(r['gap_noise'])} | "
            f"{_pct(r['share_above_noise'])} | {r['effect']} | {', '.join(r['top_two'])} | "
            + (f"[{r['report']}]({r['report']}) |" if r["report"] else "- |")
        )
    lines += ["", "![coordinates](coordinates.png)", "", "## Baseline matrices (SI)", ""]
    units = ", ".join(f"{c} {u}" for c, u in zip(data["coords"], data["units"], strict=True))
    lines += [f"Coordinates: {units}; forces {', '.join(data['force_units'])}.", ""]
    for key in ("k_matrix", "c_matrix"):
        lines.append(f"- {key}:")
        lines += [f"  - {np.array2string(np.asarray(row), precision=6)}"
                  for row in data["baseline_model"][key]]  # fmt: skip
    lines += ["", "Predictions: " + ", ".join(f"`{p}`" for p in data["predictions"]), ""]
    for note in data.get("notes", []):
        lines.append(f"Note: {note}")
    return "\n".join(lines) + "\n"


def write_coordinates_report(result: dict[str, Any], out: Path) -> None:
    """report.json, report.md, coordinates.png, predictions/ and one folder per coordinate."""
    from bushenv.diagnose.report_files import json_safe, write_report

    out.mkdir(parents=True, exist_ok=True)
    (out / "predictions").mkdir(exist_ok=True)
    coords = result["coords"]
    for name, diagnosis in result["diagnoses"].items():
        write_report(diagnosis, out / name)
    for pred in result["predictions"]:
        write_coordinate_predictions(pred, coords, out / "predictions" / f"{pred['name']}.csv")
    data = {k: v for k, v in result.items() if k not in ("predictions", "diagnoses")}
    data["predictions"] = [f"predictions/{p['name']}.csv" for p in result["predictions"]]
    data["diagnoses"] = {name: f"{name}/report.json" for name in result["diagnoses"]}
    data["plots"] = [coordinates_plot(result, out)]
    write_text(out / "report.json", json.dumps(json_safe(data), indent=2) + "\n")
    write_text(out / "report.md", coordinates_markdown(data))
