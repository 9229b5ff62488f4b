"""How far a 3-axis Bouc-Wen identification carries: the coupled sets beyond the identified
amplitude, with and without the reference's coupling, and the force under held deflections.

    python studies/2026-11-planar-fit-unseen/planar_extrapolation.py [--seed 0] [--png studies/2026-11-planar-fit-unseen/planar_extrapolation.png]
                                           [--quiet]

Three ``boucwen`` fits, as ``bushenv reproduce --planar`` identifies (random n = 1 and the
three coupled sets at n = 1, 40 s / 20 s each, no clock on the search):

1. on the reference, judged on the coupled sets at 1, 1.25, 1.5 and 1.75x the identified
   amplitude (new noise seeds);
2. the same on the reference without its elastic coupling (every other effect kept): if (1)
   misses where (2) does not, the coupling's shape is what the fit does not carry;
3. on the random records only (``--planar-identification random``): the force after a 1 s ramp
   to a held deflection and after 20 s of hold, against (1)'s and the reference's (no noise).

About 6-8 min on the shared 2-core machine. Prints the tables (docs/planar.md quotes them) and
plots the worst RMS ratio per scale.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from bushenv import reproduce as r3
from bushenv.identify import fit
from bushenv.metrics import max_error_ratio, rms_ratio
from bushenv.models.base import PAPER_DT
from bushenv.motions import coupled_sets
from bushenv.persist import write_figure
from bushenv.progress import Progress
from bushenv.reference.planar import PlanarRubber

SCALES = (1.0, 1.25, 1.5, 1.75)
HOLDS = ((2e-3, 0, 0), (0, 2e-3, 0), (0, 0, 0.05), (2e-3, 2e-3, 0.05))
COORDS = ("axial", "radial", "rotation")
HOLD_S, RAMP_S = 20.0, 1.0


def reference(seed: int, coupled: bool, dt: float) -> PlanarRubber:
    ref = PlanarRubber.preset(seed=seed, dt=dt)
    return ref if coupled else ref.without_effects(["coupling"])


def identified(seed: int, coupled: bool, identification: str, dt: float):
    """The boucwen fit on the reproduce table's identification records of this reference."""
    hist = r3.identification_records(dt, seed, 40.0, identification)
    if not coupled:  # the same motions, measured on the reference without its coupling
        hist = [
            (q, reference(seed + 50 * k, False, dt).simulate(q)) for k, (q, _) in enumerate(hist)
        ]
    return fit(hist, "boucwen", r3._untimed("boucwen"), seed, progress=False, dt=dt).model


def worst_on_sets(model, seed: int, coupled: bool, scale: float, dt: float) -> tuple[float, float]:
    """Worst RMS ratio and MAX over the moving coordinates of the three sets at ``scale``."""
    rms, peak = 0.0, 0.0
    for k, (_, q) in enumerate(coupled_sets(scale, dt, 20.0)):
        f = reference(seed + 7000 + 10 * k + int(scale * 100), coupled, dt).simulate(q)
        p = model.simulate(q)
        for i in range(3):
            if np.any(q[:, i] != 0):
                rms = max(rms, rms_ratio(f[:, i], p[:, i]))
                peak = max(peak, max_error_ratio(f[:, i], p[:, i]))
    return rms, peak


def held(vector: np.ndarray, dt: float) -> np.ndarray:
    """A 1 s half-cosine ramp to ``vector``, then ``HOLD_S`` of hold."""
    ramp, T = int(round(RAMP_S / dt)), int(round((RAMP_S + HOLD_S) / dt))
    q = np.tile(vector, (T, 1))
    q[:ramp] = np.outer(0.5 * (1 - np.cos(np.pi * np.arange(ramp) / ramp)), vector)
    return q


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--png", default="studies/2026-11-planar-fit-unseen/planar_extrapolation.png")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    dt, seed = PAPER_DT, args.seed
    progress = Progress(3.0, quiet=args.quiet, label="extrapolation")
    fits = {}
    for k, (name, coupled, ident) in enumerate(
        (
            ("every effect", True, "programme"),
            ("without the coupling", False, "programme"),
            ("random records only", True, "random"),
        )  # fmt: skip
    ):
        progress.say(f"identifying boucwen on the reference, {name}")
        fits[name] = identified(seed, coupled, ident, dt)
        progress.update(k + 1, f"{name} identified")

    print("worst RMS / MAX % over the moving coordinates of the three coupled sets")
    print(f"{'scale':>6s} {'every effect':>16s} {'without the coupling':>22s}")
    curves = {"every effect": [], "without the coupling": []}
    for scale in SCALES:
        cells = []
        for name, coupled in (("every effect", True), ("without the coupling", False)):
            rms, peak = worst_on_sets(fits[name], seed, coupled, scale, dt)
            curves[name].append((rms, peak))
            cells.append(f"{100 * rms:.1f} / {100 * peak:.1f}")
        print(f"{scale:6g} {cells[0]:>16s} {cells[1]:>22s}")

    print(f"\nforce under a held deflection: error after the {RAMP_S:g} s ramp / after "
          f"{HOLD_S:g} s of hold, % of the reference's (no noise)")  # fmt: skip
    print(f"{'hold (mm, mm, rad)':24s} {'coordinate':10s} {'random records only':>22s} "
          f"{'with the coupled sets':>24s}")  # fmt: skip
    truth = PlanarRubber.preset(measurement=False, dt=dt)
    ramp = int(round(RAMP_S / dt))
    for scale in (1.0, 1.5):
        for hold in HOLDS:
            v = scale * np.array(hold)
            q = held(v, dt)
            fr = truth.simulate(q)
            out = {n: fits[n].simulate(q) for n in ("random records only", "every effect")}
            for i in np.flatnonzero(v):
                cells = [
                    f"{100 * (p[ramp, i] - fr[ramp, i]) / abs(fr[ramp, i]):+.1f} / "
                    f"{100 * (p[-1, i] - fr[-1, i]) / abs(fr[-1, i]):+.1f}"
                    for p in out.values()
                ]
                shown = f"({v[0] * 1e3:g}, {v[1] * 1e3:g}, {v[2]:g})"
                print(f"{shown:24s} {COORDS[i]:10s} {cells[0]:>22s} {cells[1]:>24s}")
    _plot(curves, args.png)
    print(f"\nwrote {args.png}")
    return 0


def _plot(curves: dict, png: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for name, pts in curves.items():
        ax.plot(SCALES, [100 * r for r, _ in pts], "o-", label=f"RMS ratio, {name}")
        ax.plot(SCALES, [100 * m for _, m in pts], "s--", label=f"MAX, {name}")
    ax.axhline(3.0, color="k", lw=0.8, label="target RMS 3 %")
    ax.axhline(6.0, color="grey", lw=0.8, ls=":", label="target MAX 6 %")
    ax.set_xlabel("coupled sets' amplitude / identified amplitude [-]")
    ax.set_ylabel("worst over the moving coordinates [%]")
    ax.set_title("boucwen identified at n = 1, judged on the coupled sets")
    ax.legend(fontsize=7)
    fig.tight_layout()
    write_figure(fig, png, dpi=120)  # atomic, and closed


if __name__ == "__main__":
    sys.exit(main())
