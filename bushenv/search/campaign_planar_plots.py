"""Plots of the planar attack: each shrunk failure, motion and force per coordinate, the
model under attack beside the reference it is judged against."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bushenv.persist import write_figure

# per coordinate: motion label, its factor from SI, force label
ROWS = (
    ("axial [mm]", 1e3, "axial force [N]"),
    ("radial [mm]", 1e3, "radial force [N]"),
    ("rotation [mrad]", 1e3, "moment [N m]"),
)


def plot_shrunk(
    model, reference, shrunk: list[tuple[str, np.ndarray]], plot_dir: Path
) -> list[Path]:
    """One PNG per shrunk failure (``(title, profile (T, 3))``): three rows (axial, radial,
    rotation), the motion on the left, the model's and the reference's force on the right."""
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
        for row, (motion, scale, force) in enumerate(ROWS):
            ax_q, ax_f = axes[row]
            ax_q.plot(t, q[:, row] * scale, "k", lw=0.9)
            ax_q.set_ylabel(motion)
            ax_f.plot(t, f_ref[:, row], "tab:blue", lw=1.0, label="reference")
            ax_f.plot(t, f_model[:, row], "tab:red", lw=1.0, label=model.name)
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
