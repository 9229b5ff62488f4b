"""HalfCar-v0's defaults against what they must admit: the standards' steering events."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import bushenv  # noqa: F401  (registers the ids)
from bushenv.vehicle.manoeuvres import standard_manoeuvres

DT = 1.0 / 204.8


def test_every_standard_manoeuvre_replays_with_the_default_lateral_step_limit():
    """ISO 7401's step and pulse steer, NHTSA's fishhook (720 deg/s, the fastest: 0.375 m/s^2
    per step) and ISO 3888-1 replay as generated, no override; the limit still refuses a
    lateral load that jumps by more than 0.4 m/s^2 in one step."""
    env = gym.make("HalfCar-v0").unwrapped
    steps = []
    for m in standard_manoeuvres(DT):
        env.reset(seed=0, options=m.reset_options())
        steps.append(m.largest_steps()[1])
    assert max(steps) > 0.3  # the fishhook's fast steer is among them
    assert env.params.max_ay_step >= max(steps)
    try:
        env.reset(options={"lateral_accel": np.array([0.0, 0.45])})
    except bushenv.rigs.common.RigError as exc:
        assert "max_lateral_accel_step" in str(exc)
    else:
        raise AssertionError("a 0.45 m/s^2 step was accepted")
