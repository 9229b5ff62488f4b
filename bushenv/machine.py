"""The virtual test machine: runs a programme on any bushing model, of any number of coordinates.

A model (``bushenv.models.BushingModel``; the reference specimen is ``"rubber"``) is driven by
prescribed displacement like the one-axis MTS machine of seed 001 §3.1, within the limits of
seed 002 Table 1 (``bushenv.excitation``: +-12.5 mm stroke, 1.26 m/s, 25 kN dynamic force; on
a bushing of several coordinates the limits hold for each translational one, a rotation has
none). The force is the model's free-run response (``model.simulate``; velocity by central
differences, as for any record that holds displacement only). Every run gives a
``bushenv.records.Record``; the programmes are ``bushenv.programmes``.

``run`` refuses (``MachineError``) an excitation the machine cannot drive and flags
(``Record.info["force_limit_exceeded"]`` and a ``MachineWarning``) a force above the 25 kN
dynamic capacity. ``run_programme`` simulates items of equal length together as one batch,
or, given a factory of models, each item on a fresh model of its own (the reference's load
cell then measures each record with its own noise seed, ``reference_for``).

Command line: ``bushenv measure`` writes one CSV per programme item.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence

import numpy as np

from bushenv import excitation as ex
from bushenv.errors import BadInput
from bushenv.models.base import DT_TOLERANCE, BushingModel
from bushenv.programmes import (
    IDENTIFICATION_N,
    STEP_HOLD_S,
    STEP_PRE_S,
    STEP_SIZE_M,
    ProgrammeItem,
    default_random_duration,
    harmonic_programme,
    random_item,
    step_item,
)
from bushenv.records import Record


class MachineError(BadInput):
    """The machine cannot run this excitation or programme; the message says why."""


class MachineWarning(UserWarning):
    """A run exceeded the machine's force capacity (the record is kept, flagged)."""


def check_excitation(
    x: np.ndarray, dt: float, name: str = "excitation", units: Sequence[str] = ("m",)
) -> np.ndarray:
    """``x`` as a float (T,) or (T, B) array the machine can drive, or (T, C) over the
    coordinates of ``units`` (the stroke and velocity limits hold for each one in m), else
    ``MachineError``."""
    a = np.asarray(x, dtype=np.float64)
    c = len(units)
    if a.ndim not in ((1, 2) if c == 1 else (2,)) or a.shape[0] < 2:
        want = "(T,)" if c == 1 else f"(T, {c})"
        raise MachineError(
            f"{name}: expected displacement of shape {want} with T >= 2, got {a.shape}"
        )
    if c > 1 and a.shape[1] != c:
        raise MachineError(f"{name}: expected (T, {c}) for {c} coordinates, got {a.shape}")
    moved = a if c == 1 else a[:, [u == "m" for u in units]]
    ok, reason = ex.within_limits(moved, dt)
    if not ok:
        raise MachineError(
            f"{name}: outside the test machine's limits: {reason} "
            "(bushenv.excitation.clip_to_limits gives the nearest drivable signal)"
        )
    return a


def _record(
    name: str, x: np.ndarray, force: np.ndarray, dt: float, force_units: Sequence[str] = ("N",)
) -> Record:
    finite = bool(np.all(np.isfinite(force)))
    f = force.reshape(len(force), -1)
    newtons = f[:, [u == "N" for u in force_units]]
    peak = float(np.max(np.abs(newtons))) if finite and newtons.size else float("inf")
    over = peak > ex.MAX_DYNAMIC_FORCE_N
    info = {
        "max_abs_force_n": peak if finite else float("inf"),
        "force_limit_exceeded": bool(over),
        "force_finite": finite,
    }
    if f.shape[1] > 1:  # every coordinate's, in its own unit (N or N m)
        info["max_abs_force"] = np.abs(f).max(axis=0).tolist() if finite else None
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
    """Drive ``model`` with displacement ``x`` (T,) in m, or (T, C) over its coordinates, at
    ``model.dt``; returns the Record.

    Refuses (``MachineError``) anything outside the machine's stroke or velocity; flags a force
    above 25 kN in ``record.info`` and with a ``MachineWarning``.
    """
    a = check_excitation(x, model.dt, name, model.units)
    if model.n_coords == 1 and a.ndim != 1:
        raise MachineError(f"{name}: run takes one profile (T,); use run_programme for several")
    force = model.simulate(a)
    return _record(name, a, force, model.dt, model.force_units)


ModelSource = BushingModel | Callable[[int], BushingModel]


def run_programme(
    model: ModelSource, items: Sequence[ProgrammeItem], progress=None
) -> list[Record]:
    """Run every item; returns records in the order of ``items``. ``progress(message)`` is
    called per batch (per item with a factory).

    ``model``: one model, through whose ``simulate`` items of equal length go as one batch
    ((T, B), or (T, B, C) over C coordinates); or a factory ``model(k)`` of a fresh model for
    item k (``reference_for``: each record measured with its own noise). Every item is checked
    against the machine limits and the model's dt before anything runs.
    """
    models = [model(k) for k in range(len(items))] if callable(model) else None
    for k, item in enumerate(items):
        m = models[k] if models is not None else model
        if abs(item.dt - m.dt) > DT_TOLERANCE * m.dt:
            raise MachineError(
                f"{item.name}: sampled at dt={item.dt:.6g} s but the model runs at dt={m.dt:.6g} s"
            )
        check_excitation(item.x, m.dt, item.name, m.units)
        if m.n_coords == 1 and np.ndim(item.x) != 1:
            raise MachineError(f"{item.name}: expected (T,), got {np.shape(item.x)}")
    if models is not None:
        pairs = enumerate(zip(models, items, strict=True))
        return [_run_one(m, item, k, len(items), progress) for k, (m, item) in pairs]
    groups: dict[int, list[int]] = {}
    for i, item in enumerate(items):
        groups.setdefault(len(item.x), []).append(i)
    records: list[Record | None] = [None] * len(items)
    done = 0
    for length, members in groups.items():
        batch = np.stack([np.asarray(items[i].x, dtype=np.float64) for i in members], axis=1)
        forces = model.simulate(batch)
        for column, i in enumerate(members):
            records[i] = _record(
                items[i].name, batch[:, column], forces[:, column], model.dt, model.force_units
            )
        done += len(members)
        if progress is not None:
            progress(
                f"simulated {len(members)} item(s) of {length} samples ({done}/{len(items)} done)"
            )
    return records  # type: ignore[return-value]


def _run_one(model: BushingModel, item: ProgrammeItem, k: int, n: int, progress) -> Record:
    """One item on its own model, from rest."""
    x = np.asarray(item.x, dtype=np.float64)
    record = _record(item.name, x, model.simulate(x), model.dt, model.force_units)
    if progress is not None:
        progress(f"simulated [{k + 1}/{n}] {item.name}: {len(x)} samples")
    return record


def reference_for(
    name: str, n_coords: int, seed: int, dt: float, axis: str = "axial"
) -> Callable[[int], BushingModel]:
    """Registered model ``name`` of ``n_coords`` coordinates with its measurement chain, noise
    seed ``1000 * seed + k`` for record k, so no two records share their noise."""
    from bushenv.models import get_model

    def model_for(k: int) -> BushingModel:
        noise = {"seed": 1000 * seed + k}
        return get_model(name, axis=axis, dt=dt, coords=n_coords, preset=noise)

    return model_for


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
