"""Measure the reference bushing against the papers: linear fit at n = 1, its error at n = 1.5.

The papers identified a linear bushing (seed 000 Table 1) from an RPC random record at index
n = 1 (peak |x| = 2 mm) and judged it on an unseen record at n = 1.5 (Table 2: RMS ratio 9.8 %
axial, 11.9 % radial). ``calibration_numbers(axis)`` repeats that on the reference bushing:

1. drive it with the RPC-like random record of ``bushenv.excitation.random_rpc`` (durability
   spectrum, 0.5-20 Hz, 204.8 Hz, peak n * 2 mm) at n = 1, 40 s, and fit F ~ k x + c v by least
   squares (``linear_fit``), as ``bushenv.programmes.papers_programme`` records it;
2. run that linear model on the unseen n = 1.5 record (20 s, next seed); ``rms_ratio``.

tests/reference/test_rubber.py holds the reference to these numbers; ``python
scripts/reference_calibration.py`` prints them for both axes (they are recorded in
``bushenv/reference/rubber.py`` and docs/reference.md).
"""

from __future__ import annotations

import numpy as np

from bushenv.excitation import random_rpc, sine, step_hold
from bushenv.metrics import max_error_ratio, rms, rms_ratio
from bushenv.models.base import PAPER_DT, velocity_of
from bushenv.reference.rubber import RubberBushing

TABLE1 = {"axial": (379.68e3, 4.4e3), "radial": (1518.73e3, 15.0e3)}  # seed 000, SI
TABLE2_LINEAR_RMS = {"axial": 0.098, "radial": 0.119}  # seed 000 Table 2


def linear_fit(x: np.ndarray, v: np.ndarray, f: np.ndarray) -> tuple[float, float]:
    """Least-squares k [N/m], c [N s/m] of F ~ k x + c v over (T,) arrays."""
    a = np.column_stack([x, v])
    (k, c), *_ = np.linalg.lstsq(a, f, rcond=None)
    return float(k), float(c)


def calibration_numbers(
    axis: str,
    model: RubberBushing | None = None,
    seed: int = 0,
    identification_s: float = 40.0,
    verification_s: float = 20.0,
    dt: float = PAPER_DT,
) -> dict[str, float]:
    """Linear fit on an n = 1 record, judged on an unseen n = 1.5 record (seed 000 §4).

    Returns k_fit [N/m], c_fit [N s/m], their ratios to Table 1, the RMS ratio and MAX ratio of
    the fitted linear model at n = 1.5 (and at n = 1, in sample), force RMS at n = 1 and the
    largest |F| at n = 1.5.
    """
    m = RubberBushing.preset(axis, dt=dt) if model is None else model
    x1 = random_rpc(1.0, identification_s, dt, seed)
    x15 = random_rpc(1.5, verification_s, dt, seed + 1)
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


SINE_FREQS_HZ = (1.0, 5.0, 10.0, 15.0, 20.0)  # seed 001 §3.2.1
SINE_AMPS_M = (0.5e-3, 1.0e-3, 2.0e-3, 3.0e-3, 4.0e-3)


def behaviour_numbers(axis: str, dt: float = PAPER_DT) -> dict[str, object]:
    """What the papers report, measured on the specimen alone (no measurement effects).

    - ``step_force_n``: force after a held 4 mm step (seed 000 §5.2) at 0.1, 1, 5, 10, 20 s;
    - ``heating``: temperature rise and drop of the force amplitude (last 10 Hz cycle against
      the cycle at 1 s; includes ~0.3 % of slow Maxwell settling) after 10 s and 60 s of a 4 mm
      10 Hz sine, and after 10 s at 0.5 mm 1 Hz;
    - ``stroke_force_n``: largest |F| of a 12.5 mm sine at 0.1 and 1 Hz (machine: 25 kN);
    - ``kdyn_n_per_mm`` / ``loop_energy_j``: peak-to-peak force over twice the amplitude, and
      the work per cycle, on the last cycle of 3 s sines, rows SINE_AMPS_M, columns SINE_FREQS_HZ.
    """
    m = RubberBushing.preset(axis, dt=dt, measurement=False)
    pre = 0.5
    f = m.simulate(step_hold(4e-3, 20.0, dt, pre_s=pre))
    step = {s: float(f[int(round((pre + s) / dt))]) for s in (0.1, 1.0, 5.0, 10.0, 19.9)}
    heating = {}
    for name, amp, freq, dur in (
        ("4mm_10Hz_10s", 4e-3, 10.0, 10.0),
        ("4mm_10Hz_60s", 4e-3, 10.0, 60.0),
        ("0.5mm_1Hz_10s", 0.5e-3, 1.0, 10.0),
    ):
        f = m.simulate(sine(freq, amp, dur, dt))
        n = int(round(1.0 / freq / dt))
        first = np.ptp(f[int(round(1.0 / dt)) : int(round(1.0 / dt)) + n])
        heating[name] = {
            "dT_k": float(m.state[2, 0]),
            "amplitude_drop": float(1.0 - np.ptp(f[-n:]) / first),
        }
    stroke = {}
    for freq in (0.1, 1.0):
        stroke[f"{freq:g}Hz"] = float(np.max(np.abs(m.simulate(sine(freq, 12.5e-3, 2 / freq, dt)))))
    kdyn = np.zeros((len(SINE_AMPS_M), len(SINE_FREQS_HZ)))
    energy = np.zeros_like(kdyn)
    for i, amp in enumerate(SINE_AMPS_M):
        for j, freq in enumerate(SINE_FREQS_HZ):
            x = sine(freq, amp, 3.0, dt)
            f = m.simulate(x)
            n = int(round(1.0 / freq / dt))
            kdyn[i, j] = np.ptp(f[-n:]) / (2 * amp) / 1e3
            energy[i, j] = np.sum(0.5 * (f[-n:] + f[-n - 1 : -1]) * np.diff(x[-n - 1 :]))
    return {
        "step_force_n": step,
        "heating": heating,
        "stroke_force_n": stroke,
        "kdyn_n_per_mm": kdyn,
        "loop_energy_j": energy,
    }
