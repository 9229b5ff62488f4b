"""The 3-axis test machine: the programme of ``programme.py`` run on a planar model, as records.

``items(kind, dt, seed, n_index, duration_s)`` lists named (T, 3) motions; ``measure(model,
items)`` runs each from rest. ``kind``:

- ``"papers"``: what the seeds measure, in three axes: random on all axes at n = 1 (40 s,
  ``seed``), independent and correlated; the same at n = 1.5 (20 s, ``seed + 1``); the coupled
  sine sets (a 3 mm radial preload under a 0.5-5 Hz rotation sweep of 1.5 x 0.05 rad, and a
  0.075 rad rotation preload under a radial sweep of 3 mm; 20 s each);
- ``"random"``: random on all axes at ``n_index``, independent and correlated.

The planar reference (``reference`` with its load cell) measures each record with its own
noise seed, so no two records share their noise.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bushenv.planar.base import PlanarModel, PlanarModelError
from bushenv.planar.programme import preload_sweep, random_correlated, random_independent
from bushenv.planar.reference import THETA_N1_RAD, PlanarRubber

KINDS = ("papers", "random")
N_VERIFY = 1.5
PRELOAD_M = 3.0e-3


def _random(n: float, duration_s: float, dt: float, seed: int) -> list[tuple[str, np.ndarray]]:
    tail = f"n{n:g}_{duration_s:g}s_seed{seed}"
    return [
        (f"random_independent_{tail}", random_independent(n, duration_s, dt, seed)),
        (f"random_correlated_{tail}", random_correlated(n, duration_s, dt, seed)),
    ]


def items(
    kind: str, dt: float, seed: int = 0, n_index: float = 1.0, duration_s: float | None = None
) -> list[tuple[str, np.ndarray]]:
    """The named motions (T, 3) in m, m, rad of programme ``kind`` (see the module docstring)."""
    if kind not in KINDS:
        raise PlanarModelError(f"3-axis programme {kind!r}; known: {', '.join(KINDS)}")
    if kind == "random":
        if duration_s is None:
            duration_s = 40.0 if n_index <= 1.0 else 20.0
        if not (n_index > 0 and duration_s >= 1.0):
            raise PlanarModelError(
                f"3-axis random: n must be > 0 and the duration >= 1 s, got n={n_index}, "
                f"{duration_s} s"
            )
        return _random(n_index, duration_s, dt, seed)
    theta = N_VERIFY * THETA_N1_RAD
    return [
        *_random(1.0, 40.0, dt, seed),
        *_random(N_VERIFY, 20.0, dt, seed + 1),
        (
            f"radial_preload_{PRELOAD_M * 1e3:g}mm_rotation_sweep",
            preload_sweep(1, PRELOAD_M, theta, 20.0, dt),
        ),
        (
            f"rotation_preload_{theta:g}rad_radial_sweep",
            preload_sweep(2, theta, PRELOAD_M, 20.0, dt),
        ),
    ]


def measure(
    model_for: Callable[[int], PlanarModel],
    motions: list[tuple[str, np.ndarray]],
    say: Callable[[str], None] | None = None,
) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(name, q, f) per motion: ``model_for(k)`` (a fresh model for record k) run from rest."""
    out = []
    for k, (name, q) in enumerate(motions):
        f = model_for(k).simulate(q)
        if not np.all(np.isfinite(f)):
            raise PlanarModelError(f"{name}: the model's force is not finite (diverged)")
        out.append((name, q, f))
        if say:
            peak = np.abs(f).max(axis=0)
            say(f"[{k + 1}/{len(motions)}] {name}: {len(q)} samples, max |F| = {peak[0]:.4g} N, "
                f"{peak[1]:.4g} N, {peak[2]:.4g} N m")  # fmt: skip
    return out


def reference_for(seed: int, dt: float) -> Callable[[int], PlanarRubber]:
    """The planar reference with its load cell, noise seed ``seed`` apart for each record."""
    return lambda k: PlanarRubber.preset(seed=1000 * seed + k, dt=dt)
