"""The diagnosis over C coordinates: which coordinate carries a baseline's gap, which effect
closes it there, how far.

Records are any objects with ``.time`` (T,) s, ``.q`` (T, C) and ``.f`` (T, C) in the
coordinates' SI units (three-axis: m, m, rad and N, N, N m) and ``.dt`` s, such as
``bushenv.records.Record``. The steps:

1. **Baseline**: the linear model over C coordinates, ``f = K q + C v`` (C x C matrices, the
   ``linear`` form of ``bushenv.models.MODELS`` for C), identified on the TRAIN records.
2. **Per coordinate i**, the one-axis engine (``fit.diagnose``) runs unchanged on the record
   ``(q_i, f_i - sum_{j != i} (K_ij q_j + C_ij v_j))``: the coordinate's force less the
   baseline's cross-coordinate terms, which stay fixed. The engine's own linear baseline then
   refits the diagonal ``K_ii, C_ii`` with every candidate, as for one axis (k, c >= 0, every
   record used or held out), so the candidates take the coordinate's own deflection. A record
   in which the coordinate does not move (held at exactly one value) is left out of that
   coordinate's diagnosis; a coordinate no TRAIN or no TEST record moves is not diagnosed.
3. **Coupling** (``coupling.py``): terms ``q_i q_j^2`` of the other coordinates; named where
   the engine finds a gap clear of the noise that no candidate closes, or where they leave
   less than ``COUPLING_BEATS`` of the gap the named candidate leaves.
4. **Which coordinate** (``coordinate_answer.py``): each coordinate's gap on its measured
   force ranks the coordinates; the answer is the coordinate carrying a gap (the engine's
   answer there is not ``none``) with the largest gap above the noise, and its effect.

Why the candidates see one coordinate only: every candidate is a one-axis physical form, and
an effect that is coupled in the specimen (a vector friction's yield surface, relaxation of a
coupled elastic force) shows on each coordinate as that coordinate's own effect, only less
exact; the linear cross-coordinate terms are the baseline's, the cubic ones the coupling
test's (studies/2026-11-diagnose-three-axis).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from bushenv.diagnose import halves
from bushenv.diagnose.coordinate_answer import coordinate_result
from bushenv.diagnose.coupling import COUPLING_BEATS, COUPLING_MIN, coupling_test
from bushenv.diagnose.errors import DiagnoseError
from bushenv.diagnose.inputs import LINEAR, MIN_SAMPLES, Progress, names_of

RATE_RTOL = 1e-6  # records whose sample times differ by less share one rate


@dataclass(frozen=True)
class CoordinateView:
    """One coordinate of a record as the one-axis engine takes it: (T,) arrays, s, SI."""

    time: np.ndarray
    displacement: np.ndarray
    force: np.ndarray
    dt: float
    name: str


@dataclass(frozen=True)
class Setup:
    """What every coordinate's diagnosis shares: the coordinates, the baseline, the records.

    ``records``: name -> record, TRAIN first; ``roles``: name -> "train" / "test"; ``k``, ``c``:
    the baseline's (C, C) matrices; ``cross``: name -> (T, C) its cross-coordinate terms.
    """

    coords: tuple[str, ...]
    units: tuple[str, ...]
    force_units: tuple[str, ...]
    k: np.ndarray
    c: np.ndarray
    records: dict[str, Any]
    roles: dict[str, str]
    cross: dict[str, np.ndarray]

    def q(self, name: str) -> np.ndarray:
        return np.asarray(self.records[name].q, float)

    def f(self, name: str) -> np.ndarray:
        return np.asarray(self.records[name].f, float)

    def dt(self, name: str) -> float:
        return float(self.records[name].dt)

    def view(self, name: str, i: int) -> CoordinateView:
        """Coordinate ``i`` of record ``name``, its force less the cross-coordinate terms."""
        rec = self.records[name]
        force = self.f(name)[:, i] - self.cross[name][:, i]
        time = np.asarray(rec.time, float)
        return CoordinateView(time, self.q(name)[:, i], force, self.dt(name), name)

    def baseline(self, name: str) -> np.ndarray:
        """(T, C): the linear baseline's whole prediction, K q + C v."""
        from bushenv.models.base import velocity_of

        q = self.q(name)
        return q @ self.k.T + velocity_of(q, self.dt(name)) @ self.c.T

    def moves(self, name: str, i: int) -> bool:
        """Whether coordinate ``i`` moves in record ``name`` (not held at one value) under a
        force: what the one-axis diagnosis needs of a record."""
        return bool(np.ptp(self.q(name)[:, i]) > 0 and np.any(self.view(name, i).force != 0))


def add_halves(setup: Setup, d: dict[str, Any]) -> None:
    """The halves a coordinate's diagnosis judged a record on (``halves.py``) become records
    of ``setup``: its q, f, time and cross terms cut the same way."""
    used = {n for f in d["records"]["folds"] for n in f["identified_on"] + f["judged"]}
    for n in sorted(used - set(setup.records)):
        parent, i = halves.parent_of(n) or (None, 0)
        if parent not in setup.records:
            continue
        rec = setup.records[parent]
        a, b = halves.bounds(len(rec.time))[i]
        setup.records[n] = SimpleNamespace(
            time=np.asarray(rec.time, float)[a:b], q=setup.q(parent)[a:b],
            f=setup.f(parent)[a:b], dt=setup.dt(parent),
        )  # fmt: skip
        setup.roles[n] = setup.roles[parent]
        setup.cross[n] = setup.cross[parent][a:b]


