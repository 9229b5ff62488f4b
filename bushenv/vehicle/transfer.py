"""The error-transfer map: what one small bushing error of each kind, on each coordinate of each
arm pivot, changes in HalfCar-v0 under the standard manoeuvres; the predictor built from it and
its check on error combinations it was not built from.

``run_transfer(config, progress)`` runs the reference car once per manoeuvre, then one car per
component error (4 pivots x 3 coordinates x 4 kinds, ``transfer_errors``) at the size
``config.size_pct`` (the map) and, for the second-order predictor, at minus that size, then the
held-out cases (every single error at other sizes, and combinations of several errors at
random sizes); it returns the report (plain values) and the ``TransferPredictor``
(``config.order``; the first order is judged beside it on the same runs). Vehicle outputs are
the comparison's (``compare.OUTPUTS``): dynamic wheel loads, roll, camber, track change, and
the ISO 2631-1 weighted accelerations of the body (vertical Wk, lateral Wd); a change is the
RMS of the difference history over the reference car's RMS (%), not stated where that RMS is
below the output's floor.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from bushenv.rigs.halfcar_params import POSITIONS, REFERENCE
from bushenv.vehicle.comfort import weighted_acceleration
from bushenv.vehicle.compare import AW_FLOOR_M_PER_S2, OUTPUTS
from bushenv.vehicle.manoeuvres import NAMES, Manoeuvre, standard_manoeuvres
from bushenv.vehicle.study import env_overrides
from bushenv.vehicle.transfer_car import SingleRun, single_car_run
from bushenv.vehicle.transfer_errors import (
    COORDS,
    KINDS,
    ErrorTerm,
    TransferInputError,
    calibrate,
    reference_rubber,
    scaled_rubber,
)
from bushenv.vehicle.transfer_predict import (
    TransferPredictor,
    basis,
    check_cells,
    gram_matrix,
    influence_rank,
    relative_pct,
)


class MapOutput(NamedTuple):
    """A vehicle output of the map: the car output it reads, an ISO 2631-1 weighting or None."""

    name: str
    title: str
    unit: str
    source: str
    weighting: str | None
    floor: float


_FLOOR = {o.name: o.floor for o in OUTPUTS}
MAP_OUTPUTS = (
    MapOutput("wheel_load", "wheel load", "N", "wheel_load", None, _FLOOR["wheel_load"]),
    MapOutput("roll", "roll", "rad", "roll", None, _FLOOR["roll"]),
    MapOutput("camber", "camber", "rad", "camber", None, _FLOOR["camber"]),
    MapOutput("track_change", "track change", "m", "track_change", None, _FLOOR["track_change"]),
    MapOutput("a_w_Wk", "vertical a_w (Wk)", "m/s^2", "vertical_accel", "Wk", AW_FLOOR_M_PER_S2),
    MapOutput("a_w_Wd", "lateral a_w (Wd)", "m/s^2", "lateral_accel", "Wd", AW_FLOOR_M_PER_S2),
)
COMPONENTS = tuple((p, c, k) for p in POSITIONS for c in COORDS for k in KINDS)
HELD_MULTIPLES = (2.0,)  # the single errors held out: these multiples of the map's size
COMBINED_SIZE = (0.5, 1.5)  # a combination's terms: |size| drawn in these multiples of it
# a relative error is judged where the measured change is at least this share of the
# component size (below it the car barely moved: 0.5 % of an output's RMS at a 10 % error)
LEAST_SHARE = 0.05


@dataclass(frozen=True)
class TransferConfig:
    """A campaign's settings (what the report's ``settings`` holds)."""

    dt_s: float
    size_pct: float = 10.0
    manoeuvres: tuple[str, ...] = NAMES
    duration_s: float | None = None
    seed: int = 0
    combinations: int = 16
    held_multiples: tuple[float, ...] = HELD_MULTIPLES
    order: int = 2  # the predictor: 1 from the +size runs, 2 also from the -size runs

    def check(self) -> None:
        if self.order not in (1, 2):
            raise TransferInputError(f"order must be 1 or 2, got {self.order!r}")
        if not (np.isfinite(self.size_pct) and 0 < self.size_pct <= 15):
            raise TransferInputError(
                f"size_pct must be in (0, 15] %, got {self.size_pct!r} (an understated "
                "relaxation or friction can err by ~19 % at most)"
            )
        if self.combinations < 0:
            raise TransferInputError(f"combinations must be >= 0, got {self.combinations}")
        for k in self.held_multiples:
            if not (np.isfinite(k) and k != 0 and abs(k * self.size_pct) <= 30):
                raise TransferInputError(f"held multiple {k!r}: non-zero, |k size| <= 30 %")
            if k == 1 or (k == -1 and self.order == 2):
                raise TransferInputError(f"held multiple {k!r}: the predictor is built on it")


def difference_histories(run: SingleRun, base: SingleRun, dt_s: float) -> list[np.ndarray]:
    """Per ``MAP_OUTPUTS`` entry the (n, k) difference of ``run`` against ``base`` over the steps
    both hold, weighted for the comfort outputs (the weighting is linear: the weighted
    difference is the difference of the weighted histories)."""
    n = min(run.steps, base.steps)
    out = []
    for o in MAP_OUTPUTS:
        d = run.outputs[o.source][:n] - base.outputs[o.source][:n]
        if o.weighting is not None:
            d = weighted_acceleration(d[:, 0], dt_s, o.weighting)[:, None] if n >= 2 else d
        out.append(d)
    return out


def baseline_rms(base: SingleRun, dt_s: float) -> np.ndarray:
    """(O,) the reference car's RMS of each map output (a_w for the comfort ones)."""
    zero = SingleRun(base.manoeuvre, base.steps, {k: 0 * v for k, v in base.outputs.items()},
                     base.deflection, "")  # fmt: skip
    return np.array([np.sqrt(np.mean(d**2)) for d in difference_histories(base, zero, dt_s)])


