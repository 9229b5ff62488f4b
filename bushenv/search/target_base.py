"""The target base: what every ``TARGETS`` entry provides (``targets.py`` registers them), and
what a target over C coordinates shares: a verdict per coordinate (``judge_coordinates``,
``CoordinateVerdict``), a hold of the whole deflection vector (``held_vector``), the
simulation that turns a model's refusal into NaN (``simulate_or_nan``) and what a search tried
per coordinate in its unit (``CoordinateRecorder``, ``covered_search``).

Kept apart from ``targets.py`` so a target in its own module (``target_halfcar.py``) can
subclass it without an import circle.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bushenv.divergence import Verdict, judge
from bushenv.errors import DIVERGENCE_RAISES, ModelRaised
from bushenv.models.base import BushingModel, velocity_of
from bushenv.scales import MACHINE, BushingScales
from bushenv.search.base import (
    Recorder,
    SearchContext,
    Searcher,
    SearchError,
    SearchResult,
    _check_budget,
    _stable_id,
)
from bushenv.search.families import FAMILIES, Family

# metres per radian when a rotation counts as motion (any positive lever arm would do: a hold
# is a run of samples where no coordinate moves)
ROTATION_LEVER_M = 0.04


@dataclass
class Responses:
    """A batch simulated on a target: the verdict and what it was judged on, all (T, B)."""

    verdict: Verdict
    x: np.ndarray  # the model's bushing deflection, m
    f_model: np.ndarray  # N
    f_ref: np.ndarray  # N


class Target:
    """Base: the families and limits every target has; subclasses simulate and build RL envs."""

    name = ""
    env_id = ""
    profile_label = ""  # what a profile is, with its plotting unit
    cma_family = ""  # the family CMA-ES searches by default
    default_searchers: tuple[str, ...] = ()
    float32 = False  # NARX models may run in float32 on this target
    paper_step = False  # the papers' 4 mm step applies (prescribed displacement)
    reference_free = False  # can judge a model with no reference (criteria that need none)
    judges_static = False  # holds are of the bushing itself (the static criterion applies)
    coords: tuple[str, ...] = ()  # a profile's columns; () for a one-axis (T,) profile
    shown_units: tuple[str, ...] = ()  # how reports show each column (x 1e3 of its SI unit)

    def families(self) -> list[Family]:
        return [f for f in FAMILIES.values() if f.target == self.name]

    def family_names(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.families())

    def random_families(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.families() if f.random)

    def family(self, name: str) -> Family:
        fam = FAMILIES[name]
        if fam.target != self.name:
            raise SearchError(
                f"family {name!r} is for the {fam.target} target, not the {self.name}; "
                f"known for the {self.name}: {', '.join(self.family_names())}"
            )
        return fam

    def finish(self, x: np.ndarray, dt: float, limits=MACHINE) -> np.ndarray:
        """``x`` kept within the env's limits (a shrinking move may step outside them)."""
        return x

    def profile_bounds(self, limits=MACHINE) -> tuple[float, float]:
        """The largest |profile| (m) and |rate| (m/s) the env takes: every family's profile
        and every shrinking move stays within them (``bushenv/search/checks.py``)."""
        raise NotImplementedError

    def responses(
        self, model, reference, x, lengths, dt, axis, dtype="float64", scales=MACHINE
    ) -> Responses:
        raise NotImplementedError

    def rl_env(self, evaluator, n_envs, episode_steps, on_episodes, actions):
        raise NotImplementedError

    def judging_facts(self, reference) -> dict[str, dict[str, float]]:
        """What of this target's judge follows from ``reference`` beyond its parameters, by
        name, each a number per coordinate, for a case to record and a replay to compare (the
        rig3 target: its force floors)."""
        return {}

    def check_models(self, kind: str):
        """(model, reference) the contract checks (``checks.py``) run: ``active`` fails on some
        profiles (negative damping vs Table 1), ``passive`` on none (a softer spring)."""
        from bushenv.models.linear import LinearBushing

        ref = LinearBushing.preset("axial")
        scale = (1.0, -0.5) if kind == "active" else (0.8, 1.0)
        return LinearBushing(scale[0] * ref.k_n_per_m, scale[1] * ref.c_ns_per_m, ref.dt), ref


def simulate_or_nan(model: BushingModel, x: np.ndarray) -> np.ndarray:
    """``model.simulate(x)`` for (T, B) ``x`` (or (T, B, C) over C coordinates); a model that
    refuses (``ModelRefused``, e.g. Bouc-Wen's step-size control, or an ``ArithmeticError``)
    gives NaN from the sample it refused on, in the histories that made it refuse -- a
    non-finite output, which ``judge`` calls a divergence. Anything else it raises is its own
    bug: ``ModelRaised``, never a verdict."""
    try:
        return model.simulate(x)
    except DIVERGENCE_RAISES:
        pass
    except Exception as exc:
        raise ModelRaised(model.name, exc) from exc
    out = np.empty_like(x)
    for b in range(x.shape[1]):
        col = np.ascontiguousarray(x[:, b])
        try:
            out[:, b] = model.simulate(col)
            continue
        except DIVERGENCE_RAISES:
            pass
        except Exception as exc:
            raise ModelRaised(model.name, exc) from exc
        v = velocity_of(col, model.dt)  # the velocity simulate would have used
        model.reset(1)
        out[:, b] = np.nan
        for t in range(col.shape[0]):
            try:
                out[t, b] = model.step(col[t], v[t])
            except DIVERGENCE_RAISES:
                break
            except Exception as exc:
                raise ModelRaised(model.name, exc) from exc
    return out


