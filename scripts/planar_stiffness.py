"""The planar reference's tangent stiffness at 3 radial preloads x 3 rotations: table and plot.

    python scripts/planar_stiffness.py [--png docs/img/planar_stiffness.png]

Prints the markdown table of docs/planar.md (the elastic tangent dF/dq of the coupled strain
energy at u_a = 2 mm; the Maxwell branches add G_j times it at frequencies above 1/tau_j) and
writes the PNG: the radial force against rotation at each preload (Kadlowec's fall then rise)
and the entries K_rr, K_rt, K_tt against rotation.
"""

from __future__ import annotations

import argparse

import numpy as np

from bushenv.reference.planar import PlanarRubber
from bushenv.reference.planar_elastic import elastic_force, tangent_stiffness

PRELOADS_M = (0.0, 2.0e-3, 4.0e-3)
AXIAL_M = 2.0e-3  # held axial deflection: K_ar is proportional to it
ROTATIONS_RAD = (0.0, 0.05, 0.10)


def table(p: np.ndarray) -> str:
    rows = [
        "| u_r [mm] | theta [rad] | F_a [N] | K_aa [N/mm] | K_ar [N/mm] | K_rr [N/mm] "
        "| K_rt [N/rad] | K_tt [N m/rad] | F_r [N] | M [N m] |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    f = np.empty(3)
    for ur in PRELOADS_M:
        for th in ROTATIONS_RAD:
            k = tangent_stiffness(np.array([AXIAL_M, ur, th]), p)
            elastic_force(AXIAL_M, ur, th, p, f)
            rows.append(
                f"| {ur * 1e3:.0f} | {th:.2f} | {f[0]:.0f} | {k[0, 0] / 1e3:.1f} "
                f"| {k[0, 1] / 1e3:.2f} | {k[1, 1] / 1e3:.1f} | {k[1, 2] + 0.0:.0f} "
                f"| {k[2, 2]:.0f} | {f[1]:.0f} | {f[2]:.1f} |"
            )
    return "\n".join(rows)


def plot(p: np.ndarray, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    th = np.linspace(-0.15, 0.15, 301)
    fig, axes = plt.subplots(1, 4, figsize=(16, 3.8))
    f = np.empty(3)
    for ur in PRELOADS_M:
        label = f"u_r = {ur * 1e3:.0f} mm"
        fr = []
        ks = []
        for t in th:
            elastic_force(AXIAL_M, ur, t, p, f)
            fr.append(f[1])
            ks.append(tangent_stiffness(np.array([AXIAL_M, ur, t]), p))
        ks = np.array(ks)
        axes[0].plot(th, fr, label=label)
        axes[1].plot(th, ks[:, 1, 1] / 1e3, label=label)
        axes[2].plot(th, ks[:, 1, 2], label=label)
        axes[3].plot(th, ks[:, 2, 2], label=label)
    titles = (
        ("radial force F_r [N]", "held radial preload, rotation swept"),
        ("K_rr [N/mm]", "radial tangent stiffness"),
        ("K_rt = K_tr [N/rad]", "radial-rotation coupling"),
        ("K_tt [N m/rad]", "rotational tangent stiffness"),
    )
    for ax, (ylabel, title) in zip(axes, titles, strict=True):
        ax.set_xlabel("rotation theta [rad]")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("planar reference: coupled elastic tangent stiffness (u_a = 2 mm)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--png", default="docs/img/planar_stiffness.png")
    args = ap.parse_args()
    p = PlanarRubber.preset(measurement=False).elastic_params()
    print(table(p))
    plot(p, args.png)
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
