"""Figures of a fitted model on a record of any number of coordinates C: per coordinate, the
force against time beside its residual, and the force over its own deflection (the whole record
and a window around the largest deflection), measured beside the model's free run from rest
(matplotlib Agg; mm, mrad, N and N m at the edges).

A card's figures (``bushenv.identify.card._figures``): a held-out record's pair, or the first
training record's when none is held out, named ``<model>.<i>-<record>.time.png`` and
``.loops.png`` beside the model file.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.persist import save_figure

LOOP_WINDOW_S = 2.0  # the zoomed loop panel: this long around the largest deflection
# per SI unit of a coordinate: the factor and unit shown, and its force's name and unit
SHOWN = {"m": (1e3, "mm", "force", "N"), "rad": (1e3, "mrad", "moment", "N m")}


def safe_name(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_") or "record"


def _labels(record: Any) -> list[tuple[float, str, str, str]]:
    """Per coordinate: (scale, deflection label, force label, residual label)."""
    out = []
    for c in record.coords:
        scale, unit, force, force_unit = SHOWN["rad" if c == "rotation" else "m"]
        name = "displacement" if record.n_coords == 1 else c
        what = force if record.n_coords == 1 or force == "moment" else f"{c} force"
        out.append((scale, f"{name} [{unit}]", f"{what} [{force_unit}]",
                    f"residual [{force_unit}]"))  # fmt: skip
    return out


def record_figures(
    record: Any, f_model: np.ndarray, model_name: str, prefix: Path, role: str
) -> list[Path]:
    """Two PNGs for one record, named ``<prefix>.time.png`` and ``<prefix>.loops.png``.

    ``f_model`` ((T,) or (T, C)) is the model's free run from rest on ``record``; ``role``
    labels the record in titles ("held-out", or "seen in training").
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.asarray(record.time) - record.time[0]
    q, f = record.q, record.f
    fm = np.asarray(f_model).reshape(f.shape)
    c = record.n_coords
    labels = _labels(record)
    label = getattr(record, "name", "") or "record"
    paths = [prefix.with_name(prefix.name + ".time.png"),
             prefix.with_name(prefix.name + ".loops.png")]  # fmt: skip

    fig, ax = plt.subplots(c, 2, figsize=(13, 2.6 + 2.2 * c), sharex=True, width_ratios=(3, 1),
                           squeeze=False)  # fmt: skip
    for i in range(c):
        ax[i, 0].plot(t, f[:, i], color="k", lw=0.8, label="measured")
        ax[i, 0].plot(t, fm[:, i], color="tab:red", lw=0.7,
                      label=f"model ({model_name}, free run)")  # fmt: skip
        ax[i, 0].set_ylabel(labels[i][2])
        ax[i, 1].plot(t, fm[:, i] - f[:, i], color="tab:blue", lw=0.6, label="model - measured")
        ax[i, 1].axhline(0.0, color="0.5", lw=0.5)
        ax[i, 1].set_ylabel(labels[i][3])
    ax[0, 0].legend(loc="upper right", fontsize=8)
    ax[0, 1].legend(loc="upper right", fontsize=8)
    for a in ax[-1]:
        a.set_xlabel("time [s]")
    ax[-1, 1].locator_params(axis="x", nbins=4)  # a narrow panel: fewer ticks, readable
    fig.suptitle(f"{label} ({role}): force vs time, per coordinate")
    fig.tight_layout()
    save_figure(fig, paths[0])
    plt.close(fig)

    size = np.sqrt(np.sum((q / np.maximum(np.abs(q).max(axis=0), 1e-300)) ** 2, axis=1))
    k = int(np.argmax(size))
    half = int(round(0.5 * LOOP_WINDOW_S / record.dt))
    sl = slice(max(0, k - half), min(len(t), k + half))
    fig, ax = plt.subplots(2, c, figsize=(4.3 * c + 2, 7.5), squeeze=False)
    for i in range(c):
        x = q[:, i] * labels[i][0]
        for row, part in ((0, slice(None)), (1, sl)):
            lw = 0.4 if row == 0 else 0.9
            ax[row, i].plot(x[part], f[part, i], color="k", lw=lw, label="measured")
            ax[row, i].plot(x[part], fm[part, i], color="tab:red", lw=lw, alpha=0.8,
                            label=f"model ({model_name})")  # fmt: skip
            ax[row, i].set_xlabel(labels[i][1])
            ax[row, i].set_ylabel(labels[i][2])
        ax[0, i].set_title(f"{record.coords[i]}: whole record")
        ax[1, i].set_title(f"{record.coords[i]}: {LOOP_WINDOW_S:g} s around t = {t[k]:.1f} s")
    ax[0, 0].legend(loc="upper left", fontsize=8)
    fig.suptitle(f"{label} ({role}): loops, each force over its own deflection")
    fig.tight_layout()
    save_figure(fig, paths[1])
    plt.close(fig)
    return paths