@dataclass
class CoordinateVerdict(Verdict):
    """A ``Verdict`` over C coordinates, with the coordinate that decided it."""

    first_axis: list[str | None] = field(default_factory=list)
    axis_robustness: dict[str, np.ndarray] = field(default_factory=dict)

    def row(self, b: int) -> dict:
        out = super().row(b)
        out["axis"] = self.first_axis[b]
        out["axis_robustness"] = {a: _json_float(r[b]) for a, r in self.axis_robustness.items()}
        return out

    def merged_extra(self, parts: list[CoordinateVerdict]) -> dict:
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


def held_vector(x: np.ndarray, units: tuple[str, ...]) -> np.ndarray:
    """(T, B) a signal that stays constant exactly while no coordinate of (T, B, C) ``x``
    moves: the accumulated largest step, a rotation (a unit in rad or mrad) taken at
    ``ROTATION_LEVER_M``."""
    step = np.abs(np.diff(x, axis=0, prepend=x[:1]))
    for i, unit in enumerate(units):
        if unit.endswith("rad"):
            step[..., i] *= ROTATION_LEVER_M
    return np.cumsum(step.max(axis=-1), axis=0)


def judge_coordinates(
    x, fm, fr, dt, lengths, scales: list[BushingScales], coords: tuple[str, ...], units
) -> CoordinateVerdict:
    """``judge`` on each of the C coordinates of (T, B, C) arrays, each at its own
    ``scales`` (its force floor and limit), combined: fails if any fails; ``units``, each
    coordinate's, tell ``held_vector`` which is a rotation.

    A hold is a hold of the whole deflection vector: a coordinate held while another moves is
    not at rest (the coupling moves its force: the reference's moment follows a radial step),
    so the hold criteria (``self_sustained``, ``static``) see the bushing's motion, not the
    coordinate's alone."""
    hold = held_vector(x, units)
    parts = [
        judge(x[..., i], fm[..., i], fr[..., i], dt, lengths=lengths, hold_input=hold, scales=s)
        for i, s in enumerate(scales)
    ]
    rob = np.stack([p.robustness for p in parts])  # (C, B)
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
    return CoordinateVerdict(
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
            coords[deciding[b]] if np.isfinite(rob[deciding[b], b]) else None for b in range(B)
        ],
        axis_robustness={c: rob[i] for i, c in enumerate(coords)},
    )


def _nanmin(a: np.ndarray) -> np.ndarray:
    """Column minimum ignoring NaN; NaN where a column is all NaN (no warning)."""
    low = np.min(np.where(np.isnan(a), np.inf, a), axis=0)
    return np.where(np.isinf(low) & np.all(np.isnan(a), axis=0), np.nan, low)


class CoordinateRecorder(Recorder):
    """The search's book-keeping, and what it tried per family and coordinate of a target over
    C coordinates: profiles, smallest and largest peak |q|, largest |dq/dt| (the base's
    coverage takes the largest over the coordinates, which mixes m and rad)."""

    def __init__(self, result: SearchResult, evaluator) -> None:
        super().__init__(result, evaluator)
        self.per_coordinate: dict[str, list] = {}

    def _cover(self, batch, families: list[str], n: int) -> None:
        super()._cover(batch, families, n)
        x = batch.x[:, :n]  # (T, n, C)
        peak = np.max(np.abs(x), axis=0)
        rate = (
            np.max(np.abs(np.diff(x, axis=0)), axis=0) / self.evaluator.dt
            if x.shape[0] > 1
            else 0 * peak
        )
        k = x.shape[2]
        for b in range(n):
            c = self.per_coordinate.setdefault(
                families[b], [0, np.full(k, np.inf), np.zeros(k), np.zeros(k)]
            )
            c[0] += 1
            c[1] = np.minimum(c[1], peak[b])
            c[2] = np.maximum(c[2], peak[b])
            c[3] = np.maximum(c[3], rate[b])

    def coverage_json(self) -> dict[str, dict]:
        """Per family: profiles, then per coordinate its peak range and fastest rate, each
        key naming its unit (the target's ``units`` x 1e3: ``peak_mm_*`` for a translation,
        ``peak_mrad_*`` for a rotation)."""
        target = self.evaluator.target
        out = {}
        for fam, (n, lo, hi, rate) in sorted(self.per_coordinate.items()):
            row: dict[str, Any] = {"profiles": int(n)}
            for i, (c, u) in enumerate(zip(target.coords, target.shown_units, strict=True)):
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