def pivot_table(terms: list[ErrorTerm], dt_s: float) -> dict[str, Any]:
    """HalfCar-v0's pivot table for ``terms``: each pivot the reference rubber with its terms'
    parameters scaled (each calibrated alone to its size), the others the reference."""
    seen: set[tuple[str, str, str]] = set()
    table: dict[str, Any] = {}
    for t in terms:
        if t.pivot not in POSITIONS:
            raise TransferInputError(f"pivot {t.pivot!r}; known: {', '.join(POSITIONS)}")
        if t.component in seen:
            raise TransferInputError(f"error {'/'.join(t.component)} given twice")
        seen.add(t.component)
        base = table.get(t.pivot) or reference_rubber(dt_s)
        factor = calibrate(t.kind, t.coord, float(t.size_pct), dt_s)
        table[t.pivot] = scaled_rubber(base, t.kind, t.coord, factor)
    return {p: table.get(p, REFERENCE) for p in POSITIONS}


def combinations(count: int, size_pct: float, seed: int) -> list[list[ErrorTerm]]:
    """``count`` held-out combinations drawn from ``seed``: even ones one (coordinate, kind)
    error in all four pivots (a model put in every pivot), odd ones 2-6 errors on random
    components; each term's size of random sign and |size| in ``COMBINED_SIZE`` x size_pct."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 39]))
    out = []
    for i in range(count):
        if i % 2 == 0:
            c, k = COORDS[rng.integers(3)], KINDS[rng.integers(4)]
            picked = [(p, c, k) for p in POSITIONS]
        else:
            n = int(rng.integers(2, 7))
            picked = [COMPONENTS[j] for j in rng.choice(len(COMPONENTS), n, replace=False)]
        sizes = rng.uniform(*COMBINED_SIZE, len(picked)) * rng.choice([-1.0, 1.0], len(picked))
        out.append([ErrorTerm(*comp, round(float(s) * size_pct, 2))
                    for comp, s in zip(picked, sizes, strict=True)])  # fmt: skip
    return out


class Campaign:
    """The runs of one campaign: the reference cars, then cars with errors (``measure``)."""

    def __init__(self, config: TransferConfig, progress: Any = None) -> None:
        config.check()
        self.config = config
        self.progress = progress
        self.manoeuvres: list[Manoeuvre] = standard_manoeuvres(
            config.dt_s, config.seed, config.manoeuvres, config.duration_s
        )
        self.overrides = env_overrides(self.manoeuvres)
        self.samples = sum(m.samples for m in self.manoeuvres)
        self.done = 0
        self.ended: list[dict[str, Any]] = []
        self.base = [self._run(m, REFERENCE, "reference") for m in self.manoeuvres]
        self.base_rms = np.array([baseline_rms(b, config.dt_s) for b in self.base])  # (M, O)
        self.floors = np.array([o.floor for o in MAP_OUTPUTS])

    def _run(self, m: Manoeuvre, pivots: Any, label: str) -> SingleRun:
        run = single_car_run(m, pivots, self.overrides)
        self.done += m.samples
        if run.end:
            self.ended.append({"case": label, "manoeuvre": m.name, "steps": run.steps,
                               "why": run.end})  # fmt: skip
        if self.progress is not None:
            self.progress.update(self.done, f"{label}: {m.name}")
        return run

    def measure(self, terms: list[ErrorTerm], label: str) -> list[list[np.ndarray]]:
        """Per manoeuvre, the ``difference_histories`` of the car with ``terms``."""
        table = pivot_table(terms, self.config.dt_s)
        return [
            difference_histories(self._run(m, table, label), b, self.config.dt_s)
            for m, b in zip(self.manoeuvres, self.base, strict=True)
        ]

    def pct(self, diffs: list[list[np.ndarray]]) -> np.ndarray:
        """(M, O) RMS change % of the reference car's RMS (NaN where not stated)."""
        rms = np.array([[np.sqrt(np.mean(d**2)) if d.size else np.nan for d in per]
                        for per in diffs])  # fmt: skip
        return relative_pct(rms, self.base_rms, self.floors)

    def in_car_component_pct(self, term: ErrorTerm) -> list[float]:
        """Per manoeuvre, the term's component error in the car: its law and the reference's
        driven open loop by the reference car's motion of that pivot, RMS force error ratio
        on the erring coordinate (%); the bench size was measured on bench motion."""
        dt = self.config.dt_s
        i, c = POSITIONS.index(term.pivot), COORDS.index(term.coord)
        law = pivot_table([term], dt)[term.pivot]
        ref = reference_rubber(dt)
        out = []
        for b in self.base:
            q = np.ascontiguousarray(b.deflection[:, i, :])
            f_r, f_e = ref.simulate(q)[:, c], law.simulate(q)[:, c]
            power = float(np.mean(f_r**2))  # nil where the pivot has not moved yet
            err = float(np.mean((f_e - f_r) ** 2))
            out.append(100 * np.sqrt(err / power) if power > 0 else float("nan"))
        return out


