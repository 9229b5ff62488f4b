"""The diagnosis report's figures (matplotlib, Agg): ranking, where, and per judged record
the force over time with its residual panel and the force-deflection loops."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from bushenv.diagnose.regimes import residual_spectrum
from bushenv.persist import write_figure

MAX_POINTS = 3000  # points per curve drawn (records are decimated for the figure only)
SHOWN = {"m": ("mm", 1e3), "rad": ("mrad", 1e3)}  # a deflection unit as drawn, its factor


def units_of(result: dict[str, Any]) -> tuple[str, float, str]:
    """(deflection unit drawn, its factor from SI, force unit): a coordinate of a diagnosis
    over several names its own (``result["units"]``), one axis is m and N."""
    u = result.get("units") or {"displacement": "m", "force": "N"}
    shown, factor = SHOWN.get(u["displacement"], (u["displacement"], 1.0))
    return shown, factor, u["force"]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, out: Path, name: str, names: list[str]) -> None:
    fig.tight_layout()
    write_figure(fig, out / name, dpi=100)
    names.append(name)


def ranking_plot(result: dict[str, Any], out: Path, names: list[str]) -> None:
    plt = _plt()
    rows = result["ranking"] + result["pairs"]
    fig, ax = plt.subplots(figsize=(7, max(3.5, 0.22 * len(rows))))
    labels = [r["effect"] for r in rows]
    shrinks = [100 * r["shrink"] for r in rows]
    colors = ["tab:green" if r["effect"] == result["effect"] else "tab:gray" for r in rows]
    ax.barh(labels[::-1], shrinks[::-1], color=colors[::-1])
    ax.axvline(100 * result["rule"]["shrink_min"], color="k", ls="--", lw=0.8)
    ax.set_xlabel("held-out gap shrink, %  (dashed: naming threshold)")
    ax.set_xlim(left=max(-100.0, min(shrinks + [0.0])))
    ax.tick_params(axis="y", labelsize=7)
    ax.set_title(f"which effect: {result['effect']}")
    _save(fig, out, "ranking.png", names)


def regimes_plot(result: dict[str, Any], out: Path, names: list[str]) -> None:
    plt = _plt()
    regs, after = result["where"]["regimes"], result["where_after"]["regimes"]
    keys = list(regs)
    xpos = np.arange(len(keys))
    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.bar(xpos - 0.27, [100 * regs[k]["time_share"] for k in keys], 0.27, label="time share")
    ax.bar(xpos, [100 * regs[k]["energy_share"] for k in keys], 0.27, label="gap energy, baseline")
    ax.bar(
        xpos + 0.27,
        [100 * after[k]["energy_share"] for k in keys],
        0.27,
        label="gap energy, augmented",
    )
    ax.set_xticks(xpos, [k.replace("_", "\n") for k in keys], fontsize=8)
    ax.set_ylabel("share, %")
    ax.legend(fontsize=8)
    ax.set_title("where: share of the held-out gap energy by regime")
    _save(fig, out, "where_regimes.png", names)


def spectrum_plot(result: dict[str, Any], out: Path, names: list[str]) -> None:
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    for pred in result["predictions"]:
        dt, x = pred["dt"], np.asarray(pred["displacement"])
        fm = np.asarray(pred["force_measured"])
        f, p, coh = residual_spectrum(fm - pred["force_baseline"], x, dt)
        _, pa, _ = residual_spectrum(fm - pred["force_augmented"], x, dt)
        a1.loglog(f[1:], p[1:], label=f"{pred['name']} baseline")
        a1.loglog(f[1:], pa[1:], ls="--", label=f"{pred['name']} augmented")
        a2.semilogx(f[1:], coh[1:], label=pred["name"])
    force_unit = units_of(result)[2]
    squared = f"({force_unit})²" if " " in force_unit else f"{force_unit}²"
    a1.set_ylabel(f"residual PSD, {squared}/Hz")
    a1.legend(fontsize=7)
    a2.set_ylabel("coherence with input")
    a2.set_xlabel("frequency, Hz")
    a2.set_ylim(0, 1.05)
    a2.legend(fontsize=7)
    a1.set_title("where: residual spectrum")
    _save(fig, out, "where_spectrum.png", names)


def _plot_running_gap(ax, pred: dict[str, Any], t: np.ndarray) -> None:
    """The 1 s running RMS of the baseline's and the augmented model's gap at times ``t``."""
    w = max(int(round(1.0 / pred["dt"])), 1)
    step = max(t.size // MAX_POINTS, 1)
    for key, ls in (("force_baseline", "-"), ("force_augmented", "--")):
        r = np.asarray(pred["force_measured"]) - np.asarray(pred[key])
        run = np.sqrt(np.convolve(r * r, np.ones(w) / w, mode="same"))
        ax.plot(t[::step], run[::step], ls=ls, label=f"{pred['name']} {key[6:]}")


def time_plot(result: dict[str, Any], out: Path, names: list[str]) -> None:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for pred in result["predictions"]:
        _plot_running_gap(ax, pred, np.asarray(pred["time"]))
    ax.set_xlabel("time, s")
    ax.set_ylabel(f"1 s running RMS of the gap, {units_of(result)[2]}")
    ax.legend(fontsize=7)
    ax.set_title("where: the gap over time")
    _save(fig, out, "where_time.png", names)


def session_plot(result: dict[str, Any], out: Path, names: list[str]) -> None:
    """The gap through each session given by a run order: every judged record at its start
    in the session, the rests between left blank (a drift across records shows here)."""
    recs = result["records"]
    if not recs.get("sessions"):
        return
    plt = _plt()
    preds = {p["name"]: p for p in result["predictions"]}
    fig, axes = plt.subplots(
        len(recs["sessions"]), 1, figsize=(8, 2.5 + 1.5 * len(recs["sessions"])), squeeze=False
    )
    for ax, session in zip(axes[:, 0], recs["sessions"], strict=True):
        for name in session:
            if name not in preds:
                continue
            pred, t0 = preds[name], recs["session_time_s"][name]
            _plot_running_gap(ax, pred, np.asarray(pred["time"]) - pred["time"][0] + t0)
        ax.set_ylabel(f"1 s RMS gap, {units_of(result)[2]}")
        ax.legend(fontsize=7, ncol=2)
    axes[-1, 0].set_xlabel("time in the session, s (rests between records left blank)")
    axes[0, 0].set_title("where: the gap through the session, records in the order run")
    _save(fig, out, "where_session.png", names)


def _window(t: np.ndarray, r: np.ndarray, dt: float) -> tuple[slice, str]:
    """The whole record up to 30 s; else the window of max(10 s, 1/10) with the largest gap."""
    if t.size * dt <= 30.0:
        return slice(None), "whole record"
    w = max(int(round(max(10.0, 0.1 * t.size * dt) / dt)), 16)
    e = np.convolve(r * r, np.ones(w), mode="valid")
    i0 = int(np.argmax(e))
    return slice(i0, i0 + w), f"the {w * dt:.3g} s with the largest baseline gap"


def force_plot(pred: dict[str, Any], out: Path, names: list[str], force_unit: str = "N") -> None:
    """Force over time (measured, baseline, augmented) and, under it, both residuals."""
    plt = _plt()
    t = np.asarray(pred["time"])
    fm = np.asarray(pred["force_measured"])
    fb, fa = np.asarray(pred["force_baseline"]), np.asarray(pred["force_augmented"])
    sl, what = _window(t, fm - fb, pred["dt"])
    t, fm, fb, fa = t[sl], fm[sl], fb[sl], fa[sl]
    step = max(t.size // MAX_POINTS, 1)
    fig, (a1, a2) = plt.subplots(
        2, 1, figsize=(8, 5), sharex=True, gridspec_kw={"height_ratios": [2, 1]}
    )
    a1.plot(t[::step], fm[::step], "k", lw=1, label="measured")
    a1.plot(t[::step], fb[::step], lw=1, label="baseline")
    a1.plot(t[::step], fa[::step], "--", lw=1, label="augmented")
    a1.set_ylabel(f"force, {force_unit}")
    a1.legend(fontsize=8)
    a1.set_title(f"{pred['name']}: {what}")
    a2.plot(t[::step], (fm - fb)[::step], lw=0.8, label="measured - baseline")
    a2.plot(t[::step], (fm - fa)[::step], lw=0.8, label="measured - augmented")
    a2.axhline(0.0, color="k", lw=0.5)
    a2.set_xlabel("time, s")
    a2.set_ylabel(f"residual, {force_unit}")
    a2.legend(fontsize=7)
    _save(fig, out, f"forces_{pred['name']}.png", names)


def loops_plot(
    pred: dict[str, Any],
    out: Path,
    names: list[str],
    units: tuple[str, float, str] = ("mm", 1e3, "N"),
) -> None:
    """Force-deflection loops: measured, baseline, augmented (``units``: ``units_of``)."""
    plt = _plt()
    x = units[1] * np.asarray(pred["displacement"])
    step = max(x.size // (3 * MAX_POINTS), 1)
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for key, style, label in (
        ("force_measured", dict(color="k", lw=0.8), "measured"),
        ("force_baseline", dict(lw=0.8, alpha=0.8), "baseline"),
        ("force_augmented", dict(lw=0.8, ls="--", alpha=0.9), "augmented"),
    ):
        ax.plot(x[::step], np.asarray(pred[key])[::step], label=label, **style)
    ax.set_xlabel(f"deflection, {units[0]}")
    ax.set_ylabel(f"force, {units[2]}")
    ax.legend(fontsize=8)
    ax.set_title(f"{pred['name']}: force-deflection loops")
    _save(fig, out, f"loops_{pred['name']}.png", names)


def make_plots(result: dict[str, Any], out: Path) -> list[str]:
    """Every figure of the report; returns the file names (relative to ``out``)."""
    names: list[str] = []
    ranking_plot(result, out, names)
    regimes_plot(result, out, names)
    spectrum_plot(result, out, names)
    time_plot(result, out, names)
    session_plot(result, out, names)
    units = units_of(result)
    for pred in result["predictions"]:
        force_plot(pred, out, names, units[2])
        loops_plot(pred, out, names, units)
    return names
