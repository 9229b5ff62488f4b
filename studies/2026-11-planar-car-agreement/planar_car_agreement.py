"""How closely QuarterCar-v0's vector entry point (QuarterCarBatch) follows the pymunk env with a
planar arm bushing: the largest difference of each signal over a road, relative to its peak.

    python studies/2026-11-planar-car-agreement/planar_car_agreement.py [--arms linear reference] [--harsh] [--quiet]

Replays each road in the pymunk env and in column 0 of the vector env (arm_bushing = each
planar preset, the twin ``reference``, the default when measured) and prints one markdown row per arm and
road (docs/planar.md quotes them). Roads: the papers' 400 mm x 100 mm bump at 30 km/h then a
rough road (2048 steps, tests/rigs/test_quartercar_vector.py), a pothole 60 mm deep, a random
rough road and a square wave at the rate limit through the wheel hop (+-30 mm, 9-step half
period). ``--harsh`` adds the rate-limit roads 3, 8, 11, 15, 20, 25 of
tests/rigs/test_quartercar.py with the bounds removed and the twin the same preset (travel
17-280 mm). Takes about 5 s (20 s with ``--harsh``).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import gymnasium as gym  # noqa: E402

import bushenv  # noqa: E402,F401  (registers the envs)
from bushenv import excitation  # noqa: E402
from bushenv.progress import Progress  # noqa: E402

DT = 1.0 / 204.8
FORCES = (
    "force_radial_model_n",
    "force_axial_model_n",
    "moment_model_nm",
    "force_radial_reference_n",
    "force_axial_reference_n",
    "moment_reference_nm",
)
MOTION = ("chassis_y_m", "wheel_y_m", "arm_rotation_rad", "reference_arm_rotation_rad")


def roads() -> dict[str, np.ndarray]:
    bump = excitation.bump(0.4, 0.1, 30 / 3.6, DT, pre_s=0.3, post_s=0.5)
    walk = np.cumsum(np.random.default_rng(1).normal(0.0, 0.004, 2048))
    walk = np.clip(walk - np.linspace(0.0, walk[-1], 2048), -0.1, 0.1)
    steps = np.clip(np.random.default_rng(0).normal(0.0, 0.012, 600), -0.05, 0.05)
    square, x = np.zeros(400), 0.0
    for t in range(400):  # the road at the rate limit, clipped to +-30 mm (test_quartercar's)
        x = min(0.03, max(-0.03, x + (0.05 if (t // 9) % 2 == 0 else -0.05)))
        square[t] = x
    return {
        "bump then rough": np.concatenate([bump, bump[-1] + walk])[:2048],
        "pothole": -excitation.bump(0.3, 0.06, 20 / 3.6, DT, pre_s=0.2, post_s=0.8),
        "rough": np.concatenate([[0.0], np.clip(np.cumsum(steps), -0.06, 0.06)]),
        "wheel-hop square wave": np.concatenate([[0.0], square, np.zeros(200)]),
    }


def harsh_roads() -> tuple[dict[str, np.ndarray], dict]:
    """The rate-limit roads of tests/rigs/test_quartercar.py and its bounds switched off."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "rigs"))
    from test_quartercar import LOOSE, worst_roads

    roads = worst_roads(600, np.random.default_rng(0))
    loose = dict(LOOSE, arm_moment_limit_nm=1e12)
    return {f"rate-limit road {j}, no bounds": roads[:, j] for j in (3, 8, 11, 15, 20, 25)}, loose


def differences(arm: str, road: np.ndarray, **kw) -> tuple[dict[str, float], int, str]:
    """(signal -> max |pymunk - vector| / peak, steps run, how the episodes ended)."""
    kw = {"arm_bushing_reference": "reference", **kw}  # the twin as measured (the tilt set)
    env = gym.make("QuarterCar-v0", arm_bushing=arm, **kw)
    venv = gym.make_vec(
        "QuarterCar-v0", num_envs=2, vectorization_mode="vector_entry_point", arm_bushing=arm,
        **kw,
    )  # fmt: skip
    env.reset(seed=0, options={"excitation": road})
    venv.reset(seed=0, options={"excitation": road})
    keys = FORCES + MOTION
    s, v = [], []
    for _ in range(len(road)):
        *_, term, trunc, info = env.step(np.zeros(1, np.float32))
        *_, v_term, v_trunc, v_info = venv.step(np.zeros((2, 1), np.float32))
        s.append([info[k] for k in keys])
        v.append([v_info[k][0] for k in keys])
        if term or trunc or v_term[0] or v_trunc[0]:
            break
    ends = "alike" if (term, trunc) == (v_term[0], v_trunc[0]) else "DIFFER"
    s, v = np.array(s), np.array(v)
    err = np.abs(s - v).max(axis=0) / np.abs(s).max(axis=0)
    return dict(zip(keys, err, strict=True)), len(s), ends


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--arms", nargs="+", default=["linear", "reference"])
    ap.add_argument("--harsh", action="store_true", help="add the rate-limit roads, no bounds")
    ap.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    args = ap.parse_args()
    cases = [(arm, name, road, {}) for arm in args.arms for name, road in roads().items()]
    if args.harsh:
        harsh, loose = harsh_roads()
        cases += [
            (arm, name, road, {**loose, "arm_bushing_reference": arm})
            for arm in args.arms
            for name, road in harsh.items()
        ]
    progress = Progress(len(cases), quiet=args.quiet, label="agreement")
    print("| arm_bushing | road | steps | forces and moments | chassis, wheel | arm rotation "
          "| episode end |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    worst = 0.0
    for i, (arm, name, road, kw) in enumerate(cases):
        err, steps, ends = differences(arm, road, **kw)
        forces = max(err[k] for k in FORCES)
        worst = max(worst, forces)
        body = max(err["chassis_y_m"], err["wheel_y_m"])
        turn = max(err["arm_rotation_rad"], err["reference_arm_rotation_rad"])
        print(f"| {arm} | {name} | {steps} | {forces:.3%} | {body:.3%} | {turn:.3%} | {ends} |")
        progress.update(i + 1, f"{arm}, {name}")
    print(f"\nlargest force or moment difference: {worst:.3%} of its peak")


if __name__ == "__main__":
    main()
