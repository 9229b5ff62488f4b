"""The 3-axis test machine: the programme of ``programme.py`` run on a planar model, as records.

``items(kind, dt, seed, n_index, duration_s)`` lists named (T, 3) motions; ``measure(model,
items)`` runs each from rest. ``kind``:

- ``"papers"``: what the seeds measure, in three axes: random on all axes at n = 1 (40 s,
  ``seed``), independent and correlated; the same at n = 1.5 (20 s, ``seed + 1``); the coupled
  sine sets (``coupled_sets``) at n = 1.5 (a 3 mm radial preload under a 0.5-5 Hz rotation sweep
  of 0.075 rad, a 0.075 rad rotation preload under a 3 mm radial sweep, and a 3 mm axial preload
  under a 3 mm radial sweep; 20 s each) and at n = 1 (2 mm, 0.05 rad): n = 1 identifies,
  n = 1.5 verifies. The n = 1 sets hold a preload, which random motion with nothing below 1 Hz
  never does: without them a fit cannot tell its slow relaxation from its static stiffness
  (studies/2026-11-planar-fit-unseen). The axial sets came last, after the others;
- ``"random"``: random on all axes at ``n_index``, independent and correlated;
- ``"combined"``: every held combination (``programme.held_sweeps``): each coordinate held at
  +- n x its n = 1 peak while each other one is swept, 10 s each (12 records), the uses a
  vehicle makes of a bushing that random motion never holds still.

The planar reference (``reference`` with its load cell) measures each record with its own
noise seed, so no two records share their noise.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bushenv.models.planar_base import PlanarModel, PlanarModelError
from bushenv.planar.programme import (
    PEAK_AT_N1,
    held_sweeps,
    preload_sweep,
    random_correlated,
    random_independent,
)
from bushenv.reference.planar import PlanarRubber

KINDS = ("papers", "random", "combined")
# what a 3-axis identification uses of the papers' programme at n = 1 (``bushenv reproduce
# --planar-identification``): the random records and the coupled sets, or the random only
IDENTIFICATIONS = {
    "programme": "random and the coupled sine sets at n = 1",
    "random": "random n = 1 only (as seed 000)",
}
N_VERIFY = 1.5


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
    if kind == "combined":
        return held_sweeps(n_index, dt, 10.0 if duration_s is None else duration_s)
    verify, identify = coupled_sets(N_VERIFY, dt), coupled_sets(1.0, dt)
    # each addition last, so the records before keep their noise seeds (and their files)
    return [
        *_random(1.0, 40.0, dt, seed),
        *_random(N_VERIFY, 20.0, dt, seed + 1),
        *verify[:2],
        *identify[:2],
        verify[2],
        identify[2],
    ]


def coupled_sets(n_index: float, dt: float, duration_s: float = 20.0) -> list:
    """The coupled sine sets at amplitude index n, named by their preloads: a radial preload of
    n x 2 mm under a 0.5-5 Hz rotation sweep of n x 0.05 rad, a rotation preload of n x 0.05 rad
    under a radial sweep of n x 2 mm, and an axial preload of n x 2 mm under a radial sweep of
    n x 2 mm (without it no record holds the axial coordinate, and its slow relaxation is not
    told from its static stiffness)."""
    axial, radial, theta = n_index * PEAK_AT_N1
    return [
        (
            f"radial_preload_{radial * 1e3:g}mm_rotation_sweep",
            preload_sweep(1, radial, theta, duration_s, dt),
        ),
        (
            f"rotation_preload_{theta:g}rad_radial_sweep",
            preload_sweep(2, theta, radial, duration_s, dt),
        ),
        (
            f"axial_preload_{axial * 1e3:g}mm_radial_sweep",
            preload_sweep(0, axial, radial, duration_s, dt),
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
