"""Measure the reference bushing against the papers: linear fit at n = 1, its error at n = 1.5.

The papers identified a linear bushing (seed 000 Table 1) from an RPC random record at index
n = 1 (peak |x| = 2 mm) and judged it on an unseen record at n = 1.5 (Table 2: RMS ratio 9.8 %
axial, 11.9 % radial). ``calibration_numbers(axis)`` repeats that on the reference bushing:

1. drive it with a band-limited random record (``random_drive``; 0.5-20 Hz, 204.8 Hz, peak
   n * 2 mm) at n = 1 and fit F ~ k x + c v by least squares (``linear_fit``);
2. run that linear model on a different record at n = 1.5 and compute ``rms_ratio``.

Run ``python -m bushenv.reference.calibration`` to print the numbers for both axes (they are
recorded in ``rubber.py`` and docs/reference.md).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from bushenv.metrics import max_error_ratio, rms, rms_ratio
from bushenv.models.base import PAPER_DT, velocity_of
from bushenv.reference.rubber import RubberBushing

TABLE1 = {"axial": (379.68e3, 4.4e3), "radial": (1518.73e3, 15.0e3)}  # seed 000, SI
TABLE2_LINEAR_RMS = {"axial": 0.098, "radial": 0.119}  # seed 000 Table 2
PEAK_PER_INDEX_M = 2.0e-3  # seed 002 §3: peak amplitude 2 mm at n = 1


def random_drive(
    n_index: float,
    duration_s: float,
    dt: float = PAPER_DT,
    seed: int = 0,
    band_hz: tuple[float, float] = (0.5, 20.0),
) -> np.ndarray:
    """Band-limited Gaussian displacement (T,), m: flat spectrum in ``band_hz``, peak n * 2 mm.

    Stands in for an RPC drive file: white noise, zeroed outside the band in the frequency
    domain, faded in and out over 0.25 s, scaled so max |x| = n_index * 2 mm.
    """
    if n_index <= 0 or duration_s <= 0:
        raise ValueError(f"need n_index > 0 and duration_s > 0, got {n_index}, {duration_s}")
    n = int(round(duration_s / dt))
    rng = np.random.default_rng(seed)
    spec = np.fft.rfft(rng.standard_normal(n))
    f = np.fft.rfftfreq(n, dt)
    spec[(f < band_hz[0]) | (f > band_hz[1])] = 0.0
    x = np.fft.irfft(spec, n)
    ramp = min(n // 4, int(round(0.25 / dt)))
    if ramp > 0:
        w = 0.5 - 0.5 * np.cos(np.pi * np.arange(ramp) / ramp)
        x[:ramp] *= w
        x[n - ramp :] *= w[::-1]
    return x * (n_index * PEAK_PER_INDEX_M / np.max(np.abs(x)))


def linear_fit(x: np.ndarray, v: np.ndarray, f: np.ndarray) -> tuple[float, float]:
    """Least-squares k [N/m], c [N s/m] of F ~ k x + c v over (T,) arrays."""
    a = np.column_stack([x, v])
    (k, c), *_ = np.linalg.lstsq(a, f, rcond=None)
    return float(k), float(c)


def calibration_numbers(
    axis: str,
    model: RubberBushing | None = None,
    duration_s: float = 30.0,
    seed: int = 0,
    dt: float = PAPER_DT,
) -> dict[str, float]:
    """Linear fit on an n = 1 record, judged on an unseen n = 1.5 record (seed 000 §4).

    Returns k_fit [N/m], c_fit [N s/m], their ratios to Table 1, the RMS ratio and MAX ratio of
    the fitted linear model at n = 1.5 (and at n = 1, in sample), force RMS at n = 1 and the
    largest |F| at n = 1.5.
    """
    m = RubberBushing.preset(axis, dt=dt) if model is None else model
    x1 = random_drive(1.0, duration_s, dt, seed=seed)
    x15 = random_drive(1.5, duration_s, dt, seed=seed + 1)
    v1, v15 = velocity_of(x1, dt), velocity_of(x15, dt)
    f1 = m.simulate(x1, v1)
    f15 = m.simulate(x15, v15)
    k, c = linear_fit(x1, v1, f1)
    k_ref, c_ref = TABLE1[axis]
    return {
        "k_fit_n_per_m": k,
        "c_fit_ns_per_m": c,
        "k_ratio_to_table1": k / k_ref,
        "c_ratio_to_table1": c / c_ref,
        "rms_ratio_n1": rms_ratio(f1, k * x1 + c * v1),
        "rms_ratio_n15": rms_ratio(f15, k * x15 + c * v15),
        "max_ratio_n15": max_error_ratio(f15, k * x15 + c * v15),
        "force_rms_n1_n": rms(f1),
        "force_peak_n15_n": float(np.max(np.abs(f15))),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=30.0, help="record length, s")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    print(
        "| axis | k fit [N/mm] (T1) | c fit [N s/mm] (T1) | RMS n=1 | RMS n=1.5 (T2) | MAX n=1.5 |"
    )
    print("|---|---|---|---|---|---|")
    for axis in ("axial", "radial"):
        print(f"measuring {axis} ...", file=sys.stderr, flush=True)
        r = calibration_numbers(axis, duration_s=args.duration, seed=args.seed)
        k_ref, c_ref = TABLE1[axis]
        print(
            f"| {axis} | {r['k_fit_n_per_m'] / 1e3:.1f} ({k_ref / 1e3:.2f}) "
            f"| {r['c_fit_ns_per_m'] / 1e3:.2f} ({c_ref / 1e3:.1f}) "
            f"| {100 * r['rms_ratio_n1']:.1f} % "
            f"| {100 * r['rms_ratio_n15']:.1f} % ({100 * TABLE2_LINEAR_RMS[axis]:.1f} %) "
            f"| {100 * r['max_ratio_n15']:.1f} % |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
