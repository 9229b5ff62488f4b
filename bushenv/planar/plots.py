"""The figures of a 3-axis fit's card: per record, the three forces against time and the three
loops (each force over its own deflection), measured beside the model's free run from rest.

As the one-axis card's (``bushenv.identify.plots``): a held-out record's pair of figures, or the
first training record's when none is held out, named ``<model>.<i>-<record>.time.png`` and
``.loops.png`` beside the model file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bushenv.identify.plots import LOOP_WINDOW_S, safe_name
from bushenv.models.planar_base import COORDS
from bushenv.persist import save_figure

SCALE = (1e3, 1e3, 1e3)  # m -> mm, m -> mm, rad -> mrad
DEFLECTION = ("axial [mm]", "radial [mm]", "rotation [mrad]")
FORCE = ("axial force [N]", "radial force [N]", "moment [N m]")
RESIDUAL = ("residual [N]", "residual [N]", "residual [N m]")


def record_figures3(record, f_model: np.ndarray, model_name: str, prefix: Path, role: str):
    """Two PNGs for one ``PlanarRecord``: ``<prefix>.time.png`` (forces and their residual
    against time, per coordinate) and ``<prefix>.loops.png`` (each force over its deflection,
    the whole record and a window around the largest deflection vector)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = record.time - record.time[0]
    q = record.q * np.array(SCALE)
    label = Path(record.source).stem if record.source else "record"
    paths = [prefix.with_name(prefix.name + ".time.png"),
             prefix.with_name(prefix.name + ".loops.png")]  # fmt: skip

    fig, ax = plt.subplots(3, 2, figsize=(13, 8), sharex=True, width_ratios=(3, 1))
    for i in range(3):
        ax[i, 0].plot(t, record.f[:, i], color="k", lw=0.8, label="measured")
        ax[i, 0].plot(t, f_model[:, i], color="tab:red", lw=0.7,
                      label=f"model ({model_name}, free run)")  # fmt: skip
        ax[i, 0].set_ylabel(FORCE[i])
        ax[i, 1].plot(t, f_model[:, i] - record.f[:, i], color="tab:blue", lw=0.6,
                      label="model - measured")  # fmt: skip
        ax[i, 1].axhline(0.0, color="0.5", lw=0.5)
        ax[i, 1].set_ylabel(RESIDUAL[i])
    ax[0, 0].legend(loc="upper right", fontsize=8)
    ax[0, 1].legend(loc="upper right", fontsize=8)
    for a in ax[2]:
        a.set_xlabel("time [s]")
    ax[2, 1].locator_params(axis="x", nbins=4)  # a narrow panel: fewer ticks, readable
    fig.suptitle(f"{label} ({role}): forces vs time, per coordinate")
    fig.tight_layout()
    save_figure(fig, paths[0])
    plt.close(fig)

    size = np.sqrt(np.sum((record.q / np.maximum(np.abs(record.q).max(axis=0), 1e-300)) ** 2, 1))
    k = int(np.argmax(size))
    half = int(round(0.5 * LOOP_WINDOW_S / record.dt))
    sl = slice(max(0, k - half), min(len(t), k + half))
    fig, ax = plt.subplots(2, 3, figsize=(13, 7.5))
    for i in range(3):
        for row, part in ((0, slice(None)), (1, sl)):
            lw = 0.4 if row == 0 else 0.9
            ax[row, i].plot(q[part, i], record.f[part, i], color="k", lw=lw, label="measured")
            ax[row, i].plot(q[part, i], f_model[part, i], color="tab:red", lw=lw, alpha=0.8,
                            label=f"model ({model_name})")  # fmt: skip
            ax[row, i].set_xlabel(DEFLECTION[i])
            ax[row, i].set_ylabel(FORCE[i])
        ax[0, i].set_title(f"{COORDS[i]}: whole record")
        ax[1, i].set_title(f"{COORDS[i]}: {LOOP_WINDOW_S:g} s around t = {t[k]:.1f} s")
    ax[0, 0].legend(loc="upper left", fontsize=8)
    fig.suptitle(f"{label} ({role}): loops, each force over its own deflection")
    fig.tight_layout()
    save_figure(fig, paths[1])
    plt.close(fig)
    return paths


def fit_figures3(model, model_path: Path, train: list, held_out: list) -> list[str]:
    """The figure pair of each held-out record (or of the first training record); names."""
    shown = [(r, "held-out") for r in held_out] or [(train[0], "seen in training")]
    stem = model_path.name[: -len(model_path.suffix)] if model_path.suffix else model_path.name
    names = []
    for i, (rec, role) in enumerate(shown):
        name = safe_name(Path(rec.source).stem if rec.source else "record")
        prefix = model_path.with_name(f"{stem}.{i + 1}-{name}")
        f_model = model.simulate(rec.q)
        names += [p.name for p in record_figures3(rec, f_model, model.name, prefix, role)]
    return names
