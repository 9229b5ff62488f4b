"""Bouc-Wen kernel accuracy and cost: each parameter set on each input, against a converged run.

For every pair it prints the worst force error relative to the peak (and to F_REF, the scale
the tolerance refers to) of the production kernel (``boucwen_kernel``, ROS34PW2 with error
control) against ``boucwen_fixed_step`` with 512 RK4 sub-steps per sample, and the trial steps
per sample it took (both blocks, rejected ones included). Writes the table to stdout and, with
--md, as markdown.

    python scripts/boucwen_accuracy.py                 # default rtol
    python scripts/boucwen_accuracy.py --rtol 1e-7
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from bushenv import excitation as ex
from bushenv.models import PAPER_DT, get_model
from bushenv.models.boucwen import BoucWenBushing
from bushenv.models.boucwen_kernels import (
    BW_MAX_SUBSTEPS,
    BW_N_STATE,
    BW_ORDER,
    BW_RTOL,
    V_REF_M_PER_S,
    X_REF_M,
    boucwen_fixed_step,
    boucwen_kernel,
)

DT = PAPER_DT


def soft_block1_sharp_block2() -> np.ndarray:
    """Table 3 with block 1 slow and non-hysteretic (the case the previous kernel got wrong)."""
    p = BoucWenBushing.preset().vector()
    p[BW_ORDER.index("c1")] *= 100.0
    p[BW_ORDER.index("a1")] = 0.0
    return p


PARAMETER_SETS = {
    "shipped axial": lambda: get_model("boucwen", axis="axial").vector(),
    "shipped radial": lambda: get_model("boucwen", axis="radial").vector(),
    "Table 3 (seed 002)": lambda: BoucWenBushing.preset().vector(),
    "soft block 1, sharp block 2": soft_block1_sharp_block2,
}
INPUTS = {
    "random n = 1 (20 s)": lambda: ex.random_rpc(1.0, 20.0, DT, seed=0),
    "random n = 1.5 (3 s)": lambda: ex.random_rpc(1.5, 3.0, DT, seed=1),
    "4 mm step held 1.5 s": lambda: ex.step_hold(4e-3, 1.5, DT),
    "80 Hz at 1.2 m/s (1 s)": lambda: ex.sine(80.0, 1.2 / (2 * np.pi * 80.0), 1.0, DT),
    "out-of-band random (2 s)": lambda: ex.random_ood(2.0, DT, seed=0),
    "1 mm zig-zag (600 samples)": lambda: np.tile([0.0, 1e-3, 0.0, -1e-3], 150),
}


def f_ref(p: np.ndarray) -> float:
    k = abs(p[1]) + abs(p[3]) + abs(p[5])
    c = abs(p[0]) + abs(p[2]) + abs(p[4])
    return max(k * X_REF_M, c * V_REF_M_PER_S)


def measure(p: np.ndarray, x: np.ndarray, rtol: float) -> tuple[float, float, float]:
    """(max error / peak, max error / F_REF, trial steps per sample)."""
    X = np.ascontiguousarray(x[:, None])
    V = np.gradient(X, DT, axis=0)
    P = np.ascontiguousarray(p[:, None])
    ref = np.empty_like(X)
    boucwen_fixed_step(X, V, P, DT, 512, ref)
    # one sample per call, so that every sample's trial steps are counted (state row 6)
    state = np.zeros((BW_N_STATE, 1))
    out = np.empty_like(X)
    steps = 0.0
    for t in range(X.shape[0]):
        boucwen_kernel(
            X[t : t + 1], V[t : t + 1], state, P, DT, BW_MAX_SUBSTEPS, rtol, out[t : t + 1]
        )
        steps += state[6, 0]
    err = float(np.max(np.abs(out - ref)))
    return err / float(np.max(np.abs(ref))), err / f_ref(p), steps / X.shape[0]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--rtol", type=float, default=BW_RTOL, help=f"default {BW_RTOL:g}")
    ap.add_argument("--md", type=Path, help="also write the table as markdown here")
    args = ap.parse_args(argv)
    rows = []
    for i, (sname, make_p) in enumerate(PARAMETER_SETS.items(), 1):
        p = make_p()
        print(f"[{i}/{len(PARAMETER_SETS)}] {sname}", flush=True)
        for iname, make_x in INPUTS.items():
            e_peak, e_ref, steps = measure(p, make_x(), args.rtol)
            rows.append((sname, iname, e_peak, e_ref, steps))
            print(
                f"    {iname:28s} error {e_peak:8.1e} of peak, {e_ref:8.1e} of F_REF, "
                f"{steps:5.1f} trial steps/sample",
                flush=True,
            )
    worst = max(r[2] for r in rows)
    print(f"worst error: {worst:.1e} of the peak (rtol {args.rtol:g})")
    if args.md:
        lines = [
            "| parameter set | input | max error / peak | max error / F_REF | trial steps per "
            "sample |",
            "|---|---|---:|---:|---:|",
        ]
        lines += [f"| {s} | {n} | {a:.1e} | {b:.1e} | {c:.1f} |" for s, n, a, b, c in rows]
        args.md.write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