def _predictor(camp: Campaign, plus: list, minus: list | None) -> TransferPredictor:
    """The predictor from the single errors' histories ``plus`` (and ``minus``: second order),
    each a list over manoeuvres of lists over outputs."""
    M, O = len(camp.manoeuvres), len(MAP_OUTPUTS)
    k = len(COMPONENTS) * (1 if minus is None else 2)
    gram = np.empty((M, O, k, k))
    for m in range(M):
        for o in range(O):
            down = None if minus is None else [d[m][o] for d in minus]
            gram[m, o] = gram_matrix(basis([d[m][o] for d in plus], down))
    return TransferPredictor(
        tuple(x.name for x in camp.manoeuvres), tuple(o.name for o in MAP_OUTPUTS), COMPONENTS,
        camp.config.size_pct, gram, camp.base_rms, camp.floors, 1 if minus is None else 2,
    )  # fmt: skip


def _predicted_history(a: np.ndarray, plus: list, minus: list | None, m: int, o: int):
    """The predicted difference history of manoeuvre m, output o for weights ``a`` (J,)."""
    out = 0.0
    for j in np.flatnonzero(a):
        if minus is None:
            out = out + a[j] * plus[j][m][o]
        else:
            p, n = plus[j][m][o], minus[j][m][o]
            out = out + a[j] * (p - n) / 2 + a[j] ** 2 * (p + n) / 2
    return out


def _checks(camp: Campaign, config: TransferConfig, predictors: dict, plus, minus) -> dict:
    """The held-out runs and every predictor's figures on them (``predictors`` by name: the
    first one is the campaign's)."""
    s0, least = config.size_pct, LEAST_SHARE * config.size_pct
    out: dict[str, Any] = {"singles": {}, "combinations": [], "predictors": list(predictors)}
    for k in config.held_multiples:
        meas = np.array([camp.pct(camp.measure([ErrorTerm(*c, k * s0)], f"held {k:+g}x "
                                               f"{'/'.join(c)}")) for c in COMPONENTS])  # fmt: skip
        entry: dict[str, Any] = {"multiple": k, "size_pct": k * s0, "measured_pct": meas}
        for name, p in predictors.items():
            pred = np.array([p.predict_pct([ErrorTerm(*c, k * s0)]) for c in COMPONENTS])
            entry[name] = {"predicted_pct": pred, "cells": check_cells(meas, pred, least),
                           "influence": influence_rank(meas, pred)}  # fmt: skip
        out["singles"][f"{k:+g}"] = entry
    main = next(iter(predictors))
    for i, terms in enumerate(combinations(config.combinations, s0, config.seed)):
        diffs = camp.measure(terms, f"combination {i + 1}/{config.combinations}")
        a = predictors[main].weights(terms)
        down = minus if predictors[main].order == 2 else None
        resid = camp.pct([[d - _predicted_history(a, plus, down, m, o)
                           for o, d in enumerate(dm)] for m, dm in enumerate(diffs)])  # fmt: skip
        out["combinations"].append({
            "terms": [t.__dict__ for t in terms], "measured_pct": camp.pct(diffs),
            "history_error_pct": resid,
            **{f"{n}_pct": p.predict_pct(terms) for n, p in predictors.items()},
        })  # fmt: skip
    if out["combinations"]:
        meas = np.array([c["measured_pct"] for c in out["combinations"]])
        resid = np.array([c["history_error_pct"] for c in out["combinations"]])
        ok = np.isfinite(meas) & (meas >= least)
        out["combined"] = {n: check_cells(meas, np.array([c[f"{n}_pct"] for c in
                                                          out["combinations"]]), least)
                           for n in predictors}  # fmt: skip
        out["combined"][main]["median_history_error"] = (
            float(np.median(resid[ok] / meas[ok])) if ok.any() else None
        )
    return out


