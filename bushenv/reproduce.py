"""The papers' results reproduced: identify every model on the reference bushing, judge it unseen.

``bushenv reproduce --out DIR`` (also ``scripts/reproduce_papers.py``), per axis (axial, radial):

1. The virtual test machine runs the reference rubber bushing (with its measurement chain) on
   an RPC-like random drive at n = 1 (identification) and on two records never seen in
   training: another n = 1 record (the papers' protocol: seed 000 §4.2 judges on unseen data
   of the same random test) and an n = 1.5 record (50 % beyond the training amplitude).
2. linear (least squares), nn and hybrid (torch), boucwen (global search) are identified on the
   n = 1 record, each timed.
3. Each model runs free on both unseen records: RMS ratio (eq. 8), ESR (eq. 9), max error.
   Table 2/3 of seed 000 (linear, NN, hybrid), Table 4 of seed 002 (NN vs Bouc-Wen, radial),
   Table 5 (identification and verification times; the verification record is 6.44 s long).
4. The 4 mm step held 10 s: each model beside the reference; bounded or not, and when the NN
   departs (seed 000 saw 7.3 s), decided by ``bushenv.divergence`` (defined once there).

``DIR/report.json`` layout (every number of the printed tables)::

    {"axial": {"linear": {"rms_ratio", "esr", "max_error", "max_error_ratio", "peak_error",
                          "nrmse", "fit_index" (on the n = 1.5 record),
                          "same_amplitude": {the same metrics on the unseen n = 1 record},
                          "identification_s", "verification_s",
                          "linear_fit": {...} (linear only)}, "nn": {...}, ...},
     "radial": {...},
     "step": {"axial": {"nn": {"bounded": bool, "departure_s": float | null,
                               "criteria": [...], "worst_deviation": float,
                               "peak_force_n": float}, ...}, "radial": {...}},
     "paper": {...the published figures...}, "settings": {...}}

Ratios are fractions (0.051 = 5.1 %); forces in N; times in s.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from bushenv import metrics
from bushenv.models import AXES, MODELS, get_model
from bushenv.persist import json_text, write_figure, write_text
from bushenv.progress import Progress

# Identification time relative to the linear least squares, for the time-left estimate only.
EFFORT = {"linear": 1.0, "nn": 12.0, "hybrid": 15.0, "boucwen": 45.0}


def identified_models() -> tuple[str, ...]:
    """Every registered model that can be identified from a record (``MODELS`` with a fit)."""
    return tuple(name for name, entry in MODELS.items() if entry.fit is not None)


# Published figures (percent unless stated): seed 000 Tables 2-3, seed 002 Tables 4-5.
PAPER = {
    "table2": {  # prediction error on unseen random data, %
        "axial": {"linear": (9.8, 13.7), "nn": (5.1, 7.7), "hybrid": (4.8, 7.5)},
        "radial": {"linear": (11.9, 20.1), "nn": (4.3, 8.8), "hybrid": (4.6, 9.1)},
    },
    "table3": {  # 3-axes rig simulation: RMS ratio %, ESR %, MAX %
        "axial": {"linear": (10.9, 0.5, 24.9), "nn": (5.2, 0.2, 9.3), "hybrid": (5.1, 0.2, 8.4)},
        "radial": {"linear": (5.1, 0.4, 20.7), "nn": (3.0, 0.2, 8.3), "hybrid": (3.0, 0.2, 7.8)},
    },
    "table4": {  # radial: RMS ratio %, ESR %, max error N, peak error N
        "nn": (4.5, 0.2, 218.8, 56.0),
        "boucwen": (3.7, 0.1, 248.6, 163.2),
    },
    "table5": {  # identification and verification (6.44 s record) times
        "nn": {"identification_s": 263 * 60.0, "verification_s": 22 * 60.0},
        "boucwen": {"identification_s": 725 * 60.0, "verification_s": 4.0},
    },
    "step": {"nn_departure_s": 7.3, "hybrid": "bounded"},
}
VERIFICATION_RECORD_S = 6.44  # seed 002 §5: the verification data is 6.44 s long


def _records(axis: str, seed: int, ident_s: float, verif_s: float):
    """Training record (n = 1), unseen n = 1 record, unseen n = 1.5 record."""
    from bushenv.machine import random_test
    from bushenv.reference.rubber import RubberBushing

    # Separate drive and sensor-noise seeds: no two measurements share either.
    ref = RubberBushing.preset(axis, seed=seed)
    train = random_test(ref, n_index=1.0, duration_s=ident_s, seed=seed)
    ref = RubberBushing.preset(axis, seed=seed + 2)
    same = random_test(ref, n_index=1.0, duration_s=verif_s, seed=seed + 2)
    ref = RubberBushing.preset(axis, seed=seed + 1)
    test = random_test(ref, n_index=1.5, duration_s=verif_s, seed=seed + 1)
    return train, same, test


def _identify(name: str, axis: str, train, seed: int, shipped: bool):
    from bushenv.identify import fit_model

    t0 = time.perf_counter()
    if shipped and MODELS[name].shipped:
        model = get_model(name, axis=axis, dt=train.dt)
    else:
        # the papers' network (5 + 5 lags, 9 units): no choice of size on validation here
        options = MODELS[name].options_class()
        fixed = (
            {"choose": "off"} if "choose" in getattr(options, "__dataclass_fields__", {}) else {}
        )
        model = fit_model(
            name, train.displacement, train.force, train.dt, seed=seed, progress=True, **fixed
        )
    return model, time.perf_counter() - t0


def _verification_time(model, dt: float) -> float:
    """Seconds to run a 6.44 s record (the papers' verification task) through the model."""
    from bushenv.excitation import random_rpc

    x = random_rpc(1.5, VERIFICATION_RECORD_S, dt, seed=12345)
    model.simulate(x)  # warm (compiled kernels load once)
    reps, t0 = 0, time.perf_counter()
    while reps < 5 or time.perf_counter() - t0 < 0.2:
        model.simulate(x)
        reps += 1
    return (time.perf_counter() - t0) / reps


def _step_verdicts(axis: str, models: dict[str, Any], dt: float) -> dict[str, Any]:
    from bushenv.divergence import judge
    from bushenv.excitation import step_hold

    x = step_hold(4e-3, 10.0, dt, pre_s=1.0)
    from bushenv.reference.rubber import RubberBushing

    # The real part's step response (the specimen and its load cell, noise seed apart).
    f_ref = RubberBushing.preset(axis, seed=7).simulate(x)
    out: dict[str, Any] = {"time": None, "displacement": x, "reference": f_ref}
    for name, model in models.items():
        f = model.simulate(x)
        verdict = judge(x[:, None], f[:, None], f_ref[:, None], dt).row(0)
        out[name] = {"force": f, "verdict": verdict}
    return out


def reproduce(
    out: Path,
    axes: list[str],
    seed: int,
    ident_s: float,
    verif_s: float,
    shipped: bool,
    progress: Progress | None = None,
    models: tuple[str, ...] | None = None,
) -> dict[str, Any]:
    """Identify (or load) every model per axis (``models``, default every identified one),
    judge it on the unseen records and the step; writes ``out/report.json``, ``report.md`` and
    the plots; returns the report."""
    import torch

    progress = progress or Progress(quiet=True)
    names = identified_models() if models is None else tuple(models)
    progress.total = len(axes) * sum(EFFORT.get(n, 10.0) for n in names)
    _say = progress.say
    torch.manual_seed(seed)
    report: dict[str, Any] = {"paper": PAPER, "step": {}}
    report["settings"] = {
        "seed": seed,
        "identification_record_s": ident_s,
        "verification_record_s": verif_s,
        "shipped_models": shipped,
        "dt_s": None,
    }
    plots: dict[str, Any] = {}
    t_start = time.perf_counter()
    for axis in axes:
        _say(
            f"[{axis}] measuring the reference bushing: n=1 ({ident_s} s) to identify; unseen "
            f"n=1 and n=1.5 ({verif_s} s each)"
        )
        train, same, test = _records(axis, seed, ident_s, verif_s)
        report["settings"]["dt_s"] = train.dt
        models, rows = {}, {}
        for name in names:
            _say(f"[{axis}] identifying {name} ...")
            model, t_ident = _identify(name, axis, train, seed, shipped)
            models[name] = model
            f_sim = model.simulate(test.displacement)
            row = metrics.all_metrics(test.force, f_sim)
            row["same_amplitude"] = metrics.all_metrics(
                same.force, model.simulate(same.displacement)
            )
            row["identification_s"] = t_ident
            row["verification_s"] = _verification_time(model, train.dt)
            if name == "linear":
                row["linear_fit"] = {
                    "k_n_per_mm": model.k_n_per_m / 1e3,
                    "c_ns_per_mm": model.c_ns_per_m / 1e3,
                }
            rows[name] = row
            _say(
                f"[{axis}] {name:8s} RMS ratio unseen n=1 "
                f"{100 * row['same_amplitude']['rms_ratio']:5.2f} %, n=1.5 "
                f"{100 * row['rms_ratio']:5.2f} %  ESR {100 * row['esr']:5.2f} %  max "
                f"{row['max_error']:8.1f} N  (identified in {t_ident:.1f} s, "
                f"{time.perf_counter() - t_start:.0f} s total)"
            )
            plots.setdefault(axis, {})[name] = f_sim
            progress.update(progress.done + EFFORT.get(name, 10.0), f"[{axis}] {name} judged")
        report[axis] = rows
        _say(f"[{axis}] 4 mm step held 10 s ...")
        step = _step_verdicts(axis, models, train.dt)
        report["step"][axis] = {
            name: {
                "bounded": not step[name]["verdict"]["diverged"],
                "departure_s": step[name]["verdict"]["first_time_s"],
                "criteria": step[name]["verdict"]["criteria"],
                "worst_deviation": step[name]["verdict"]["worst_deviation"],
                "peak_force_n": float(np.max(np.abs(step[name]["force"]))),
            }
            for name in models
        }
        plots[axis]["_test"] = test
        plots[axis]["_step"] = step
    _write(out, report, plots)
    return report


def _write(out: Path, report: dict[str, Any], plots: dict[str, Any]) -> None:
    write_text(out / "report.json", json_text(report, indent=2))
    figures = _plot(out, plots)
    md = ["# The papers reproduced\n", "```", format_tables(report), "```\n"]
    md += [f"![{name}]({name})\n" for name in figures]
    write_text(out / "report.md", "\n".join(md))


def _plot(out: Path, plots: dict[str, Any]) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = []
    for axis, data in plots.items():
        test, step = data["_test"], data["_step"]
        t = np.arange(len(test.force)) * test.dt
        fig, ax = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
        ax[0].plot(t, 1e3 * test.displacement, "k", lw=0.8)
        ax[0].set_ylabel("displacement [mm]")
        ax[1].plot(t, test.force, "k", lw=1.2, label="reference (measured)")
        models = [n for n in data if not n.startswith("_")]
        for name in models:
            ax[1].plot(t, data[name], lw=0.8, label=name)
        ax[1].set_xlim(0, min(t[-1], 5.0))
        ax[1].set_ylabel("force [N]")
        ax[1].set_xlabel("time [s]")
        ax[1].legend(ncol=5, fontsize=8)
        fig.suptitle(f"{axis}: unseen n = 1.5 record (first 5 s)")
        names.append(f"{axis}_force_vs_time.png")
        write_figure(fig, out / names[-1], dpi=110)

        fig, axs = plt.subplots(1, len(models), figsize=(14, 3.6), sharey=True, squeeze=False)
        axs = axs[0]
        for a, name in zip(axs, models, strict=True):
            a.plot(1e3 * test.displacement, test.force, "k", lw=0.5, label="reference")
            a.plot(1e3 * test.displacement, data[name], "r", lw=0.5, label=name)
            a.set_title(name)
            a.set_xlabel("displacement [mm]")
        axs[0].set_ylabel("force [N]")
        axs[0].legend(fontsize=8)
        fig.suptitle(f"{axis}: force-displacement loops, n = 1.5")
        names.append(f"{axis}_loops.png")
        fig.tight_layout()
        write_figure(fig, out / names[-1], dpi=110)

        ts = np.arange(len(step["reference"])) * test.dt
        fig, ax = plt.subplots(figsize=(10, 4))
        ax.plot(ts, step["reference"], "k", lw=1.5, label="reference")
        for name in models:
            ax.plot(ts, step[name]["force"], lw=0.9, label=name)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("force [N]")
        ax.set_title(f"{axis}: 4 mm step at 1 s, held 10 s (seed 000 Fig. 14)")
        ax.legend(ncol=5, fontsize=8)
        names.append(f"{axis}_step.png")
        write_figure(fig, out / names[-1], dpi=110)
    return names


def _pct(x: float) -> str:
    return f"{100 * x:6.1f}"


def format_tables(report: dict[str, Any]) -> str:
    lines = []
    axes = [a for a in AXES if a in report]
    for key, what in (
        ("same_amplitude", "the unseen n = 1 record (the papers' protocol)"),
        (None, "the unseen n = 1.5 record (50 % beyond the training amplitude)"),
    ):
        lines.append(f"Table 2/3 (seed 000): error on {what}, %  [ours | paper T2]")
        lines.append(
            f"{'':10s}" + "".join(f"{a + ' ' + m:>22s}" for a in axes for m in ("RMS", "MAX"))
        )
        for name in ("linear", "nn", "hybrid"):
            cells = []
            for a in axes:
                r = report[a][name][key] if key else report[a][name]
                p_rms, p_max = PAPER["table2"][a][name]
                cells.append(f"{_pct(r['rms_ratio'])} | {p_rms:5.1f}".rjust(22))
                cells.append(f"{_pct(r['max_error_ratio'])} | {p_max:5.1f}".rjust(22))
            lines.append(f"{name:10s}" + "".join(cells))
        lines.append("")
    lines.append("ESR (seed 000 Table 3 reports 0.2-0.5 %), ours on the n = 1.5 record, %:")
    models = list(report[axes[0]]) if axes else []
    for name in models:
        lines.append(
            f"  {name:8s}" + "".join(f"  {a}: {_pct(report[a][name]['esr'])}" for a in axes)
        )
    if "radial" in report:
        lines.append("")
        for key, what in (("same_amplitude", "unseen n = 1"), (None, "unseen n = 1.5")):
            lines.append(f"Table 4 (seed 002, radial), {what}: [ours | paper]")
            lines.append(
                f"{'':10s}{'RMS ratio %':>20s}{'ESR %':>18s}{'max err N':>22s}{'peak err N':>22s}"
            )
            for name in ("nn", "boucwen"):
                r = report["radial"][name][key] if key else report["radial"][name]
                p = PAPER["table4"][name]
                lines.append(
                    f"{name:10s}{_pct(r['rms_ratio'])} | {p[0]:5.1f}".ljust(30)
                    + f"{_pct(r['esr'])} | {p[1]:4.1f}".rjust(18)
                    + f"{r['max_error']:10.1f} | {p[2]:6.1f}".rjust(22)
                    + f"{r['peak_error']:10.1f} | {p[3]:6.1f}".rjust(22)
                )
    lines.append("")
    lines.append("Table 5 (seed 002): identification / verification (6.44 s record) time")
    for name in models:
        for a in axes:
            r = report[a][name]
            paper = PAPER["table5"].get(name)
            ptxt = (
                f"   paper: {paper['identification_s'] / 60:.0f} min / "
                f"{paper['verification_s']:.0f} s"
                if paper and a == axes[0]
                else ""
            )
            lines.append(
                f"  {name:8s} {a:7s} {r['identification_s']:8.1f} s / "
                f"{1e3 * r['verification_s']:8.3f} ms{ptxt}"
            )
    lines.append("")
    lines.append("4 mm step held 10 s (seed 000 §5.2: NN diverges after 7.3 s, hybrid bounded)")
    for a in axes:
        for name, s in report["step"][a].items():
            dep = s["departure_s"]
            lines.append(
                f"  {a:7s} {name:8s} {'bounded' if s['bounded'] else 'DIVERGED':9s}"
                + (f" departs at {dep:.2f} s" if dep is not None else "")
                + f"  peak {s['peak_force_n']:8.1f} N"
            )
    return "\n".join(lines)
