"""One HalfCar-v0 car driven through a manoeuvre without its reference twin.

An error-transfer campaign runs the same reference car once and then a hundred cars that differ
from it by one small bushing error; HalfCarEnv would step the unchanged twin beside every one
(half of the cost). ``single_car_run`` steps only the model car, with HalfCarEnv's own pieces
in HalfCarEnv's order (sample the pivots, integrate, read the outputs, judge the bounds), so
its outputs equal the env's model car's bit for bit (tests/vehicle/test_transfer.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv.rigs.halfcar_car import HalfCar
from bushenv.rigs.halfcar_inputs import replay_inputs
from bushenv.rigs.halfcar_outputs import car_outputs, out_of_bounds, sample
from bushenv.rigs.halfcar_params import ENV_ID, POSITIONS, HalfCarParameters
from bushenv.rigs.specs import spec_kwargs
from bushenv.vehicle.compare import OUTPUTS
from bushenv.vehicle.manoeuvres import Manoeuvre

KEYS = tuple(k for o in OUTPUTS for k in o.keys)  # the car's output columns, ``OUTPUTS`` order


@dataclass
class SingleRun:
    """One car's outputs: ``outputs`` output name -> (n, k) over the ``steps`` run (wheel loads
    less the static load, as ``compare.CarRun``); ``deflection`` (n, 4, 3) the pivots (axial m,
    radial m, rotation rad, ``POSITIONS`` order); ``end`` why it stopped early ("" if not)."""

    manoeuvre: str
    steps: int
    outputs: dict[str, np.ndarray]
    deflection: np.ndarray
    end: str


def single_car_run(
    manoeuvre: Manoeuvre, pivots: Any, env_kwargs: dict[str, Any] | None = None
) -> SingleRun:
    """Replay ``manoeuvre`` with ``pivots`` (a model, name or file for all four, or a table by
    position) in HalfCar-v0's model car; ``env_kwargs`` override the spec's."""
    p = HalfCarParameters(spec_kwargs(ENV_ID, {**(env_kwargs or {}), "model": pivots}))
    inputs = replay_inputs(p, manoeuvre.reset_options())
    models = p.models
    for m in models.values() if isinstance(models, dict) else (models,):
        m.reset(1 if isinstance(models, dict) else len(POSITIONS))
    car = HalfCar(p, "model")
    before = np.zeros(3)
    prev_v = (0.0, 0.0)
    rows: list[list[float]] = []
    end = ""
    for now in inputs:
        q, _, _, why = sample(car, models, p)
        car.integrate(before[:2], now[:2], before[2], now[2])
        roads = now[:2].tolist()
        road_v = ((now[:2] - before[:2]) / p.dt).tolist()
        out = car_outputs(p, car, roads, road_v, prev_v, float(now[2]))
        prev_v = (out["body_vx_m_per_s"], out["body_vy_m_per_s"])
        end = why or out_of_bounds(p, out, q)
        if end:
            break
        rows.append([out[k] for k in KEYS] + q.ravel().tolist())
        before = now
    data = np.array(rows, dtype=np.float64).reshape(len(rows), len(KEYS) + 3 * len(POSITIONS))
    outputs, col = {}, 0
    for o in OUTPUTS:
        shift = p.tyre_static_n if o.name == "wheel_load" else 0.0
        outputs[o.name] = data[:, col : col + len(o.keys)] - shift
        col += len(o.keys)
    q_all = data[:, col:].reshape(-1, len(POSITIONS), 3)
    return SingleRun(manoeuvre.name, len(rows), outputs, q_all, end)