def run_transfer(
    config: TransferConfig, progress: Any = None
) -> tuple[dict[str, Any], TransferPredictor]:
    """The map, the predictor and its check (module docstring); ``progress`` a
    ``bushenv.progress.Progress`` or None (its ``total`` set here to the car steps to run).
    Returns the report and the campaign's predictor (``config.order``)."""
    t0 = time.perf_counter()
    s0, J = config.size_pct, len(COMPONENTS)
    n_runs = 1 + J * (config.order + len(config.held_multiples)) + config.combinations
    if progress is not None:
        names = config.manoeuvres
        progress.total = n_runs * sum(m.samples for m in standard_manoeuvres(
            config.dt_s, config.seed, names, config.duration_s))  # fmt: skip
        signs = "+-" if config.order == 2 else "+"
        progress.say(f"{J} component errors at {signs}{s0:g} % x {len(names)} manoeuvres, then "
                     f"{J * len(config.held_multiples)} held-out singles and "
                     f"{config.combinations} combinations: {n_runs} cars")  # fmt: skip
    camp = Campaign(config, progress)
    plus = [camp.measure([ErrorTerm(*c, s0)], f"map {'/'.join(c)}") for c in COMPONENTS]
    minus = None
    if config.order == 2:
        minus = [camp.measure([ErrorTerm(*c, -s0)], f"map -{s0:g} % {'/'.join(c)}")
                 for c in COMPONENTS]  # fmt: skip
    first = _predictor(camp, plus, None)
    predictors = {"second_order": _predictor(camp, plus, minus)} if minus is not None else {}
    predictors["first_order"] = first
    checks = _checks(camp, config, predictors, plus, minus)
    if minus is not None:  # the first order's sign reversal, on the -s0 runs built in
        meas = np.array([camp.pct(d) for d in minus])
        pred = np.array([first.predict_pct([ErrorTerm(*c, -s0)]) for c in COMPONENTS])
        checks["first_order_sign"] = {"cells": check_cells(meas, pred, LEAST_SHARE * s0),
                                      "influence": influence_rank(meas, pred)}  # fmt: skip
    report = {
        "settings": {**config.__dict__, "manoeuvres": list(config.manoeuvres),
                     "held_multiples": list(config.held_multiples)},
        "manoeuvres": [m.describe() for m in camp.manoeuvres],
        "outputs": [o._asdict() for o in MAP_OUTPUTS],
        "components": [list(c) for c in COMPONENTS],
        "factors": {"/".join(c[1:]): calibrate(c[2], c[1], s0, config.dt_s)
                    for c in COMPONENTS[: len(COORDS) * len(KINDS)]},
        "baseline_rms": camp.base_rms,
        "map_pct": np.array([camp.pct(d) for d in plus]),  # (J, M, O)
        "map_minus_pct": None if minus is None else np.array([camp.pct(d) for d in minus]),
        "map_rms": np.sqrt(np.maximum(np.einsum("mojj->jmo", first.gram), 0.0)),
        "in_car_component_pct": [camp.in_car_component_pct(ErrorTerm(*c, s0))
                                 for c in COMPONENTS],
        "checks": checks, "ended": camp.ended, "cars": n_runs,
        "car_steps": camp.done, "run_seconds": time.perf_counter() - t0,
    }  # fmt: skip
    return report, next(iter(predictors.values()))
