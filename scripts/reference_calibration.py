"""The reference bushing measured against the papers, printed as the tables of docs/reference.md.

    python scripts/reference_calibration.py [--behaviour]

The measurement is tests/reference/papers_calibration.py, the one tests/reference/test_rubber.py
holds the reference bushing to.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "reference"))
import papers_calibration as calibration  # noqa: E402
from papers_calibration import (  # noqa: E402
    SINE_AMPS_M,
    SINE_FREQS_HZ,
    TABLE1,
    TABLE2_LINEAR_RMS,
    behaviour_numbers,
    calibration_numbers,
)


def _print_behaviour(axis: str) -> None:
    b = behaviour_numbers(axis)
    print(f"\n{axis}: held 4 mm step, force [N] at t after the step")
    print(" ".join(f"{t:g}s: {v:.0f}" for t, v in b["step_force_n"].items()))
    print(f"{axis}: self-heating")
    for name, h in b["heating"].items():
        print(
            f"  {name}: dT {h['dT_k']:.2f} K, "
            f"force amplitude drop {100 * h['amplitude_drop']:.2f} %"
        )
    print(
        f"{axis}: largest |F| of a 12.5 mm sine: "
        + ", ".join(f"{k} {v / 1e3:.1f} kN" for k, v in b["stroke_force_n"].items())
    )
    for key, unit in (("kdyn_n_per_mm", "dynamic stiffness [N/mm]"), ("loop_energy_j", "J/cycle")):
        print(f"{axis}: {unit}, rows amplitude [mm], columns frequency [Hz]")
        print("| mm | " + " | ".join(f"{f:g} Hz" for f in SINE_FREQS_HZ) + " |")
        print("|---" * (len(SINE_FREQS_HZ) + 1) + "|")
        for amp, row in zip(SINE_AMPS_M, b[key], strict=True):
            fmt = "{:.0f}" if key == "kdyn_n_per_mm" else "{:.3g}"
            print(f"| {amp * 1e3:g} | " + " | ".join(fmt.format(v) for v in row) + " |")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=calibration.__doc__.splitlines()[0])
    p.add_argument("--identification-s", type=float, default=40.0, help="n = 1 record, s")
    p.add_argument("--verification-s", type=float, default=20.0, help="n = 1.5 record, s")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--behaviour", action="store_true", help="also step, heating, sine grid")
    args = p.parse_args(argv)
    print(
        "| axis | k fit [N/mm] (T1) | c fit [N s/mm] (T1) | RMS n=1 | RMS n=1.5 (T2) | MAX n=1.5 |"
    )
    print("|---|---|---|---|---|---|")
    for axis in ("axial", "radial"):
        print(f"measuring {axis} ...", file=sys.stderr, flush=True)
        r = calibration_numbers(
            axis,
            seed=args.seed,
            identification_s=args.identification_s,
            verification_s=args.verification_s,
        )
        k_ref, c_ref = TABLE1[axis]
        print(
            f"| {axis} | {r['k_fit_n_per_m'] / 1e3:.1f} ({k_ref / 1e3:.2f}) "
            f"| {r['c_fit_ns_per_m'] / 1e3:.2f} ({c_ref / 1e3:.1f}) "
            f"| {100 * r['rms_ratio_n1']:.1f} % "
            f"| {100 * r['rms_ratio_n15']:.1f} % ({100 * TABLE2_LINEAR_RMS[axis]:.1f} %) "
            f"| {100 * r['max_ratio_n15']:.1f} % |"
        )
    if args.behaviour:
        for axis in ("axial", "radial"):
            print(f"measuring {axis} behaviour ...", file=sys.stderr, flush=True)
            _print_behaviour(axis)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