def coordinate_count(rec: Any) -> int:
    """C of a record: 1 for a one-axis record (``.displacement``), q's last axis otherwise."""
    if hasattr(rec, "q") and hasattr(rec, "f"):
        q = np.asarray(rec.q)
        return int(q.shape[1]) if q.ndim == 2 else 1
    return 1


def coordinates_of(rec: Any, c: int) -> tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]:
    """(names, displacement units, force units) of the C coordinates: the record's own
    ``coords`` / ``units`` / ``force_units`` if it has them, the three-axis bushing's for C = 3."""
    from bushenv.models.planar_base import COORDS, FORCE_UNITS, UNITS

    if c == 3:
        default = (COORDS, UNITS, FORCE_UNITS)
    else:
        default = (tuple(f"q{i + 1}" for i in range(c)), ("m",) * c, ("N",) * c)
    attrs = ("coords", "units", "force_units")
    names, units, force_units = (
        tuple(getattr(rec, a, None) or d) for a, d in zip(attrs, default, strict=True)
    )
    return names, units, force_units


def check_coordinate_records(trains: list, tests: list, t_names: list, names: list) -> int:
    """C shared by every record; ``DiagnoseError`` naming a record of another count or shape."""
    labelled = [(f"TRAIN {n}", r) for n, r in zip(t_names, trains, strict=True)]
    labelled += [(f"TEST {n}", r) for n, r in zip(names, tests, strict=True)]
    first, c = labelled[0][0], coordinate_count(labelled[0][1])
    for label, rec in labelled:
        if coordinate_count(rec) != c:
            raise DiagnoseError(
                f"{label} has {coordinate_count(rec)} coordinate(s) but {first} has {c}: one "
                "diagnosis takes records of one kind (all one-axis or all three-axis)"
            )
    if len(set(t_names + names)) != len(labelled):
        raise DiagnoseError(
            f"records need distinct names (file stems), got TRAIN {t_names} and TEST {names}"
        )
    dt0 = float(trains[0].dt)
    for label, rec in labelled:
        q, f = np.asarray(rec.q, float), np.asarray(rec.f, float)
        n = np.size(rec.time)
        if q.shape != (n, c) or f.shape != (n, c):
            raise DiagnoseError(
                f"{label}: q and f must be ({n}, {c}) arrays, got {q.shape} and {f.shape}"
            )
        if n < MIN_SAMPLES:
            raise DiagnoseError(f"{label}: {n} samples; the diagnosis needs at least {MIN_SAMPLES}")
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(f))):
            raise DiagnoseError(f"{label}: q or f holds NaN or inf")
        if not (np.isfinite(rec.dt) and rec.dt > 0):
            raise DiagnoseError(f"{label}: sample time {rec.dt!r} is not a positive number")
        if abs(float(rec.dt) - dt0) > RATE_RTOL * dt0:
            raise DiagnoseError(
                f"{label}: sampled at {1 / rec.dt:.6g} Hz but {first} at {1 / dt0:.6g} Hz; the "
                f"{c}-coordinate baseline is identified at one rate: resample the records to "
                "one rate first"
            )
    return c


