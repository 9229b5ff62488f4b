"""``bushenv diagnose``: a baseline's sim-to-real gap, where it lies, which effect closes it.

    bushenv diagnose TRAIN_CSV TEST_CSV [TEST_CSV ...] --out DIR [--baseline linear|...]

TRAIN identifies the baseline and every candidate effect; the TESTs judge (held out). Writes

- ``DIR/report.json``: effect named, ranking, pairs tried, where the gap lies (docs/diagnose.md)
- ``DIR/report.md`` with the plots ``DIR/*.png``
- ``DIR/predictions/<test-file-stem>.csv``: time,force_measured,force_baseline,force_augmented

An existing DIR is refused unless ``--force``; with ``--force`` only the files named above are
replaced, nothing else in DIR is touched. The core is ``bushenv.diagnose.fit.diagnose``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.diagnose.fit import BASELINES, DiagnoseError, diagnose

EXAMPLE = "bushenv diagnose train.csv test_random.csv test_steps.csv --out diag/ --baseline linear"
PLOTS = ("ranking.png", "where_regimes.png", "where_spectrum.png", "where_time.png")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("train", metavar="TRAIN_CSV", help="record that identifies the models")
    parser.add_argument("tests", metavar="TEST_CSV", nargs="+", help="held-out records that judge")
    parser.add_argument(
        "--out", required=True, metavar="DIR", help="output folder (must not exist)"
    )
    parser.add_argument(
        "--baseline",
        default="linear",
        choices=BASELINES,
        help="baseline model identified on TRAIN (default: linear, by least squares)",
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="write into an existing DIR (replaces only the report's own files)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed for baseline identification")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")


def run(args: argparse.Namespace) -> int:
    from bushenv.records import load_csv

    out = Path(args.out)
    check_out_dir(out, args.force)
    start = time.monotonic()

    def progress(msg: str) -> None:
        if not args.quiet:
            print(f"[{time.monotonic() - start:6.1f} s] {msg}", file=sys.stderr, flush=True)

    progress(f"loading TRAIN {args.train}")
    train = load_csv(args.train)
    tests = []
    for path in args.tests:
        progress(f"loading TEST {path}")
        tests.append(load_csv(path))
    stems = [Path(p).stem for p in args.tests]
    if len(set(stems)) != len(stems):
        raise DiagnoseError(
            f"TEST files need distinct file names (stems {stems}): each one's predictions go to "
            "predictions/<stem>.csv"
        )
    result = diagnose(
        train, tests, baseline=args.baseline, progress=progress, seed=args.seed, test_names=stems
    )
    result["files"] = {"train": str(args.train), "tests": [str(p) for p in args.tests]}
    progress(f"writing {out}")
    write_report(result, out)
    progress(
        f"done: effect {result['effect']}, gap {100 * result['gap_before']:.2f} % -> "
        f"{100 * result['gap_after']:.2f} % (shrink {100 * result['shrink']:.0f} %)"
    )
    print(out / "report.md")
    return 0


def check_out_dir(out: Path, force: bool) -> None:
    if out.exists() and not out.is_dir():
        raise DiagnoseError(f"--out {out}: exists and is not a folder; refusing to touch it")
    if out.exists() and not force:
        raise DiagnoseError(
            f"--out {out}: folder already exists; refusing to write into it (pass --force to "
            "replace the report's own files there; nothing else is touched)"
        )


# ----- writing -----------------------------------------------------------------------------
def _json_safe(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, float | np.floating):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def _atomic_write(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix="." + path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_predictions(pred: dict[str, Any], path: Path) -> None:
    cols = ("time", "force_measured", "force_baseline", "force_augmented")
    data = np.column_stack([np.asarray(pred[c], dtype=np.float64) for c in cols])
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix="." + path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            np.savetxt(fh, data, delimiter=",", header=",".join(cols), comments="", fmt="%.10g")
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_report(result: dict[str, Any], out: Path) -> None:
    """report.json, report.md, plots and predictions/<stem>.csv under ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "predictions").mkdir(exist_ok=True)
    for pred in result["predictions"]:
        write_predictions(pred, out / "predictions" / f"{pred['name']}.csv")
    data = {k: v for k, v in result.items() if k != "predictions"}
    data["predictions"] = [f"predictions/{p['name']}.csv" for p in result["predictions"]]
    data["plots"] = []
    plots = make_plots(result, out)
    data["plots"] = plots
    _atomic_write(out / "report.json", json.dumps(_json_safe(data), indent=2) + "\n")
    _atomic_write(out / "report.md", markdown(data))


