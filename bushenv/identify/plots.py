"""Figures of a fitted model on a record: force vs time with its residual, and force-deflection
loops, measured beside model (matplotlib Agg; mm and N at the edges)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.persist import save_figure

LOOP_WINDOW_S = 2.0  # the zoomed loop panel: this long around the largest deflection


def _save(fig: Any, path: Path) -> None:
    save_figure(fig, path)


def safe_name(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or "record"


def record_figures(
    record: Any, f_model: np.ndarray, model_name: str, prefix: Path, role: str
) -> list[Path]:
    """Two PNGs for one record, named ``<prefix>.time.png`` and ``<prefix>.loops.png``.

    ``f_model`` (T,) N is the model's free run from rest on ``record``; ``role`` labels the
    record in titles ("held-out", or "training, seen in training").
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.asarray(record.time) - record.time[0]
    x_mm = 1e3 * np.asarray(record.displacement)
    f = np.asarray(record.force)
    label = getattr(record, "name", "") or "record"
    paths = [
        prefix.with_name(prefix.name + ".time.png"),
        prefix.with_name(prefix.name + ".loops.png"),
    ]

    fig, ax = plt.subplots(3, 1, figsize=(11, 7.5), sharex=True, height_ratios=(1, 2, 1))
    ax[0].plot(t, x_mm, color="0.3", lw=0.7)
    ax[0].set_ylabel("displacement [mm]")
    ax[1].plot(t, f, color="k", lw=1.0, label="measured")
    ax[1].plot(t, f_model, color="tab:red", lw=0.8, label=f"model ({model_name}, free run)")
    ax[1].set_ylabel("force [N]")
    ax[1].legend(loc="upper right", fontsize=8)
    ax[2].plot(t, f_model - f, color="tab:blue", lw=0.7, label="model - measured")
    ax[2].axhline(0.0, color="0.5", lw=0.5)
    ax[2].set_ylabel("residual [N]")
    ax[2].set_xlabel("time [s]")
    ax[2].legend(loc="upper right", fontsize=8)
    fig.suptitle(f"{label} ({role}): force vs time")
    fig.tight_layout()
    _save(fig, paths[0])
    plt.close(fig)

    fig, axs = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    axs[0].plot(x_mm, f, color="k", lw=0.4, label="measured")
    axs[0].plot(x_mm, f_model, color="tab:red", lw=0.4, alpha=0.8, label=f"model ({model_name})")
    axs[0].set_title("whole record")
    i = int(np.argmax(np.abs(x_mm)))
    half = int(round(0.5 * LOOP_WINDOW_S / record.dt))
    sl = slice(max(0, i - half), min(len(t), i + half))
    axs[1].plot(x_mm[sl], f[sl], color="k", lw=0.9, label="measured")
    axs[1].plot(x_mm[sl], f_model[sl], color="tab:red", lw=0.9, label=f"model ({model_name})")
    axs[1].set_title(f"{LOOP_WINDOW_S:g} s around the largest deflection (t = {t[i]:.1f} s)")
    for a in axs:
        a.set_xlabel("displacement [mm]")
        a.legend(loc="upper left", fontsize=8)
    axs[0].set_ylabel("force [N]")
    fig.suptitle(f"{label} ({role}): force-deflection loops")
    fig.tight_layout()
    _save(fig, paths[1])
    plt.close(fig)
    return paths
