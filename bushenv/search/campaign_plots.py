"""A campaign's pictures: the worst profile of every search and every shrunk failure (over
three coordinates, ``plot_shrunk_coordinates``: motion and force per coordinate).

Each row shows the profile over time, the model's force beside the reference's (the reference
always blue, the model red, the moment of divergence a dashed line named in the legend), and
the force-deflection loop of both. For an ``energy`` failure the loop panel states the net
work each did over the profile (``W = int F dx``): a passive bushing's is positive; a model
that gives back more than it took generates energy, which a bounded-looking force trace hides.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from bushenv.divergence import cumulative_work
from bushenv.models.base import BushingModel
from bushenv.persist import write_figure
from bushenv.search.campaign_cases import Shrunk
from bushenv.search.campaign_resolve import Resolved
from bushenv.search.campaign_search import Searched
from bushenv.search.corpus import load_case

REF_COLOUR, MODEL_COLOUR, FAIL_COLOUR = "tab:blue", "tab:red", "tab:purple"


def _row(axes, t, profile, x, fm, fr, verdict: dict, key: str, profile_label: str) -> None:
    """One row of three panels for one profile judged on model ``key``."""
    ax_p, ax_f, ax_l = axes
    ax_p.plot(t, profile * 1e3, "k", lw=0.8)
    ax_p.set_ylabel(profile_label)
    if fr is not None:
        ax_f.plot(t, fr, color=REF_COLOUR, lw=0.9, label="reference")
        ax_l.plot(x * 1e3, fr, color=REF_COLOUR, lw=0.8, label="reference")
    ax_f.plot(t, fm, color=MODEL_COLOUR, lw=0.8, label=key)
    ax_f.set_ylabel("force [N]")
    ax_l.plot(x * 1e3, fm, color=MODEL_COLOUR, lw=0.7, label=key)
    ax_l.set_xlabel("bushing deflection [mm]")
    ax_l.set_ylabel("force [N]")
    t_fail = verdict.get("first_time_s")
    if verdict.get("diverged") and t_fail is not None:
        what = f"divergence: {verdict.get('first_criterion')} at {t_fail:.2f} s"
        for a in (ax_p, ax_f):
            a.axvline(t_fail, color=FAIL_COLOUR, ls="--", lw=0.9, label=what)
    if verdict.get("first_criterion") == "energy" or "energy" in verdict.get("criteria", []):
        w_m = float(cumulative_work(x[:, None], np.nan_to_num(fm)[:, None])[-1, 0])
        ref = "" if fr is None else "reference "
        if fr is not None:
            w_r = float(cumulative_work(x[:, None], fr[:, None])[-1, 0])
            ref = f"reference {w_r:+.3g} J, "
        ax_l.set_title(f"net work over the profile: {ref}{key} {w_m:+.3g} J", fontsize=8)
    ax_f.legend(fontsize=7, loc="upper right")
    ax_l.legend(fontsize=7, loc="upper left")


def _figure(plt, n_rows: int):
    return plt.subplots(n_rows, 3, figsize=(15, 2.8 * n_rows), squeeze=False)


def plot_worst(
    resolved: Resolved, searched: Searched, threads: int, plt: Any, plot_dir: Path
) -> list[str]:
    """``plots/worst-<model>.png``: each search's worst profile on that model."""
    dt, label = resolved.dt, resolved.target.profile_label
    names = []
    for key in resolved.models:
        rows = searched.worst(key)
        if not rows:
            continue
        fig, axes = _figure(plt, len(rows))
        with resolved.evaluator(key, threads) as ev:
            batch = ev.evaluate([p for _, p, _ in rows])
        for r, (name, p, m) in enumerate(rows):
            n, v = p.size, m["verdict"]
            t = np.arange(n) * dt
            fr = None if batch.f_ref is None else batch.f_ref[:n, r]
            args = (batch.x[:n, r], batch.f_model[:n, r], fr)
            _row(axes[r], t, p, *args, v, key, label)
            state = "DIVERGES" if v["diverged"] else "bounded"
            axes[r, 0].set_title(
                f"{key} / {name}: worst {m['family']}, robustness {v['robustness']:.3g}, {state}",
                fontsize=9,
            )
        for a in axes[-1, :2]:
            a.set_xlabel("time [s]")
        fig.tight_layout()
        names.append(f"worst-{key}.png")
        write_figure(fig, plot_dir / names[-1], dpi=90)
    return names


