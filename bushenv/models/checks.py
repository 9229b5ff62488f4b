"""The model contract as checks any registered model gets (like scikit-learn's estimator checks
and Gymnasium's env checker): ``tests/models/test_registry_checks.py`` runs every check over
every ``MODELS`` entry, every form of it (one coordinate on each axis, three coordinates), so
registering a model is the one step that tests it.

Each check takes a fresh model and raises ``AssertionError`` naming the model and what broke.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from bushenv.models.base import BushingModel

Check = Callable[[Callable[[], BushingModel]], None]


# a coordinate's drive scale: about +-2 mm for a translation, +-0.05 rad for a rotation
SCALE = {"m": 2e-4, "rad": 5e-3}


def drive(
    T: int, B: int, seed: int, dt: float, units: tuple[str, ...] = ("m",)
) -> tuple[np.ndarray, np.ndarray]:
    """A smooth random deflection (about +-2 mm, +-0.05 rad) and its velocity: (T, B) each for
    one coordinate, (T, B, C) for the C coordinates of ``units``."""
    rng = np.random.default_rng(seed)
    if len(units) == 1:
        x = np.cumsum(rng.normal(size=(T, B)), axis=0) * SCALE[units[0]]
    else:
        scale = np.array([SCALE[u] for u in units])
        x = np.cumsum(rng.normal(size=(T, B, len(units))), axis=0) * scale
    x -= x.mean(axis=0)
    return x, np.gradient(x, dt, axis=0)


def check_reset_reruns_identically(make: Callable[[], BushingModel]) -> None:
    m = make()
    x, v = drive(300, 1, 0, m.dt, m.units)
    first = m.simulate(x[:, 0], v[:, 0])
    again = m.simulate(x[:, 0], v[:, 0])
    m.reset()
    stepped = np.array([m.step(x[t, 0], v[t, 0]) for t in range(300)])
    assert np.array_equal(first, again), f"{m.name}: a second simulate differs from the first"
    assert np.array_equal(first, stepped), f"{m.name}: step after reset differs from simulate"
    assert np.all(np.isfinite(first)), f"{m.name}: not finite on a 2 mm random drive"
    assert np.max(np.abs(first)) > 0, f"{m.name}: no force at all"


def check_batched_equals_looped(make: Callable[[], BushingModel]) -> None:
    m = make()
    x, v = drive(200, 4, 1, m.dt, m.units)
    batched = m.simulate(x, v)
    m.reset(4)
    looped = np.array([m.step(x[t], v[t]) for t in range(200)])
    singles = np.stack([m.simulate(x[:, b], v[:, b]) for b in range(4)], axis=1)
    assert np.array_equal(batched, looped), f"{m.name}: batched simulate != looped step"
    assert np.array_equal(batched, singles), f"{m.name}: a batch != its columns run alone"


def check_copy_is_independent(make: Callable[[], BushingModel]) -> None:
    m = make()
    x, v = drive(100, 1, 2, m.dt, m.units)
    alone = m.copy()
    alone.reset(1)
    want = [alone.step(x[t, 0], v[t, 0]) for t in range(100)]
    a, b = m.copy(), m.copy()
    a.reset(1)
    b.reset(1)
    got = []
    for t in range(100):  # b stepped in between must not move a's state
        got.append(a.step(x[t, 0], v[t, 0]))
        b.step(-x[t, 0], -v[t, 0])
    assert np.array_equal(got, want), f"{m.name}: copies share state"
    assert a.dt == m.dt, f"{m.name}: copy changed dt"


def check_save_load_round_trip(make: Callable[[], BushingModel]) -> None:
    from bushenv.models import get_model, load_model

    m = make()
    if not m.param_names:  # a model without parameters to save (the reference rubber)
        return
    x, v = drive(150, 2, 3, m.dt, m.units)
    with tempfile.TemporaryDirectory() as tmp:
        path = m.save(Path(tmp) / "m.npz")
        m2 = load_model(path)
        assert type(m2) is type(m), f"{m.name}: loads as {type(m2).__name__}"
        assert np.array_equal(m.simulate(x, v), m2.simulate(x, v)), f"{m.name}: file differs"
        assert get_model(str(path), coords=m.n_coords).name == m.name


def check_shapes_follow_the_coordinates(make: Callable[[], BushingModel]) -> None:
    m = make()
    c = m.n_coords
    assert len(m.units) == len(m.force_units) == c, f"{m.name}: units for {c} coordinates"
    x, v = drive(30, 3, 4, m.dt, m.units)
    want = (30, 3) if c == 1 else (30, 3, c)
    assert m.simulate(x, v).shape == want, f"{m.name}: (T, B{', C' * (c > 1)}) in, same out"
    one = m.simulate(x[:, 0], v[:, 0])
    assert one.shape == want[:1] + want[2:], f"{m.name}: one history in, one out"
    m.reset(1)
    f = m.step(x[0, 0], v[0, 0])
    assert np.shape(f) == (() if c == 1 else (c,)), f"{m.name}: step's force shape"


def example(name: str, coords: int = 1, axis: str = "axial") -> BushingModel:
    """A model of the registered kind ``name`` over ``coords`` coordinates, as it is checked:
    the shipped file or the preset (a reference's as it judges: the rubber without its
    measurement chain's noise, whose stream is per batch), else an untrained network."""
    from bushenv.models import MODELS, get_model, get_reference, has_preset

    entry = MODELS[name]
    if coords == 1:
        if entry.reference_preset:
            return get_reference(name, axis=axis)
        return get_model(name, axis=axis)
    cls = entry.model_class(coords)
    if has_preset(cls):
        return cls.preset(**entry.preset, **entry.reference_preset)
    return cls.untrained(seed=0)


def forms() -> list[tuple[str, int, str]]:
    """(name, coordinates, axis) of every registered form: one coordinate on each axis."""
    from bushenv.models import AXES, MODELS

    return [
        (name, c, axis)
        for name, entry in MODELS.items()
        for c in entry.coordinate_counts()
        for axis in (AXES if c == 1 else ("",))
    ]


CHECKS: dict[str, Check] = {
    "reset_reruns_identically": check_reset_reruns_identically,
    "batched_equals_looped": check_batched_equals_looped,
    "copy_is_independent": check_copy_is_independent,
    "save_load_round_trip": check_save_load_round_trip,
    "shapes_follow_the_coordinates": check_shapes_follow_the_coordinates,
}
