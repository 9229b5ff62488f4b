"""A three-axis bushing of this study's own, outside the reference's and the candidates' forms.

    python studies/2026-11-diagnose-three-axis/outside_bushing.py [--seeds 5]

Coordinates (axial m, radial m, rotation rad) as the reference's, but every law written here
and none of them a candidate's or the reference's form; 512 Hz; a symmetric linear coupling
K_ar = 0.1 sqrt(k_a k_r) that the baseline's cross terms must carry; noise 0.5 % of each
coordinate's RMS force. One effect per case:

| case | law |
|---|---|
| none | linear (with the cross term) |
| boucwen@radial | Bouc-Wen hysteresis, n = 2 (no Iwan/Dahl sum), 10-20 % of k_r x peak |
| fractional@rotation | a power-law term k_f D^alpha theta, alpha 0.2-0.4 |
| softening@axial | tanh backbone k_a L tanh(u_a / L), 15-30 % softer at TEST's peak |
| abscoupling | radial stiffness rising with abs(axial), k_r a abs(u_a) / L u_r, and its energy's |
|  | axial force: acts on axial and radial, and is not q_i q_j^2 |

TRAIN: random on all coordinates (independent drives, n = 1, 20 s); TEST: a chirp 0.3-8 Hz
per coordinate at 1.3 x the n = 1 peaks with different phases and a 3 s held step in the
middle. Writes ``outside.json`` and prints the table of the README.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from scipy.signal import fftconvolve

from bushenv.diagnose.fit import diagnose
from bushenv.excitation import chirp
from bushenv.models.base import velocity_of
from bushenv.motions import PEAK_AT_N1, random_independent
from bushenv.records import Record

HERE = Path(__file__).parent
DT = 1.0 / 512.0
K = np.array([2.0e5, 7.4e5, 3000.0])
C = np.array([3950.0, 12880.0, 52.0])
CASES = {  # case: (the effect a right answer names, the coordinates it acts on)
    "none": ("none", ()),
    "boucwen@radial": ("friction", ("radial",)),
    "fractional@rotation": ("relaxation", ("rotation",)),
    "softening@axial": ("hardening", ("axial",)),
    "abscoupling": ("coupling", ("radial", "axial")),
}


def test_motion(seed: int, duration_s: float = 20.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    n = int(round(duration_s / DT))
    q = np.zeros((n, 3))
    for i in range(3):
        phase = int(rng.integers(0, n // 4))
        sweep = chirp(0.3, 8.0, 1.3 * PEAK_AT_N1[i], duration_s, DT)[:n]
        q[:, i] = np.roll(sweep, phase) * np.hanning(n) ** 0.1
        a, b = n // 2, n // 2 + int(3.0 / DT)
        q[a:b, i] = 0.8 * PEAK_AT_N1[i] * (1 if i != 1 else -1)
    return q


def forces(q: np.ndarray, case: str, seed: int, noise_seed: int) -> np.ndarray:
    rng = np.random.default_rng([seed, list(CASES).index(case)])
    v = velocity_of(q, DT)
    kar = 0.1 * np.sqrt(K[0] * K[1])
    f = q * K + v * C
    f[:, 0] += kar * q[:, 1]
    f[:, 1] += kar * q[:, 0]
    if case == "boucwen@radial":
        share, x_y = rng.uniform(0.10, 0.20), rng.uniform(0.15, 0.4) * PEAK_AT_N1[1]
        f_y = share * K[1] * PEAK_AT_N1[1]
        z, dq = 0.0, np.diff(q[:, 1], prepend=0.0)
        zs = np.empty(len(q))
        for t, d in enumerate(dq):  # dz = (dx - b |dx| |z| z - g dx z^2) / x_y, n = 2
            m = int(np.ceil(abs(d) / (0.05 * x_y))) or 1  # substeps: explicit Euler stays stable
            for _ in range(m):
                z += (d / m - 0.5 * abs(d / m) * z * abs(z) - 0.5 * d / m * z * z) / x_y
            zs[t] = z
        f[:, 1] += f_y * zs
    elif case == "fractional@rotation":
        alpha = rng.uniform(0.2, 0.4)
        w = np.cumprod(np.r_[1.0, (np.arange(1, len(q)) - 1 - alpha) / np.arange(1, len(q))])
        d_alpha = fftconvolve(q[:, 2], w)[: len(q)] / DT**alpha  # Grunwald-Letnikov
        tau = 0.3  # s: the weight k_f = 0.3 k_t tau^alpha
        f[:, 2] += 0.3 * K[2] * tau**alpha * d_alpha
    elif case == "softening@axial":
        peak = 1.3 * PEAK_AT_N1[0]
        lost = rng.uniform(0.15, 0.30)  # secant stiffness lost at the peak: tanh(p/L) L/p
        grid = np.linspace(0.3, 10, 4000) * peak
        length = grid[np.argmin(np.abs(np.tanh(peak / grid) * grid / peak - (1 - lost)))]
        f[:, 0] += K[0] * (length * np.tanh(q[:, 0] / length) - q[:, 0])
    elif case == "abscoupling":
        a, lc = rng.uniform(0.2, 0.4), PEAK_AT_N1[0]
        f[:, 1] += K[1] * a * np.abs(q[:, 0]) / lc * q[:, 1]
        f[:, 0] += K[1] * a * np.sign(q[:, 0]) / lc * q[:, 1] ** 2 / 2  # the energy's partner
    noise = np.random.default_rng(noise_seed).standard_normal(q.shape)
    return f + 0.005 * np.sqrt(np.mean(f**2, axis=0)) * noise


def run(seeds: int) -> list[dict]:
    rows = []
    for seed in range(seeds):
        for case, (expected, coords) in CASES.items():
            motions = (random_independent(1.0, 20.0, DT, 50 + seed), test_motion(seed))
            recs = [
                Record(np.arange(len(q)) * DT, q, forces(q, case, seed, 10 * seed + k), n)
                for k, (n, q) in enumerate(zip(("train", "test"), motions, strict=True))
            ]
            r = diagnose(recs[0], [recs[1]])
            if coords:
                hit = r["coordinate"] in coords and r["effect"] == expected
            else:
                hit = r["coordinate"] is None
            false = [c for c, e in r["effects"].items() if c not in coords and e != "none"]
            rows.append(
                {
                    "seed": seed,
                    "case": case,
                    "hit": bool(hit),
                    "answer": r["answer"],
                    "effects": r["effects"],
                    "shrink": r["shrink"],
                    "false_coordinates": false,
                }
            )
            print(
                f"seed {seed} {case:20s} {'hit ' if hit else 'MISS'} {r['answer']:36s} "
                f"shrink {100 * r['shrink']:5.1f} % {r['effects']}",
                flush=True,
            )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    rows = run(parser.parse_args().seeds)
    (HERE / "outside.json").write_text(json.dumps(rows, indent=1) + "\n")
    print("| case | hits | median shrink (hits) | effect named where none acts |")
    print("|---|---|---|---|")
    for case in CASES:
        r = [x for x in rows if x["case"] == case]
        hits = [x["shrink"] for x in r if x["hit"]]
        med = f"{100 * np.median(hits):.0f} %" if hits and case != "none" else "-"
        false = sum(bool(x["false_coordinates"]) for x in r)
        print(f"| {case} | {len(hits)}/{len(r)} | {med} | {false} |")


if __name__ == "__main__":
    main()
