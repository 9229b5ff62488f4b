"""Passivity (matrix test) and fixed-point certificates of the planar models: tables and plot.

    python scripts/planar_passivity.py [--models linear reference nn nn-axis hybrid FILE.npz ...]
                                       [--seed 0] [--png docs/img/planar_passivity.png] [--quiet]

Holds: u_a = 0, radial preloads 0 / 2 / 4 mm x rotations 0 / 0.05 / 0.10 rad (docs/planar.md's
grid). ``linear`` is the fitted 3x3 model and ``nn``, ``nn-axis``, ``hybrid`` are trained
(default budget, seed ``--seed``) on 60 s of independent random motion at n = 1 of the
reference, as ``scripts/planar_benchmark.py`` does; ``linear-preset`` is Table 1's diagonal.
A ``.npz`` argument is a planar model file. Prints the passivity table (least eigenvalue of
D H_I D, J, over the frequencies and holds; where it is negative) and, for the networks, the
fixed-point certificate on a finer grid (5 x 5 x 5 over +-2 mm, +-2 mm, +-0.05 rad).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from bushenv.certify.fixed_points import fixed_points, folds, grid
from bushenv.certify.passivity import passivity
from bushenv.models import MODELS, load_model
from bushenv.models.base import PAPER_DT, velocity_of
from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_linear import fit_linear
from bushenv.models.planar_narx import PlanarNarx
from bushenv.motions import random_independent
from bushenv.progress import Progress

HOLDS = grid([0.0], [0.0, 2e-3, 4e-3], [0.0, 0.05, 0.10])
FREQ_HZ = np.geomspace(0.1, 100.0, 40)
CERT_AXES = (np.linspace(-2e-3, 2e-3, 5), np.linspace(-2e-3, 2e-3, 5), np.linspace(-0.05, 0.05, 5))
TRAINED = ("nn", "nn-axis", "hybrid")


def hold_text(q) -> str:
    return f"({q[0] * 1e3:.0f} mm, {q[1] * 1e3:.0f} mm, {q[2]:.2f} rad)"


def build_models(names: list[str], seed: int, progress: Progress, training: str = "plain") -> dict:
    dt = PAPER_DT
    need_data = any(n in TRAINED or n == "linear" for n in names)
    if need_data:
        q = random_independent(1.0, 60.0, dt, seed)
        f = MODELS["reference"].model_class(3).preset(seed=seed).simulate(q)
    models = {}
    for k, name in enumerate(names):
        if name.endswith(".npz"):
            models[Path(name).name] = load_model(name, coords=3, wanted_by="planar_passivity.py")
        elif name == "linear":
            models["linear (fitted)"] = fit_linear(q, velocity_of(q, dt), f, dt)
        elif name == "linear-preset":
            models[name] = MODELS["linear"].model_class(3).preset()
        elif name == "reference":
            models[name] = MODELS["reference"].model_class(3).preset(measurement=False)
        elif name in TRAINED:
            from bushenv.identify.mimo_train import fit_mimo

            opts = None
            if name == "hybrid" and training == "noisy-feedback":
                from bushenv.identify.mimo_options import (
                    NOISY_FEEDBACK_TRAINING,
                    MimoOptions,
                )

                opts = MimoOptions(**NOISY_FEEDBACK_TRAINING)
            models[name] = fit_mimo(q, f, dt, kind=name, options=opts, seed=seed)
        else:
            raise PlanarModelError(
                f"--models {name!r}: unknown three-axis model; known: linear, linear-preset, "
                f"reference, {', '.join(sorted(TRAINED))}, or a three-axis .npz model file"
            )
        progress.update(k + 1, f"{name} ready")
    return models


def passivity_table(reports: dict) -> str:
    rows = [
        "| model | K(jw) by | least eigenvalue [J] | where | active (hold: band Hz) |",
        "|---|---|---|---|---|",
    ]
    for name, rep in reports.items():
        if rep.eig.size == 0:
            rows.append(f"| {name} | {rep.method} | - | no stable fixed point at any hold | - |")
            continue
        p, fi = np.unravel_index(np.argmin(rep.eig[..., 0]), rep.eig.shape[:2])
        bands = rep.active_bands()
        act = "; ".join(
            f"{hold_text(rep.q[r])}: " + ", ".join(f"{lo:.2g}-{hi:.3g}" for lo, hi in b)
            for r, b in bands[:4]
        )
        if len(bands) > 4:
            act += f"; ... ({len(bands)} rows)"
        extra = (
            f" ({len(rep.no_stable)} holds without a stable fixed point)"
            if len(rep.no_stable)
            else ""
        )
        rows.append(
            f"| {name} | {rep.method} | {rep.min_eig:.4g} | {hold_text(rep.q[p])}, "
            f"{rep.freq_hz[fi]:.3g} Hz | {act or 'none: passive'}{extra} |"
        )
    return "\n".join(rows)


def certificate_table(models: dict) -> str:
    rows = [
        "| model | holds | fixed points per hold | holds with > 1 | holds without a stable one "
        "| fold-surface crossings on grid edges | seconds |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, m in models.items():
        if not isinstance(m, PlanarNarx):
            continue
        t0 = time.perf_counter()
        fp = fixed_points(m, grid(*CERT_AXES))
        crossings = folds(m, fp, CERT_AXES, refine=False)  # counted, not located
        n = fp.count
        un = int(fp.unresolved.sum())
        rows.append(
            f"| {name} | {len(n)} | {n.min()}-{n.max()} | {int((n > 1).sum())} "
            f"| {int((fp.stable_count == 0).sum())} | {len(crossings)} "
            f"| {time.perf_counter() - t0:.1f}{f' ({un} unresolved boxes)' if un else ''} |"
        )
    return "\n".join(rows)


def plot(reports: dict, png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(reports)
    cols = min(n, 3)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.4 * cols, 3.4 * rows), squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    for ax, (name, rep) in zip(axes.flat, reports.items(), strict=False):
        for p in range(len(rep.q)):
            ax.semilogx(rep.freq_hz, rep.eig[p, :, 0], lw=1, label=hold_text(rep.q[p]))
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_title(f"{name} ({rep.method})", fontsize=9)
        ax.set_xlabel("frequency [Hz]")
        ax.set_yscale("symlog", linthresh=1e-3)
    for row in axes:
        row[0].set_ylabel("least eigenvalue of D H_I D [J]\n(work per cycle / pi)")
    axes[0, -1].legend(fontsize=6, title="hold (u_a, u_r, theta)", title_fontsize=6)
    fig.suptitle("Planar passivity: below 0 the model gives energy back", fontsize=10)
    fig.tight_layout()
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=110)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument(
        "--models", nargs="+", default=["linear-preset", "linear", "reference", *TRAINED]
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--training", choices=("plain", "noisy-feedback"), default="plain",
        help="the hybrid's training (bushenv fit --training)",
    )  # fmt: skip
    p.add_argument("--png", type=Path, default=Path("docs/img/planar_passivity.png"))
    p.add_argument("--quiet", action="store_true")
    args = p.parse_args(argv)
    progress = Progress(len(args.models) * 2, quiet=args.quiet, label="planar passivity")
    try:
        models = build_models(args.models, args.seed, progress, args.training)
    except PlanarModelError as exc:  # a bad name or file: one line, exit 2
        print(f"planar_passivity.py: {exc}", file=sys.stderr)
        return 2
    reports = {}
    for k, (name, m) in enumerate(models.items()):
        reports[name] = passivity(m, HOLDS, FREQ_HZ)
        progress.update(len(models) + k + 1, f"{name}: passivity done")
    print(passivity_table(reports))
    print()
    print(certificate_table(models))
    plot(reports, args.png)
    print(f"\nwrote {args.png}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
