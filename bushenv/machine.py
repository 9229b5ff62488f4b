"""The virtual test machine: runs the papers' test programme on any bushing model.

A model (``bushenv.models.BushingModel``; the reference specimen is ``"rubber"``) is driven by
prescribed displacement like the one-axis MTS machine of seed 001 §3.1, within the limits of
seed 002 Table 1 (``bushenv.excitation``: +-12.5 mm stroke, 1.26 m/s, 25 kN dynamic force). The
force is the model's free-run response (``model.simulate``; velocity by central differences,
as for any record that holds displacement only). Every run gives a ``bushenv.records.Record``.

The programme (seed 001 §3.2, seed 000 §5.2):

| test           | function               | excitation                                      |
|----------------|------------------------|-------------------------------------------------|
| harmonic       | ``harmonic_programme`` | sines 1, 5, 10, 15, 20 Hz x 0.5-4 mm, 10 s each |
| identification | ``random_test``        | RPC-like random, n = 1 (2 mm peak), 40 s        |
| verification   | ``random_test``        | RPC-like random, n = 1.5 (3 mm peak), 20 s      |
| step           | ``step_test``          | 4 mm step after 0.5 s at rest, held 10 s        |

Durations: the papers' random records lasted 8.22 s (identification) and 6.44 s (verification)
(seed 002 §5); we default to 40 s and 20 s so that identification sees every part of the
spectrum many times (40 s at 204.8 Hz is 8192 samples) and verification is still long enough
for the thermal and relaxation memory of the reference bushing to show. The verification drive
uses a different seed from the identification drive (``seed + 1``), as the papers' two records
were different drives.

``run`` refuses (``MachineError``) an excitation the machine cannot drive and flags
(``Record.info["force_limit_exceeded"]`` and a ``MachineWarning``) a force above the 25 kN
dynamic capacity. ``run_programme`` simulates items of equal length together as one (T, B)
batch.

Command line: ``bushenv measure`` (see ``EXAMPLE``) writes one CSV per programme item.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bushenv import excitation as ex
from bushenv.errors import BadInput
from bushenv.models.base import DT_TOLERANCE, PAPER_DT, BushingModel
from bushenv.records import Record

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
PROGRAMMES = ("harmonic", "random", "step", "papers")


class MachineError(BadInput):
    """The machine cannot run this excitation or programme; the message says why."""


class MachineWarning(UserWarning):
    """A run exceeded the machine's force capacity (the record is kept, flagged)."""


@dataclass(frozen=True, eq=False)
class ProgrammeItem:
    """One test of a programme: a ``name`` (the record's file stem), displacement ``x`` (T,)
    in m sampled at ``dt`` s."""

    name: str
    x: np.ndarray
    dt: float


# ----- programmes ------------------------------------------------------------------------------
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


# ----- running ---------------------------------------------------------------------------------
def check_excitation(x: np.ndarray, dt: float, name: str = "excitation") -> np.ndarray:
    """``x`` as a float (T,) or (T, B) array the machine can drive, else ``MachineError``."""
    a = np.asarray(x, dtype=np.float64)
    if a.ndim not in (1, 2) or a.shape[0] < 2:
        raise MachineError(
            f"{name}: expected displacement of shape (T,) with T >= 2, got {a.shape}"
        )
    ok, reason = ex.within_limits(a, dt)
    if not ok:
        raise MachineError(
            f"{name}: outside the test machine's limits: {reason} "
            "(bushenv.excitation.clip_to_limits gives the nearest drivable signal)"
        )
    return a


def _record(name: str, x: np.ndarray, force: np.ndarray, dt: float) -> Record:
    peak = float(np.max(np.abs(force))) if np.all(np.isfinite(force)) else float("inf")
    over = peak > ex.MAX_DYNAMIC_FORCE_N
    info = {
        "max_abs_force_n": peak,
        "force_limit_exceeded": bool(over),
        "force_finite": bool(np.all(np.isfinite(force))),
    }
    if over:
        warnings.warn(
            MachineWarning(
                f"{name}: force reaches {peak:.4g} N, beyond the machine's "
                f"{ex.MAX_DYNAMIC_FORCE_N / 1e3:g} kN dynamic capacity"
            ),
            stacklevel=3,
        )
    return Record.from_arrays(x, force, dt, name=name, info=info)


