"""The test machine's programmes: named lists of motions for a bushing of C coordinates.

One coordinate (seed 001 §3.2, seed 000 §5.2):

| programme      | function               | excitation                                      |
|----------------|------------------------|-------------------------------------------------|
| harmonic       | ``harmonic_programme`` | sines 1, 5, 10, 15, 20 Hz x 0.5-4 mm, 10 s each |
| random         | ``random_item``        | RPC-like random at index n (n = 1: 2 mm peak)   |
| step           | ``step_item``          | 4 mm step after 0.5 s at rest, held 10 s        |
| papers         | ``papers_programme``   | all the above: random n = 1 40 s, n = 1.5 20 s  |

Durations: the papers' random records lasted 8.22 s (identification) and 6.44 s (verification)
(seed 002 §5); we default to 40 s and 20 s so that identification sees every part of the
spectrum many times (40 s at 204.8 Hz is 8192 samples) and verification is still long enough
for the thermal and relaxation memory of the reference bushing to show. The verification drive
uses a different seed from the identification drive (``seed + 1``), as the papers' two records
were different drives.

The three in-plane coordinates (``bushenv.motions``):

- ``papers``: random on all axes at n = 1 (40 s, ``seed``), independent and correlated; the
  same at n = 1.5 (20 s, ``seed + 1``); the coupled sine sets (``coupled_sets``) at n = 1.5
  and at n = 1: n = 1 identifies, n = 1.5 verifies. The n = 1 sets hold a preload, which random
  motion with nothing below 1 Hz never does: without them a fit cannot tell its slow relaxation
  from its static stiffness (studies/2026-11-planar-fit-unseen). The axial sets came last;
- ``random``: random on all axes at ``n_index``, independent and correlated;
- ``combined``: every held combination (``held_sweeps``): each coordinate held at +- n x its
  n = 1 peak while each other one is swept, 10 s each (12 records), the uses a vehicle makes
  of a bushing that random motion never holds still.

``programme_items(kind, n_coords, ...)`` gives any of them as ``ProgrammeItem``s;
``PROGRAMMES`` says which coordinate counts each has a form for.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bushenv import excitation as ex
from bushenv.errors import BadInput
from bushenv.models.base import PAPER_DT
from bushenv.motions import (
    N_VERIFY,
    coupled_sets,
    held_sweeps,
    random_correlated,
    random_independent,
)

HARMONIC_FREQUENCIES_HZ = (1.0, 5.0, 10.0, 15.0, 20.0)  # seed 001 §3.2.1
HARMONIC_AMPLITUDES_M = (0.5e-3, 1.0e-3, 2.0e-3, 3.0e-3, 4.0e-3)
HARMONIC_DURATION_S = 10.0
IDENTIFICATION_N = 1.0  # seed 001 §3.2.2, Figs. 12-15
VERIFICATION_N = 1.5
IDENTIFICATION_DURATION_S = 40.0  # papers: 8.22 s (seed 002 §5); see the module docstring
VERIFICATION_DURATION_S = 20.0  # papers: 6.44 s
STEP_SIZE_M = 4.0e-3  # seed 000 §5.2
STEP_HOLD_S = 10.0
STEP_PRE_S = 0.5
# programme -> the coordinate counts it has a form for, and what it holds there
PROGRAMMES = {
    "harmonic": {1: "25 sines"},
    "random": {
        1: "one RPC-like record (--n, --duration, --seed)",
        3: "random on all axes, independent and correlated",
    },
    "step": {1: "one held step (--step-mm, --hold)"},
    "papers": {
        1: "harmonic + random n=1 40 s + random n=1.5 20 s (seed+1) + 4 mm step",
        3: "random n = 1 and 1.5, independent and correlated, and the coupled sine sets",
    },
    "combined": {
        3: "each coordinate held at +- n x its n = 1 peak while each other one is swept "
        "(10 s each or --duration): 12 records",
    },
}
# what a three-axis identification uses of the papers' programme at n = 1 (``bushenv
# reproduce --planar-identification``): the random records and the coupled sets, or the random
IDENTIFICATIONS = {
    "programme": "random and the coupled sine sets at n = 1",
    "random": "random n = 1 only (as seed 000)",
}


class ProgrammeError(BadInput):
    """A programme that does not exist, or has no form for this many coordinates."""


@dataclass(frozen=True, eq=False)
class ProgrammeItem:
    """One test of a programme: a ``name`` (the record's file stem), displacement ``x`` (T,)
    in m, or (T, C) in SI per coordinate, sampled at ``dt`` s."""

    name: str
    x: np.ndarray
    dt: float


def _mm(value_m: float) -> str:
    return f"{value_m * 1e3:g}mm"


def harmonic_programme(
    dt: float = PAPER_DT,
    frequencies_hz: Sequence[float] = HARMONIC_FREQUENCIES_HZ,
    amplitudes_m: Sequence[float] = HARMONIC_AMPLITUDES_M,
    duration_s: float = HARMONIC_DURATION_S,
) -> list[ProgrammeItem]:
    """The harmonic tests of seed 001 §3.2.1: every frequency x every amplitude, 10 s each.

    Items are ordered by frequency then amplitude and named ``sine_10hz_2mm``; all share one
    length, so ``run_programme`` simulates them as one batch.
    """
    items = []
    for f in frequencies_hz:
        ex.check_frequency(f)
        for a in amplitudes_m:
            items.append(ProgrammeItem(f"sine_{f:g}hz_{_mm(a)}", ex.sine(f, a, duration_s, dt), dt))
    return items


def random_item(
    n_index: float, duration_s: float, seed: int, dt: float = PAPER_DT
) -> ProgrammeItem:
    """The RPC-like random drive with index n (peak n * 2 mm), named ``random_n1_40s_seed0``."""
    x = ex.random_rpc(n_index, duration_s, dt, seed)
    return ProgrammeItem(f"random_n{n_index:g}_{duration_s:g}s_seed{seed}", x, dt)


def step_item(
    size_m: float = STEP_SIZE_M,
    hold_s: float = STEP_HOLD_S,
    dt: float = PAPER_DT,
    pre_s: float = STEP_PRE_S,
    rise_s: float | None = None,
) -> ProgrammeItem:
    """The step test of seed 000 §5.2: ``pre_s`` at rest, a step of ``size_m``, held ``hold_s``.

    ``rise_s=None``: an ideal one-sample step when the machine can move that fast at ``dt``
    (4 mm at 204.8 Hz: 0.82 m/s), else the shortest half-cosine rise within
    ``MAX_VELOCITY_M_PER_S`` (its peak speed is pi/2 * size / rise).
    """
    if rise_s is None:
        rise_s = 0.0
        if abs(size_m) / dt > ex.MAX_VELOCITY_M_PER_S:
            rise_s = 0.5 * np.pi * abs(size_m) / ex.MAX_VELOCITY_M_PER_S * (1 + 1e-6)
    x = ex.step_hold(size_m, hold_s, dt, pre_s=pre_s, rise_s=rise_s)
    return ProgrammeItem(f"step_{_mm(size_m)}_hold{hold_s:g}s", x, dt)


def papers_programme(dt: float = PAPER_DT, seed: int = 0) -> list[ProgrammeItem]:
    """Everything the papers measured: harmonic grid, identification (n = 1, 40 s, ``seed``),
    verification (n = 1.5, 20 s, ``seed + 1``) and the 4 mm step held 10 s."""
    return [
        *harmonic_programme(dt),
        random_item(IDENTIFICATION_N, IDENTIFICATION_DURATION_S, seed, dt),
        random_item(VERIFICATION_N, VERIFICATION_DURATION_S, seed + 1, dt),
        step_item(dt=dt),
    ]


def default_random_duration(n_index: float) -> float:
    """40 s for identification-size drives (n <= 1), 20 s for larger (verification) ones."""
    return IDENTIFICATION_DURATION_S if n_index <= IDENTIFICATION_N else VERIFICATION_DURATION_S


def random_motions(n_index: float, duration_s: float, dt: float, seed: int) -> list[ProgrammeItem]:
    """Random on all three in-plane coordinates at ``n_index``, independent and correlated."""
    tail = f"n{n_index:g}_{duration_s:g}s_seed{seed}"
    return [
        ProgrammeItem(f"random_{kind}_{tail}", drive(n_index, duration_s, dt, seed), dt)
        for kind, drive in (("independent", random_independent), ("correlated", random_correlated))
    ]


def papers_motions(dt: float, seed: int = 0) -> list[ProgrammeItem]:
    """The papers' programme in three coordinates (see the module docstring)."""
    verify, identify = (
        [ProgrammeItem(name, q, dt) for name, q in coupled_sets(n, dt)] for n in (N_VERIFY, 1.0)
    )
    # each addition last, so the records before keep their noise seeds (and their files)
    return [
        *random_motions(1.0, 40.0, dt, seed),
        *random_motions(N_VERIFY, 20.0, dt, seed + 1),
        *verify[:2],
        *identify[:2],
        verify[2],
        identify[2],
    ]


def programme_items(
    kind: str,
    n_coords: int,
    dt: float,
    seed: int = 0,
    n_index: float = IDENTIFICATION_N,
    duration_s: float | None = None,
    step_m: float = STEP_SIZE_M,
    hold_s: float = STEP_HOLD_S,
) -> list[ProgrammeItem]:
    """The items of programme ``kind`` for a bushing of ``n_coords`` coordinates;
    ``ProgrammeError`` naming the programmes there are when it has no form for that many."""
    forms = PROGRAMMES.get(kind)
    if forms is None or n_coords not in forms:
        have = [k for k, v in PROGRAMMES.items() if n_coords in v]
        what = "no such programme" if forms is None else f"no form for {n_coords} coordinate(s)"
        raise ProgrammeError(
            f"programme {kind!r}: {what}; for {n_coords} coordinate(s) choose "
            + "; ".join(f"{k} ({PROGRAMMES[k][n_coords]})" for k in have)
        )
    if duration_s is None and kind in ("random", "combined"):
        duration_s = default_random_duration(n_index) if kind == "random" else 10.0
    builders = {
        ("harmonic", 1): lambda: harmonic_programme(dt),
        ("random", 1): lambda: [random_item(n_index, duration_s, seed, dt)],
        ("step", 1): lambda: [step_item(step_m, hold_s, dt)],
        ("papers", 1): lambda: papers_programme(dt, seed=seed),
        ("random", 3): lambda: random_motions(n_index, duration_s, dt, seed),
        ("papers", 3): lambda: papers_motions(dt, seed),
        ("combined", 3): lambda: [
            ProgrammeItem(name, q, dt) for name, q in held_sweeps(n_index, dt, duration_s)
        ],
    }
    return builders[kind, n_coords]()