def linear_baseline(trains: list, c: int, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(K, C) of the ``linear`` form over ``c`` coordinates identified on ``trains``: least
    squares of f on K q + C v over every TRAIN sample (v by ``velocity_of``, the project's
    convention), as that form's own identification does; computed here so the diagnosis does
    not depend on how the identification functions are called."""
    from bushenv.models import MODELS, ModelError
    from bushenv.models.base import velocity_of

    try:
        MODELS[LINEAR].form(c)
    except ModelError:
        have = ", ".join(str(n) for n in MODELS[LINEAR].coordinate_counts())
        raise DiagnoseError(
            f"records of {c} coordinates: the baseline is the linear model over them, which "
            f"bushenv.models.MODELS has for {have} coordinate(s) only (register its form for "
            f"{c})"
        ) from None
    q = np.concatenate([np.asarray(r.q, float) for r in trains])
    v = np.concatenate([velocity_of(np.asarray(r.q, float), dt) for r in trains])
    f = np.concatenate([np.asarray(r.f, float) for r in trains])
    a = np.hstack([q, v])
    scale = np.maximum(np.abs(a).max(axis=0), 1e-300)  # metres and radians differ by orders
    coef, *_ = np.linalg.lstsq(a / scale, f, rcond=None)
    coef = (coef / scale[:, None]).T  # (c, 2c): force row i = [K_i, C_i]
    return coef[:, :c], coef[:, c:]


def cross_terms(q: np.ndarray, dt: float, k: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(T, C): per coordinate i, sum over j != i of K_ij q_j + C_ij v_j (v by ``velocity_of``)."""
    from bushenv.models.base import velocity_of

    off_k, off_c = k - np.diag(np.diag(k)), c - np.diag(np.diag(c))
    return q @ off_k.T + velocity_of(q, dt) @ off_c.T


# ----- the diagnosis ---------------------------------------------------------------------------
def diagnose_coordinates(
    train: Any,
    tests: Sequence[Any],
    baseline: str = LINEAR,
    progress: Progress | None = None,
    seed: int = 0,
    test_names: Sequence[str] | None = None,
    *,
    cross: bool | None = None,
    effects: Sequence[str] | None = None,
    train_names: Sequence[str] | None = None,
    engine: Callable[..., dict[str, Any]],
    run_order: Sequence[tuple[str, Any]] | None = None,
) -> dict[str, Any]:
    """Which coordinate carries the gap, which effect closes it there, how far (module doc).
    ``engine`` is the one-axis diagnosis run on each coordinate (``bushenv.diagnose.fit.
    diagnose``, which hands records of several coordinates here).

    Returns a JSON-ready dict (docs/diagnose.md, "Three-axis records") plus ``"predictions"``
    (per judged record: ``time`` (T,), ``q``, ``force_measured``, ``force_baseline``,
    ``force_augmented`` (T, C)) and ``"diagnoses"``: per diagnosed coordinate, the one-axis
    engine's whole result on that coordinate (with its own predictions).
    """
    say = progress or (lambda msg: None)
    trains = list(train) if isinstance(train, list | tuple) else [train]
    if not trains:
        raise DiagnoseError("no TRAIN record given")
    if not tests:
        raise DiagnoseError("no TEST record given; the gap is judged on held-out records only")
    t_names = names_of(trains, train_names, "train")
    names = names_of(tests, test_names, "test")
    c = check_coordinate_records(trains, list(tests), t_names, names)
    if baseline != LINEAR:
        raise DiagnoseError(
            f"baseline {baseline!r}: records of {c} coordinates are diagnosed against the linear "
            f"{c}-coordinate baseline (K and C matrices); --baseline {baseline} takes one-axis "
            "records"
        )
    coords, units, force_units = coordinates_of(trains[0], c)
    dt = float(trains[0].dt)
    say(f"identifying the linear {c}-coordinate baseline on TRAIN ({len(trains)} record(s))")
    k, cm = linear_baseline(trains, c, dt)
    records = dict(zip(t_names, trains, strict=True)) | dict(zip(names, tests, strict=True))
    setup = Setup(
        coords,
        units,
        force_units,
        k,
        cm,
        records,
        {n: ("train" if n in t_names else "test") for n in records},
        {n: cross_terms(np.asarray(r.q, float), dt, k, cm) for n, r in records.items()},
    )
    diagnoses: dict[str, dict] = {}
    couplings: dict[str, dict] = {}
    left_out: dict[str, list[str]] = {}
    for i, name in enumerate(coords):
        tr = [n for n in t_names if setup.moves(n, i)]
        te = [n for n in names if setup.moves(n, i)]
        left_out[name] = [n for n in records if n not in tr + te]
        if not tr or not te:
            say(f"coordinate {name}: moves in no {'TRAIN' if not tr else 'TEST'} record; not "
                "diagnosed")  # fmt: skip
            continue
        say(f"coordinate {name} ({i + 1}/{c})")
        d = engine(
            [setup.view(n, i) for n in tr],
            [setup.view(n, i) for n in te],
            progress=lambda msg, name=name: say(f"{name}: {msg}"),
            seed=seed,
            test_names=te,
            train_names=tr,
            cross=cross,
            effects=effects,
            run_order=run_order,
        )
        d["coordinate"] = name
        add_halves(setup, d)
        diagnoses[name] = d
        couplings[name] = _coupling(setup, i, d)
        say(f"{name}: coupling terms close {100 * couplings[name]['closes']:.0f} % beyond its own")
    if not diagnoses:
        raise DiagnoseError(
            "no coordinate moves in both a TRAIN and a TEST record: nothing to diagnose"
        )
    return coordinate_result(setup, diagnoses, couplings, left_out)


def _coupling(setup: Setup, i: int, d: dict[str, Any]) -> dict[str, Any]:
    """The coupling test on coordinate ``i`` (``coupling.py``), on the engine's folds; named
    where the one-axis diagnosis found a gap clear of the noise that no candidate closes."""
    used = [n for f in d["records"]["folds"] for n in f["identified_on"] + f["judged"]]
    records = {
        n: {"q": setup.q(n), "force": setup.view(n, i).force, "dt": setup.dt(n)}
        for n in dict.fromkeys(used)
    }
    test = coupling_test(records, d["records"]["folds"], i, list(setup.coords), d["gap_noise"])
    leaves = d["effect"] == "outside_candidates" or (
        d["effect"] != "none" and test["gap_coupled"] < COUPLING_BEATS * d["gap_after"]
    )  # no candidate closes the gap, or the one named leaves far more than the coupling
    test["named"] = bool(
        leaves and test["closes"] >= COUPLING_MIN and test["gap_coupled"] < test["gap_null"]
    )
    return test