def plot_shrunk(
    resolved: Resolved, shrunk: Shrunk, out: Path, threads: int, plt: Any, plot_dir: Path
) -> list[str]:
    """``plots/shrunk-<i>.png``: each shrunk failure on every model of the campaign."""
    dt, label = resolved.dt, resolved.target.profile_label
    names = []
    for i, entry in enumerate(shrunk.entries):
        case = load_case(out / entry["case_file"])
        p = case.profile
        t = np.arange(p.size) * dt
        fig, axes = _figure(plt, len(resolved.models))
        for r, key in enumerate(resolved.models):
            with resolved.evaluator(key, threads) as ev:
                b = ev.evaluate([p])
            row = b.verdict.row(0)
            fr = None if b.f_ref is None else b.f_ref[:, 0]
            _row(axes[r], t, p, b.x[:, 0], b.f_model[:, 0], fr, row, key, label)
            state = "DIVERGES" if row["diverged"] else "bounded"
            axes[r, 0].set_title(f"shrunk failure {case.name}: {key} {state}", fontsize=9)
        for a in axes[-1, :2]:
            a.set_xlabel("time [s]")
        fig.tight_layout()
        names.append(f"shrunk-{i}.png")
        write_figure(fig, plot_dir / names[-1], dpi=90)
    return names


def plot_campaign(
    resolved: Resolved, searched: Searched, shrunk: Shrunk, out: Path, threads: int = 1
) -> list[str]:
    """Every plot of the campaign in ``out/plots``; returns their file names."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plot_dir = out / "plots"
    plot_dir.mkdir(parents=True, exist_ok=True)
    if resolved.target.coords:  # a row per coordinate: the shrunk failures on the target
        model = resolved.models[resolved.target_key].model
        shown = [
            (f"{e['family']}, failed in {e.get('axis')}", load_case(out / e["case_file"]).profile)
            for e in shrunk.entries
        ]
        paths = plot_shrunk_coordinates(model, resolved.judge.reference, shown, plot_dir)
        return [q.name for q in paths]
    worst = plot_worst(resolved, searched, threads, plt, plot_dir)
    return worst + plot_shrunk(resolved, shrunk, out, threads, plt, plot_dir)


# per coordinate: motion label, its factor from SI, force label
COORDINATE_ROWS = (
    ("axial [mm]", 1e3, "axial force [N]"),
    ("radial [mm]", 1e3, "radial force [N]"),
    ("rotation [mrad]", 1e3, "moment [N m]"),
)


def plot_shrunk_coordinates(
    model: BushingModel,
    reference: BushingModel,
    shrunk: list[tuple[str, np.ndarray]],
    plot_dir: Path,
) -> list[Path]:
    """One PNG per shrunk failure over three coordinates (``(title, profile (T, 3))``): a row
    per coordinate (axial, radial, rotation), the motion on the left, the model's and the
    reference's force on the right."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    for i, (title, q) in enumerate(shrunk):
        t = np.arange(q.shape[0]) * model.dt
        with np.errstate(all="ignore"):
            f_model = model.copy().simulate(q)
            f_ref = reference.copy().simulate(q)
        fig, axes = plt.subplots(3, 2, figsize=(12, 7.5), sharex=True, squeeze=False)
        for row, (motion, scale, force) in enumerate(COORDINATE_ROWS):
            ax_q, ax_f = axes[row]
            ax_q.plot(t, q[:, row] * scale, "k", lw=0.9)
            ax_q.set_ylabel(motion)
            ax_f.plot(t, f_ref[:, row], REF_COLOUR, lw=1.0, label="reference")
            ax_f.plot(t, f_model[:, row], MODEL_COLOUR, lw=1.0, label=model.name)
            ax_f.set_ylabel(force)
            if row == 0:
                ax_q.set_title(f"shrunk failure {i + 1}: {title} -- motion")
                ax_f.set_title("force and moment")
                ax_f.legend(loc="best", fontsize=8)
        for ax in axes[-1]:
            ax.set_xlabel("time [s]")
        fig.tight_layout()
        paths.append(write_figure(fig, plot_dir / f"shrunk_{i + 1}.png"))
    return paths
