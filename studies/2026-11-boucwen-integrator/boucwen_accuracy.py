"""Bouc-Wen kernel accuracy and cost: each parameter set on each input, against a converged run.

For every pair: the worst force error of the production kernel (ROS34PW2 with error control)
relative to the peak and to F_REF (the scale the tolerance refers to), against fixed-step RK4
with 512 sub-steps per sample, and the trial steps per sample it took (both blocks, rejected
ones included). The cases: ``tests/models/boucwen_converged.py``.

    python studies/2026-11-boucwen-integrator/boucwen_accuracy.py                 # default rtol
    python studies/2026-11-boucwen-integrator/boucwen_accuracy.py --rtol 1e-7 --md table.md
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bushenv.models.boucwen.kernels import BW_RTOL

# The cases and the converged run the tests measure the kernel with.
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "models"))
from boucwen_converged import INPUTS, error_against_converged, parameter_sets  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--rtol", type=float, default=BW_RTOL, help=f"default {BW_RTOL:g}")
    ap.add_argument("--md", type=Path, help="also write the table as markdown here")
    args = ap.parse_args(argv)
    sets = parameter_sets()
    rows = []
    for i, (sname, make_p) in enumerate(sets.items(), 1):
        p = make_p()
        print(f"[{i}/{len(sets)}] {sname}", flush=True)
        for iname, make_x in INPUTS.items():
            e_peak, e_ref, steps = error_against_converged(p, make_x(), args.rtol)
            rows.append((sname, iname, e_peak, e_ref, steps))
            print(
                f"    {iname:28s} error {e_peak:8.1e} of peak, {e_ref:8.1e} of F_REF, "
                f"{steps:5.1f} trial steps/sample",
                flush=True,
            )
    print(f"worst error: {max(r[2] for r in rows):.1e} of the peak (rtol {args.rtol:g})")
    if args.md:
        lines = [
            "| parameter set | input | max error / peak | max error / F_REF | trial steps "
            "per sample |",
            "|---|---|---:|---:|---:|",
        ]
        lines += [f"| {s} | {n} | {a:.1e} | {b:.1e} | {c:.1f} |" for s, n, a, b, c in rows]
        args.md.write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
