"""The planar model contract as checks, run by tests over every ``PLANAR_MODELS`` entry.

A registered planar model gets them without editing a test: ``example(name)`` builds one from
its ``preset`` or, for networks, ``untrained``; ``check_planar_model`` raises ``AssertionError``
naming the model and the broken clause.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bushenv.planar.base import PlanarModel
from bushenv.planar.registry import load_planar_model, model_class


def example(name: str) -> PlanarModel:
    """An instance of the registered ``name``: its preset, else an untrained network."""
    cls = model_class(name)
    return cls.preset() if hasattr(cls, "preset") else cls.untrained(seed=0)


def _drive(T: int, B: int) -> np.ndarray:
    t = np.arange(T)[:, None, None] * 0.01
    phase = np.arange(B)[None, :, None] + np.arange(3)[None, None, :] * 0.7
    return np.sin(2 * np.pi * (1.3 + np.arange(3)) * t + phase) * np.array([2e-3, 2e-3, 0.05])


def check_planar_model(model: PlanarModel, tmp: Path) -> None:
    """The contract: shapes, step loop == batched simulate (bits), reset forgets, copy and
    save/load give the same forces, rest gives a finite force."""
    name = model.name
    q = _drive(60, 3)
    v = np.gradient(q, model.dt, axis=0)
    f = model.simulate(q, v)
    assert f.shape == q.shape and np.all(np.isfinite(f)), f"{name}: simulate shape or finiteness"
    f2 = model.simulate(q[:, 0, :], v[:, 0, :])
    assert f2.shape == (60, 3), f"{name}: (T, 3) in must give (T, 3) out"
    model.reset(3)
    looped = np.stack([model.step(q[t], v[t]) for t in range(60)])
    assert np.array_equal(looped, f), f"{name}: step loop differs from batched simulate"
    assert np.array_equal(model.simulate(q, v), f), f"{name}: simulate after use differs"
    assert np.array_equal(model.copy().simulate(q, v), f), f"{name}: copy differs"
    back = load_planar_model(model.save(tmp / f"{name}.npz"))
    assert type(back) is type(model), f"{name}: file loads as {type(back).__name__}"
    assert np.array_equal(back.simulate(q, v), f), f"{name}: saved and loaded model differs"
