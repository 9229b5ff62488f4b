"""Which three-axis twin QuarterCar-v0's arm can carry on the harshest roads: the 32 rate-limit
roads of tests/rigs/test_quartercar.py with the bounds removed, model and twin the same preset.

    python studies/2026-11-planar-car-agreement/twin_roads.py [--arms rubber-torsion reference]

Per arm: how many roads settle (the moment's last 0.5 s flat to 1 % of its peak, no episode
ended), within the 120 mm travel bound and beyond it, and the largest arm rotation within it
(docs/planar.md quotes the lines). About 1 min per arm.
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
from bushenv.progress import Progress  # noqa: E402

TRAVEL_M = 0.125  # the car's 120 mm bound, with the margin tests/rigs uses


def run(arm: str, road: np.ndarray, loose: dict) -> tuple[bool, float, float]:
    """(settled, largest |travel| m, largest |arm rotation| rad) on one road."""
    env = gym.make("QuarterCar-v0", arm_bushing=arm, arm_bushing_reference=arm, **loose)
    env.reset(seed=0, options={"excitation": road})
    rows = []
    while not rows or not (rows[-1][2] or rows[-1][3]):
        rows.append(env.step(np.zeros(1, np.float32)))
    m = np.array([r[4]["moment_model_nm"] for r in rows])
    theta = np.abs([r[4]["arm_rotation_rad"] for r in rows]).max()
    travel = max(abs(r[4]["suspension_travel_m"]) for r in rows)
    flat = np.isfinite(m).all() and np.ptp(m[-100:]) <= 0.01 * np.abs(m).max()
    return bool(flat and not rows[-1][2]), float(travel), float(theta)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", nargs="+", default=["rubber-torsion", "reference"])
    args = ap.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "rigs"))
    from test_quartercar import LOOSE, worst_roads

    roads = worst_roads(600, np.random.default_rng(0))
    loose = dict(LOOSE, arm_moment_limit_nm=1e12)
    progress = Progress(len(args.arms) * roads.shape[1], label="twin roads")
    for arm in args.arms:
        out = []
        for j in range(roads.shape[1]):
            out.append(run(arm, roads[:, j], loose))
            progress.update(progress.done + 1, f"{arm} road {j}")
        inside = [o for o in out if o[1] <= TRAVEL_M]
        beyond = [o for o in out if o[1] > TRAVEL_M]
        top = max((o[2] for o in inside), default=float("nan"))
        print(
            f"{arm}: within travel {sum(o[0] for o in inside)}/{len(inside)} settle "
            f"(arm rotation up to {top:.3f} rad); beyond it {sum(o[0] for o in beyond)}/"
            f"{len(beyond)} (travel up to {max((o[1] for o in beyond), default=0) * 1e3:.0f} mm)"
        )


if __name__ == "__main__":
    main()
