"""HalfCar-v0's info: the twin's bushing deflections beside the model car's."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import bushenv  # noqa: F401  (registers the ids)
from bushenv.rigs.halfcar_params import LINEAR, POSITIONS, REFERENCE

KEYS = tuple(
    (f"deflection_{p}_{c}_m" if c != "rotation" else f"rotation_{p}_rad")
    for p in POSITIONS for c in ("axial", "radial", "rotation")
)  # fmt: skip


def run(model: str, n: int = 120) -> list[dict]:
    env = gym.make("HalfCar-v0", model=model).unwrapped
    k = np.arange(n)
    inputs = {"road_left": 0.02 * np.sin(k / 8), "lateral_accel": np.minimum(0.1 * k, 4.0)}
    env.reset(seed=0, options=inputs)
    return [env.step(None)[4] for _ in range(n)]


def test_info_carries_the_reference_bushings_deflections_per_pivot_and_coordinate():
    """With the twin's law in the model car too, the two cars' deflections are one; with a
    linear model car they part, and each is the car's own."""
    same = run(REFERENCE)
    for k in KEYS:
        a = np.array([i[k] for i in same])
        b = np.array([i["reference_" + k] for i in same])
        assert np.abs(a).max() > 0 and np.array_equal(a, b), k
    other = run(LINEAR)
    for k in KEYS:
        ref = np.array([i["reference_" + k] for i in other])
        np.testing.assert_array_equal(ref, np.array([i["reference_" + k] for i in same]))
    parted = [np.abs(np.array([i[k] for i in other]) - np.array([i["reference_" + k]
                                                                 for i in other])).max()
              for k in KEYS]  # fmt: skip
    assert max(parted) > 0