def make_plots(result: dict[str, Any], out: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bushenv.diagnose.regimes import residual_spectrum

    names = []
    # ranking
    fig, ax = plt.subplots(figsize=(7, 3.5))
    rows = result["ranking"] + result["pairs"]
    labels = [r["effect"] for r in rows]
    shrinks = [100 * r["shrink"] for r in rows]
    colors = ["tab:green" if r["effect"] == result["effect"] else "tab:gray" for r in rows]
    ax.barh(labels[::-1], shrinks[::-1], color=colors[::-1])
    ax.axvline(100 * result["rule"]["shrink_min"], color="k", ls="--", lw=0.8)
    ax.set_xlabel("held-out gap shrink, %  (dashed: naming threshold)")
    ax.set_title(f"which effect: {result['effect']}")
    fig.tight_layout()
    fig.savefig(out / "ranking.png", dpi=100)
    plt.close(fig)
    names.append("ranking.png")

    # regimes
    regs = result["where"]["regimes"]
    regs_after = result["where_after"]["regimes"]
    keys = list(regs)
    xpos = np.arange(len(keys))
    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.bar(xpos - 0.27, [100 * regs[k]["time_share"] for k in keys], 0.27, label="time share")
    ax.bar(xpos, [100 * regs[k]["energy_share"] for k in keys], 0.27, label="gap energy, baseline")
    ax.bar(
        xpos + 0.27,
        [100 * regs_after[k]["energy_share"] for k in keys],
        0.27,
        label="gap energy, augmented",
    )
    ax.set_xticks(xpos, [k.replace("_", "\n") for k in keys], fontsize=8)
    ax.set_ylabel("%")
    ax.legend(fontsize=8)
    ax.set_title("where: share of the held-out gap energy by regime")
    fig.tight_layout()
    fig.savefig(out / "where_regimes.png", dpi=100)
    plt.close(fig)
    names.append("where_regimes.png")

    # spectrum and coherence
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    for pred in result["predictions"]:
        dt, x = pred["dt"], np.asarray(pred["displacement"])
        fm = np.asarray(pred["force_measured"])
        f, p, coh = residual_spectrum(fm - pred["force_baseline"], x, dt)
        _, pa, _ = residual_spectrum(fm - pred["force_augmented"], x, dt)
        a1.loglog(f[1:], p[1:], label=f"{pred['name']} baseline")
        a1.loglog(f[1:], pa[1:], ls="--", label=f"{pred['name']} augmented")
        a2.semilogx(f[1:], coh[1:], label=pred["name"])
    a1.set_ylabel("residual PSD, N²/Hz")
    a1.legend(fontsize=7)
    a2.set_ylabel("coherence with input")
    a2.set_xlabel("frequency, Hz")
    a2.set_ylim(0, 1.05)
    a1.set_title("where: residual spectrum")
    fig.tight_layout()
    fig.savefig(out / "where_spectrum.png", dpi=100)
    plt.close(fig)
    names.append("where_spectrum.png")

    # over time: running RMS of the residual
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for pred in result["predictions"]:
        t = np.asarray(pred["time"])
        dt = float((t[-1] - t[0]) / (t.size - 1))
        w = max(int(round(1.0 / dt)), 1)
        for key, ls in (("force_baseline", "-"), ("force_augmented", "--")):
            r = np.asarray(pred["force_measured"]) - np.asarray(pred[key])
            run = np.sqrt(np.convolve(r * r, np.ones(w) / w, mode="same"))
            step = max(t.size // 4000, 1)
            ax.plot(t[::step], run[::step], ls=ls, label=f"{pred['name']} {key[6:]}")
    ax.set_xlabel("time, s")
    ax.set_ylabel("1 s running RMS of the gap, N")
    ax.legend(fontsize=7)
    ax.set_title("where: the gap over time")
    fig.tight_layout()
    fig.savefig(out / "where_time.png", dpi=100)
    plt.close(fig)
    names.append("where_time.png")

    # one force window per TEST
    for pred in result["predictions"]:
        t = np.asarray(pred["time"])
        dt = float((t[-1] - t[0]) / (t.size - 1))
        fm = np.asarray(pred["force_measured"])
        r = fm - np.asarray(pred["force_baseline"])
        w = min(t.size, max(int(round(4.0 / dt)), 16))
        # the 4 s window where the baseline's gap is largest
        e = np.convolve(r * r, np.ones(w), mode="valid")
        i0 = int(np.argmax(e))
        sl = slice(i0, i0 + w)
        fig, ax = plt.subplots(figsize=(8, 3.5))
        ax.plot(t[sl], fm[sl], "k", lw=1, label="measured")
        ax.plot(t[sl], np.asarray(pred["force_baseline"])[sl], lw=1, label="baseline")
        ax.plot(t[sl], np.asarray(pred["force_augmented"])[sl], "--", lw=1, label="augmented")
        ax.set_xlabel("time, s")
        ax.set_ylabel("force, N")
        ax.legend(fontsize=8)
        ax.set_title(f"{pred['name']}: the 4 s with the largest baseline gap")
        fig.tight_layout()
        name = f"forces_{pred['name']}.png"
        fig.savefig(out / name, dpi=100)
        plt.close(fig)
        names.append(name)
    return names


def markdown(data: dict[str, Any]) -> str:
    pct = lambda v: f"{100 * v:.2f} %"  # noqa: E731
    lines = [
        "# Sim-to-real gap diagnosis",
        "",
        f"- TRAIN: `{data.get('files', {}).get('train', 'train')}` "
        f"({data['records']['train']['samples']} samples at "
        f"{data['records']['train']['rate_hz']:.6g} Hz)",
    ]
    for t in data["records"]["tests"]:
        lines.append(f"- TEST: `{t['name']}` ({t['samples']} samples at {t['rate_hz']:.6g} Hz)")
    lines += [
        f"- baseline: `{data['baseline']}`",
        "",
        f"## Which effect: **{data['effect']}**",
        "",
        f"Gap (RMS ratio, seed 000 eq. 8, all TESTs together): {pct(data['gap_before'])} with the "
        f"baseline, {pct(data['gap_after'])} with the named effect added "
        f"(shrink {100 * data['shrink']:.1f} %).",
        "",
        f"Rule: {data['rule']['text']}",
        "",
        "| rank | effect | gap before | gap after | shrink | extra parameters | passes rule |",
        "|---|---|---|---|---|---|---|",
    ]
    for i, r in enumerate(data["ranking"], 1):
        lines.append(
            f"| {i} | {r['effect']} | {pct(r['gap_before'])} | {pct(r['gap_after'])} | "
            f"{100 * r['shrink']:.1f} % | {r['n_extra_parameters']} | {r['passes']} |"
        )
    if data["pairs"]:
        lines += ["", "Pairs tried:", "", "| pair | gap after | shrink | passes rule |"]
        lines.append("|---|---|---|---|")
        for r in data["pairs"]:
            lines.append(
                f"| {r['effect']} | {pct(r['gap_after'])} | {100 * r['shrink']:.1f} % | "
                f"{r['passes']} |"
            )
    lines += ["", "![ranking](ranking.png)", "", "## Where the gap lies (baseline)", ""]
    lines += [f"- {s}" for s in data["where"]["summary"]]
    lines += [
        "",
        "| regime | time share | gap energy share (baseline) | (augmented) |",
        "|---|---|---|---|",
    ]
    for k, v in data["where"]["regimes"].items():
        va = data["where_after"]["regimes"][k]
        lines.append(
            f"| {k} | {pct(v['time_share'])} | {pct(v['energy_share'])} | "
            f"{pct(va['energy_share'])} |"
        )
    lines += ["", "| band | gap energy share |", "|---|---|"]
    for b in data["where"]["frequency"]["bands"]:
        hi = "Nyquist" if b["hi_hz"] is None or not math.isfinite(b["hi_hz"]) else f"{b['hi_hz']:g}"
        lines.append(f"| {b['lo_hz']:g} - {hi} Hz | {pct(b['energy_share'])} |")
    lines += [
        "",
        f"Linearly coherent with the input: {pct(data['where']['frequency']['coherent_share'])}.",
        "",
        "![regimes](where_regimes.png)",
        "",
        "![spectrum](where_spectrum.png)",
        "",
        "![time](where_time.png)",
        "",
    ]
    for p in data["plots"]:
        if p.startswith("forces_"):
            lines += [f"![{p}]({p})", ""]
    lines += ["## Augmented model parameters", ""]
    lines += [f"- {k}: {v:.6g}" for k, v in data["parameters"].items()]
    lines += ["", "Predictions: " + ", ".join(f"`{p}`" for p in data["predictions"]), ""]
    for note in data.get("notes", []):
        lines.append(f"Note: {note}")
    return "\n".join(lines) + "\n"
