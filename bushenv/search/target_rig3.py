"""The ``rig3`` target: BushRig3-v0's prescribed motion in three coordinates, a planar model
against the coupled planar reference, judged axis by axis; what a search on it tried, per
coordinate in its unit (``CoordinateRecorder``, ``covered_search``).

A profile is a (T, 3) array (axial m, radial m, rotation rad) within a stroke and rate per
coordinate (``families_planar.Rig3Limits``: the rig's, ``rig3_limits``, or a user's bushing's,
passed as the evaluator's ``scales``); a batch is (T, B, 3). Each coordinate's force (or moment) is
judged by ``divergence.judge`` on its own scale (``axis_scales``): stroke, rate and force limit
of that coordinate from the env's spec, and a force floor per coordinate. A profile fails when
any coordinate fails; the verdict names the coordinate (``PlanarVerdict.first_axis``: the one
that failed first, or, when none failed, the closest to failing).

The force floors are the papers' bushing's (``MACHINE_FLOORS``: the one-axis 200 N, and for the
rotation that floor scaled by the moment cell's range over the force cell's, 2500 N m / 25 kN)
scaled per coordinate by the judging reference's static stiffness over the built-in
reference's (``reference_floors``): a stiffer bushing's forces are judged at a higher floor, as
the one-axis judge sets the floor from its reference (``scales.scales_of_reference``); the
built-in reference gets exactly the papers' floors. The static criterion does not run here
(the planar reference has no static curve yet), nor does RL.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from bushenv.divergence import Verdict, judge
from bushenv.errors import DIVERGENCE_RAISES, ModelRaised
from bushenv.identify.static_estimate import coordinate_stiffness
from bushenv.scales import FORCE_FLOOR_N, MACHINE, BushingScales
from bushenv.search.base import (
    Recorder,
    SearchContext,
    Searcher,
    SearchError,
    SearchResult,
    _check_budget,
    _stable_id,
)
from bushenv.search.families_planar import COORDS, ENV_ID, UNITS, clip3, limits3
from bushenv.search.target_base import Responses, Target

ROTATION_FLOOR_NM = FORCE_FLOOR_N * 2500.0 / 25000.0
MACHINE_FLOORS = np.array([FORCE_FLOOR_N, FORCE_FLOOR_N, ROTATION_FLOOR_NM])


@dataclass
class PlanarVerdict(Verdict):
    """A ``Verdict`` over the three coordinates, with the coordinate that decided it."""

    first_axis: list[str | None] = field(default_factory=list)
    axis_robustness: dict[str, np.ndarray] = field(default_factory=dict)

    def row(self, b: int) -> dict:
        out = super().row(b)
        out["axis"] = self.first_axis[b]
        out["axis_robustness"] = {a: _json_float(r[b]) for a, r in self.axis_robustness.items()}
        return out

    def merged_extra(self, parts: list[PlanarVerdict]) -> dict:
        return {
            "first_axis": [a for p in parts for a in p.first_axis],
            "axis_robustness": {
                a: np.concatenate([p.axis_robustness[a] for p in parts])
                for a in self.axis_robustness
            },
        }


def _json_float(v) -> float | None:
    v = float(v)
    return v if np.isfinite(v) else None


def axis_scales(floors: np.ndarray = MACHINE_FLOORS) -> list[BushingScales]:
    """One ``BushingScales`` per coordinate: its force floor and BushRig3-v0's force limit
    (``judge`` reads only those two; the stroke and rate are the target's, not a scale's)."""
    from bushenv.rigs.specs import load_spec

    kw = load_spec(ENV_ID)["kwargs"]
    return [
        BushingScales(
            force_floor_n=floors[i],
            force_limit_n=float(kw["force_limit"][c]),
            source=f"{ENV_ID} spec, {c}",
        )
        for i, c in enumerate(COORDS)
    ]


# metres per radian when a rotation counts as motion (any positive lever arm would do: a hold
# is a run of samples where no coordinate moves)
ROTATION_LEVER_M = 0.04


@lru_cache(maxsize=8)
def _builtin_stiffness(dt: float) -> np.ndarray:
    from bushenv.rigs.common import resolve_model

    return coordinate_stiffness(
        resolve_model("reference", dt=dt, coords=3, what="reference", env_id="BushRig3-v0")
    )


def reference_floors(reference) -> tuple[np.ndarray, str]:
    """(floors (3,) N, N, N m; where they come from): ``MACHINE_FLOORS`` times the reference's
    static stiffness over the built-in reference's, per coordinate. A coordinate whose
    stiffness is not a positive number keeps the machine's floor (the vetting's holds then
    say why the reference cannot judge)."""
    k, k0 = coordinate_stiffness(reference), _builtin_stiffness(reference.dt)
    ratio = np.where(np.isfinite(k) & (k > 0), k / k0, 1.0)
    floors = MACHINE_FLOORS * ratio
    text = ", ".join(f"{c} x{r:.3g}" for c, r in zip(COORDS, ratio, strict=True))
    return (
        floors,
        f"the papers' floors times the reference's static stiffness over the built-in's ({text})",
    )


def held_vector(x: np.ndarray) -> np.ndarray:
    """(T, B) a signal that stays constant exactly while no coordinate of (T, B, 3) ``x``
    moves: the accumulated largest step, rotation taken at ``ROTATION_LEVER_M``."""
    step = np.abs(np.diff(x, axis=0, prepend=x[:1]))
    step[..., 2] *= ROTATION_LEVER_M
    return np.cumsum(step.max(axis=-1), axis=0)


def judge_axes(x, fm, fr, dt, lengths, floors: np.ndarray = MACHINE_FLOORS) -> PlanarVerdict:
    """``judge`` on each coordinate of (T, B, 3) arrays, combined: fails if any fails.

    A hold is a hold of the whole deflection vector: a coordinate held while another moves is
    not at rest (the coupling moves its force: the reference's moment follows a radial step),
    so the hold criteria (``self_sustained``, ``static``) see the bushing's motion, not the
    coordinate's alone."""
    hold = held_vector(x)
    parts = [
        judge(x[..., i], fm[..., i], fr[..., i], dt, lengths=lengths, hold_input=hold, scales=s)
        for i, s in enumerate(axis_scales(floors))
    ]
    rob = np.stack([p.robustness for p in parts])  # (3, B)
    first = np.stack([p.first_time_s for p in parts])
    B = rob.shape[1]
    deciding = np.argmin(rob, axis=0)
    failed = np.isfinite(first)
    for b in range(B):  # of the coordinates that failed, the first to fail decides
        if failed[:, b].any():
            deciding[b] = int(np.nanargmin(np.where(failed[:, b], first[:, b], np.nan)))
    pick = np.arange(B)

    def stacked(get):
        return np.stack([get(p) for p in parts])

    first_time = _nanmin(first)
    return PlanarVerdict(
        diverged=np.any(stacked(lambda p: p.diverged), axis=0),
        flags={c: np.any(stacked(lambda p, c=c: p.flags[c]), axis=0) for c in parts[0].flags},
        first_time_s=first_time,
        first_criterion=[parts[deciding[b]].first_criterion[b] for b in range(B)],
        worst_deviation=np.max(stacked(lambda p: p.worst_deviation), axis=0),
        robustness=np.min(rob, axis=0),
        criterion_robustness={
            c: np.min(stacked(lambda p, c=c: p.criterion_robustness[c]), axis=0)
            for c in parts[0].criterion_robustness
        },
        scale_n=stacked(lambda p: p.scale_n)[deciding, pick],
        criteria_run=parts[0].criteria_run,
        reference_unusable=np.any(stacked(lambda p: p.reference_unusable), axis=0),
        criterion_first_s={
            c: _nanmin(stacked(lambda p, c=c: p.criterion_first_s[c]))
            for c in parts[0].criterion_first_s
        },
        first_axis=[
            COORDS[deciding[b]] if np.isfinite(rob[deciding[b], b]) else None for b in range(B)
        ],
        axis_robustness={c: rob[i] for i, c in enumerate(COORDS)},
    )


def _nanmin(a: np.ndarray) -> np.ndarray:
    """Column minimum ignoring NaN; NaN where a column is all NaN (no warning)."""
    low = np.min(np.where(np.isnan(a), np.inf, a), axis=0)
    return np.where(np.isinf(low) & np.all(np.isnan(a), axis=0), np.nan, low)


def simulate_planar_or_nan(model, q: np.ndarray) -> np.ndarray:
    """``model.simulate(q)`` for (T, B, 3) ``q``; a history the model refuses on (a
    ``ModelRefused`` or ``ArithmeticError``) is NaN from the start (a non-finite output, a
    divergence); anything else it raises is its own bug (``ModelRaised``)."""
    try:
        return model.simulate(q)
    except DIVERGENCE_RAISES:
        pass
    except Exception as exc:
        raise ModelRaised(model.name, exc) from exc
    out = np.full_like(q, np.nan)
    for b in range(q.shape[1]):
        try:
            out[:, b] = model.simulate(np.ascontiguousarray(q[:, b]))
        except DIVERGENCE_RAISES:
            pass
        except Exception as exc:
            raise ModelRaised(model.name, exc) from exc
    return out


class CoordinateRecorder(Recorder):
    """The search's book-keeping, and what it tried per family and coordinate: profiles,
    smallest and largest peak |q|, largest |dq/dt| (the base's coverage takes the largest
    over the coordinates, which mixes m and rad)."""

    def __init__(self, result: SearchResult, evaluator) -> None:
        super().__init__(result, evaluator)
        self.per_coordinate: dict[str, list] = {}

    def _cover(self, batch, families: list[str], n: int) -> None:
        super()._cover(batch, families, n)
        x = batch.x[:, :n]  # (T, n, 3)
        peak = np.max(np.abs(x), axis=0)
        rate = (
            np.max(np.abs(np.diff(x, axis=0)), axis=0) / self.evaluator.dt
            if x.shape[0] > 1
            else 0 * peak
        )
        for b in range(n):
            c = self.per_coordinate.setdefault(
                families[b], [0, np.full(3, np.inf), np.zeros(3), np.zeros(3)]
            )
            c[0] += 1
            c[1] = np.minimum(c[1], peak[b])
            c[2] = np.maximum(c[2], peak[b])
            c[3] = np.maximum(c[3], rate[b])

    def coverage_json(self) -> dict[str, dict]:
        """Per family: profiles, then per coordinate its peak range and fastest rate, each
        key naming its unit (``peak_mm_*`` for axial and radial, ``peak_mrad_*`` for the
        rotation)."""
        out = {}
        for fam, (n, lo, hi, rate) in sorted(self.per_coordinate.items()):
            row: dict[str, Any] = {"profiles": int(n)}
            for i, (c, u) in enumerate(zip(COORDS, UNITS, strict=True)):
                per_s = "rad_per_s" if u == "mrad" else "m_per_s"
                row[c] = {
                    f"peak_{u}_min": round(1e3 * float(lo[i]), 4),
                    f"peak_{u}_max": round(1e3 * float(hi[i]), 4),
                    f"max_rate_{per_s}": round(float(rate[i]), 4),
                }
            out[fam] = row
        return out


def covered_search(searcher: Searcher, evaluator, budget: int, seed: int, progress=None):
    """``searcher.run(evaluator, budget, seed, progress)`` -- the same seeding, the same
    result -- with a ``CoordinateRecorder``: (result, its per-coordinate coverage)."""
    budget = _check_budget(budget)
    result = SearchResult(searcher.name, int(seed), budget, evaluator.target.name)
    recorder = CoordinateRecorder(result, evaluator)
    rng = np.random.default_rng([int(seed), _stable_id(searcher.name)])
    said = progress or (lambda line: None)
    searcher.search(SearchContext(evaluator, budget, rng, recorder, int(seed), said))
    result.seconds = time.perf_counter() - recorder.t0
    return result, recorder.coverage_json()


class Rig3Target(Target):
    """BushRig3-v0: prescribed motion in axial, radial and rotation; model and reference see
    the same motion, each coordinate judged on its own scale."""

    name = "rig3"
    env_id = ENV_ID
    profile_label = "deflection [mm, mm, mrad]"
    cma_family = "any3"
    default_searchers = ("random", "cma")
    coords = COORDS

    def finish(self, x: np.ndarray, dt: float, limits=MACHINE) -> np.ndarray:
        return clip3(x, dt, limits)

    def judging_facts(self, reference) -> dict[str, dict[str, float]]:
        floors = reference_floors(reference)[0]
        return {"force_floors": dict(zip(COORDS, floors.tolist(), strict=True))}

    def profile_bounds(self, limits=MACHINE) -> tuple[np.ndarray, np.ndarray]:
        """Per coordinate (3,) arrays: the stroke and rate of ``limits`` when they are
        ``Rig3Limits``, else BushRig3-v0's (a one-axis bushing's ``BushingScales`` do not apply)."""
        return limits3(limits)

    def responses(
        self, model, reference, x, lengths, dt, axis, dtype="float64", scales=MACHINE
    ) -> Responses:
        if x.ndim != 3 or x.shape[2] != 3:
            raise SearchError(f"the rig3 target takes (T, B, 3) profiles, got {x.shape}")
        fm = simulate_planar_or_nan(model, x)
        fr = reference.forces(x, lengths)
        floors = reference.cached("rig3 floors", lambda m: reference_floors(m)[0])
        verdict = judge_axes(x, fm, fr, dt, lengths, floors)
        return Responses(verdict, x, fm, fr)

    def check_models(self, kind: str):
        """(model, reference) the contract checks run: ``active`` a planar Kelvin-Voigt with
        negative damping, ``passive`` one 20 % softer, both against the planar linear preset."""
        from bushenv.models.planar_linear import PlanarLinear

        ref = PlanarLinear.preset()
        if kind == "active":
            return PlanarLinear(ref.k_matrix, -0.5 * ref.c_matrix, ref.dt), ref
        return PlanarLinear(0.8 * ref.k_matrix, ref.c_matrix, ref.dt), ref

    def rl_env(self, evaluator, n_envs, episode_steps, on_episodes, actions):
        raise SearchError("the rig3 target has no RL env for the search yet")
