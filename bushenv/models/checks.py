"""The model contract as checks any registered model gets (like scikit-learn's estimator checks
and Gymnasium's env checker): ``tests/models/test_registry_checks.py`` runs every check over
every ``MODELS`` entry and axis, so registering a model is the one step that tests it.

Each check takes a fresh model and raises ``AssertionError`` naming the model and what broke.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from bushenv.models.base import BushingModel

Check = Callable[[Callable[[], BushingModel]], None]


def drive(T: int, B: int, seed: int, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """A smooth random deflection (about +-2 mm) and its velocity, (T, B) each."""
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.normal(size=(T, B)), axis=0) * 2e-4
    x -= x.mean(axis=0)
    return x, np.gradient(x, dt, axis=0)


def check_reset_reruns_identically(make: Callable[[], BushingModel]) -> None:
    m = make()
    x, v = drive(300, 1, 0, m.dt)
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
    x, v = drive(200, 4, 1, m.dt)
    batched = m.simulate(x, v)
    m.reset(4)
    looped = np.array([m.step(x[t], v[t]) for t in range(200)])
    singles = np.stack([m.simulate(x[:, b], v[:, b]) for b in range(4)], axis=1)
    assert np.array_equal(batched, looped), f"{m.name}: batched simulate != looped step"
    assert np.array_equal(batched, singles), f"{m.name}: a batch != its columns run alone"


def check_copy_is_independent(make: Callable[[], BushingModel]) -> None:
    m = make()
    x, v = drive(100, 1, 2, m.dt)
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
    x, v = drive(150, 2, 3, m.dt)
    with tempfile.TemporaryDirectory() as tmp:
        path = m.save(Path(tmp) / "m.npz")
        m2 = load_model(path)
        assert type(m2) is type(m), f"{m.name}: loads as {type(m2).__name__}"
        assert np.array_equal(m.simulate(x, v), m2.simulate(x, v)), f"{m.name}: file differs"
        assert get_model(str(path)).name == m.name


CHECKS: dict[str, Check] = {
    "reset_reruns_identically": check_reset_reruns_identically,
    "batched_equals_looped": check_batched_equals_looped,
    "copy_is_independent": check_copy_is_independent,
    "save_load_round_trip": check_save_load_round_trip,
}