def run(model: BushingModel, x: np.ndarray, name: str = "excitation") -> Record:
    """Drive ``model`` with displacement ``x`` (T,) in m at ``model.dt``; returns the Record.

    Refuses (``MachineError``) anything outside the machine's stroke or velocity; flags a force
    above 25 kN in ``record.info`` and with a ``MachineWarning``.
    """
    a = check_excitation(x, model.dt, name)
    if a.ndim != 1:
        raise MachineError(f"{name}: run takes one profile (T,); use run_programme for several")
    force = model.simulate(a)
    return _record(name, a, force, model.dt)


def run_programme(
    model: BushingModel, items: Sequence[ProgrammeItem], progress=None
) -> list[Record]:
    """Run every item on ``model``; items of equal length go through ``simulate`` as one (T, B)
    batch. Returns records in the order of ``items``. ``progress(message)`` is called per batch.

    Every item is checked against the machine limits and ``model.dt`` before anything runs.
    """
    for item in items:
        if abs(item.dt - model.dt) > DT_TOLERANCE * model.dt:
            raise MachineError(
                f"{item.name}: sampled at dt={item.dt:.6g} s but the model runs at "
                f"dt={model.dt:.6g} s"
            )
        check_excitation(item.x, model.dt, item.name)
        if np.ndim(item.x) != 1:
            raise MachineError(f"{item.name}: expected (T,), got {np.shape(item.x)}")
    groups: dict[int, list[int]] = {}
    for i, item in enumerate(items):
        groups.setdefault(len(item.x), []).append(i)
    records: list[Record | None] = [None] * len(items)
    done = 0
    for length, members in groups.items():
        batch = np.stack([np.asarray(items[i].x, dtype=np.float64) for i in members], axis=1)
        forces = model.simulate(batch)
        for column, i in enumerate(members):
            records[i] = _record(items[i].name, batch[:, column], forces[:, column], model.dt)
        done += len(members)
        if progress is not None:
            progress(
                f"simulated {len(members)} item(s) of {length} samples ({done}/{len(items)} done)"
            )
    return records  # type: ignore[return-value]


def harmonic_test(model: BushingModel, **programme_kwargs) -> list[Record]:
    """Run ``harmonic_programme(model.dt, **programme_kwargs)`` on ``model``: 25 records."""
    return run_programme(model, harmonic_programme(model.dt, **programme_kwargs))


def random_test(
    model: BushingModel,
    n_index: float = IDENTIFICATION_N,
    duration_s: float | None = None,
    seed: int = 0,
) -> Record:
    """One RPC-like random record at index ``n_index`` (n = 1 identifies, n = 1.5 verifies).

    ``duration_s`` defaults to 40 s for n <= 1 (identification) and 20 s above (verification).
    """
    if duration_s is None:
        duration_s = default_random_duration(n_index)
    item = random_item(n_index, duration_s, seed, model.dt)
    return run(model, item.x, name=item.name)


def default_random_duration(n_index: float) -> float:
    """40 s for identification-size drives (n <= 1), 20 s for larger (verification) ones."""
    return IDENTIFICATION_DURATION_S if n_index <= IDENTIFICATION_N else VERIFICATION_DURATION_S


def step_test(
    model: BushingModel,
    size_m: float = STEP_SIZE_M,
    hold_s: float = STEP_HOLD_S,
    pre_s: float = STEP_PRE_S,
    rise_s: float | None = None,
) -> Record:
    """The step test: ``pre_s`` at rest, a ``size_m`` step, held ``hold_s`` (default 4 mm, 10 s).

    ``rise_s`` as in ``step_item`` (None: ideal step if drivable, else the fastest allowed).
    """
    item = step_item(size_m, hold_s, model.dt, pre_s, rise_s)
    return run(model, item.x, name=item.name)


# ----- command line ----------------------------------------------------------------------------
