"""The adversary in the car: search the standards' manoeuvres (``adversary_space``) for the one
that maximises the wheel-load difference between the car with model bushings and its twin with
the reference bushings, with the project's searchers on the ``halfcar`` target
(``bushenv/search/target_halfcar.py``), and put the find beside the worst standard manoeuvre.

``run_adversary(bushings, config, progress)`` returns the report (plain values) and what the
figures need. Per bushing kind: the seven standard manoeuvres judged as the search judges
(``standard``), each searcher's run, the largest difference found among the runs where both
cars ran to the end (``found``) and its amplification over the worst standard manoeuvre
that ran to the end, the manoeuvres that ended the model car (``terminations``), and which
pivot and coordinate carry the found difference (``adversary_blame``).
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv.progress import Progress
from bushenv.rigs.halfcar_params import REFERENCE as CAR_REFERENCE
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.families import FAMILIES
from bushenv.search.searchers import SEARCHERS
from bushenv.search.target_halfcar import HalfCarTarget
from bushenv.vehicle import adversary_space as space
from bushenv.vehicle.checks import VehicleInputError
from bushenv.vehicle.manoeuvres import Manoeuvre, standard_manoeuvres
from bushenv.vehicle.study import IDENTICAL_PCT

REFERENCE = CAR_REFERENCE  # the judge: the coupled rubber in torsion, as in ``bushenv vehicle``
ROAD_FAMILIES = ("car_road", "car_bump", "car_pothole")


@dataclass(frozen=True)
class AdversaryConfig:
    """What one adversary run does; ``budget`` car runs per searcher per bushing kind."""

    searchers: tuple[str, ...] = ("random", "cma")
    budget: int = 96
    seed: int = 0
    tolerance_pct: float = IDENTICAL_PCT

    def checked(self) -> AdversaryConfig:
        bad = [s for s in self.searchers if s not in ("random", "cma")]
        if bad or not self.searchers:
            raise VehicleInputError(
                f"searchers {list(self.searchers)}: the half car takes random and cma (the RL "
                "agents and the certificate search need a rig)"
            )
        if self.budget < 2:
            raise VehicleInputError(f"the search budget must be >= 2 car runs, got {self.budget}")
        if not self.tolerance_pct > 0:
            raise VehicleInputError(f"the tolerance must be > 0 %, got {self.tolerance_pct}")
        return self


def profile_of(m: Manoeuvre) -> np.ndarray:
    """A manoeuvre's (T, 3) half-car profile (road left, road right, a_y)."""
    return np.column_stack([m.road_m, m.lateral_accel_m_per_s2])


def describe_point(family: str, u: list[float] | None, dt_s: float) -> dict[str, Any]:
    """The physical parameters of a searched point: ``car_any``'s when ``u`` has its size (CMA
    labels a ``car_any`` point with the family its first coordinate picked)."""
    if u is None:
        return {"family": family}
    name = "car_any" if len(u) == space.ANY_DIM else family
    return space.build(name, u, dt_s)[1] | {"unit_point": [round(float(v), 6) for v in u]}


def _entry(kind_label: str, row: dict, params: dict, profile: np.ndarray, dt_s: float) -> dict:
    d = 100 * (row["worst_deviation"] or 0.0)
    return {"kind": kind_label, "d_pct": d, "reference_peak_n": row["reference_peak_n"],
            "difference_peak_n": d / 100 * row["reference_peak_n"],
            "criterion": row["first_criterion"], "time_s": row["first_time_s"],
            "robustness": row["robustness"], "end": row["end"], "steps": row["steps"],
            "outputs_peak_pct": row["outputs_peak_pct"], "params": params,
            "duration_s": len(profile) * dt_s,
            "reference_unusable": row["reference_unusable"]}  # fmt: skip


def completed(e: dict) -> bool:
    """Both cars ran the whole manoeuvre (no termination, the twin within its bounds)."""
    return e["criterion"] != "terminated" and not e["reference_unusable"]


def standard(evaluator: BatchEvaluator, manoeuvres: list[Manoeuvre]) -> list[dict]:
    """The standard manoeuvres judged by the search's own judge, one entry each."""
    batch = evaluator.evaluate([profile_of(m) for m in manoeuvres])
    return [
        _entry(m.name, batch.verdict.row(b), {"family": m.name, **m.params}, profile_of(m),
               m.dt_s) | {"profile": profile_of(m)}
        for b, m in enumerate(manoeuvres)
    ]  # fmt: skip


def searched(result, dt_s: float) -> list[dict]:
    """Every candidate a search kept (its worst and its failures), once each, with its
    physical parameters and profile."""
    seen, out = set(), []
    for c in [result.worst, *result.failures]:
        if c is None or c.evaluation in seen:
            continue
        seen.add(c.evaluation)
        e = _entry(c.family, c.verdict, describe_point(c.family, c.params, dt_s), c.profile, dt_s)
        out.append(e | {"evaluation": c.evaluation, "profile": c.profile, "u": c.params,
                        "searcher": result.searcher})  # fmt: skip
    return out


def largest(entries: list[dict]) -> dict | None:
    """The completed entry with the largest D (None if none completed)."""
    done = [e for e in entries if completed(e)]
    return max(done, key=lambda e: e["d_pct"]) if done else None


def peak_input(e: dict) -> float:
    """A profile's size: its largest |road| (mm) on a road, its largest |a_y| (m/s^2) else."""
    x = e["profile"]
    road = float(np.abs(x[:, :2]).max())
    return 1e3 * road if road > 0 else float(np.abs(x[:, 2]).max())


def terminations(entries: list[dict], result_coverage: dict[str, list[float]]) -> dict:
    """Per family: how many searched profiles ended the model car, of how many tried; the
    earliest end (s) with its manoeuvre's parameters; the smallest input that ended it and the
    largest kept input that ran to the end (road mm, a_y m/s^2: ``peak_input``). Profiles that
    ran to the end within the tolerance are not kept by a search, so the bracket is of the
    kept ones."""
    out: dict[str, Any] = {}
    for fam, cov in sorted(result_coverage.items()):
        mine = [e for e in entries if e["params"].get("family") == fam]
        ended = [e for e in mine if e["criterion"] == "terminated"]
        ran = [peak_input(e) for e in mine if completed(e)]
        first = min(ended, key=lambda e: e["time_s"]) if ended else None
        out[fam] = {"tried": int(cov[0]), "ended": len(ended),
                    "earliest_s": first["time_s"] if first else None,
                    "earliest_params": _plain_params(first["params"]) if first else None,
                    "earliest_reason": first["end"] if first else None,
                    "smallest_input_ended": min(map(peak_input, ended)) if ended else None,
                    "largest_input_ran": max(ran) if ran else None,
                    "input_unit": "mm" if fam in ROAD_FAMILIES else "m/s^2"}  # fmt: skip
    return out


def _plain_params(p: dict) -> dict:
    return {k: (round(v, 4) if isinstance(v, float) else v) for k, v in p.items()}


def _coverage(results) -> dict[str, list[float]]:
    cov: dict[str, list[float]] = {}
    for r in results:
        for fam, c in r.coverage.items():
            cov.setdefault(fam, [0, 0, 0, 0])[0] += c[0]
    return cov


def attack_kind(kind: str, model, reference, config: AdversaryConfig, manoeuvres, progress):
    """One bushing kind: the standard manoeuvres, then every searcher; the kind's report."""
    from bushenv.vehicle.adversary_blame import blame

    target = HalfCarTarget(config.tolerance_pct)
    dt = model.dt
    t0 = time.perf_counter()
    with BatchEvaluator(model, reference, target) as ev:
        std = standard(ev, manoeuvres)
        results, entries = [], []
        for name in config.searchers:
            base = progress.done

            def said(line: str, base=base) -> None:
                done = re.search(r"(\d+)/\d+ evals", line)  # the searchers' own count
                progress.update(base + (int(done.group(1)) if done else 0), f"{kind}: {line}")

            r = SEARCHERS[name].make().run(ev, config.budget, seed=config.seed, progress=said)
            progress.update(base + config.budget, f"{kind}: {name} done", force=True)
            results.append(r)
            entries += searched(r, dt)
    worst_std = largest(std)
    found = largest(entries)
    amp = (found["d_pct"] / worst_std["d_pct"]) if found and worst_std else None
    report = {
        "kind": kind,
        "standard": [_public(e) for e in std],
        "worst_standard": _public(worst_std) if worst_std else None,
        "found": _public(found) if found else None,
        "amplification": amp,
        "searches": [r.summary() for r in results],
        "terminations": terminations(entries, _coverage(results)),
        "standard_terminated": [e["kind"] for e in std if e["criterion"] == "terminated"],
        "reference_unusable": sum(r.n_reference_unusable for r in results),
        "seconds": time.perf_counter() - t0,
    }
    if found is not None:
        progress.say(f"{kind}: attributing the found difference to the pivots (8 more runs)")
        report["blame"] = blame(found["profile"], dt, model, REFERENCE)
    kept = {"found": found, "worst_standard": worst_std, "entries": entries, "results": results}
    return report, kept


def _public(e: dict) -> dict:
    return {k: v for k, v in e.items() if k not in ("profile",)}


def run_adversary(
    bushings: dict[str, Any], config: AdversaryConfig, progress: Progress | None = None
) -> tuple[dict, dict]:
    """Search for every kind in ``bushings`` (label -> three-axis model); (report, kept)."""
    from bushenv.rigs.common import resolve_model
    from bushenv.rigs.halfcar_params import ENV_ID

    config = config.checked()
    progress = progress or Progress(quiet=True)
    dt = next(iter(bushings.values())).dt
    manoeuvres = standard_manoeuvres(dt, config.seed)
    reference = resolve_model(REFERENCE, dt=dt, coords=3, what="reference", env_id=ENV_ID)
    progress.total = len(bushings) * len(config.searchers) * config.budget
    progress.say(f"adversary: {len(bushings)} kinds x {', '.join(config.searchers)} x "
                 f"{config.budget} car runs, seed {config.seed}")  # fmt: skip
    t0 = time.perf_counter()
    kinds, kept = {}, {}
    for kind, model in bushings.items():
        kinds[kind], kept[kind] = attack_kind(kind, model, reference, config, manoeuvres, progress)
    report = {
        "objective": "peak |dynamic wheel load, model car - reference car| over both wheels, "
        "% of the reference car's peak (the vehicle study's peak_pct; stated where the "
        "reference car's RMS is at least 10 N)",
        "judge": {"reference": REFERENCE, "tolerance_pct": config.tolerance_pct,
                  "criteria": "terminated: HalfCar-v0 ended the model car, its twin ran on; "
                  "differs: ran to the end and the objective above the tolerance"},
        "families": {n: {"dim": FAMILIES[n].dim, "source": s}
                     for n, (_, _, s) in space.BUILDERS.items()},
        "config": {"searchers": list(config.searchers), "budget": config.budget,
                   "seed": config.seed},
        "kinds": kinds, "seconds": time.perf_counter() - t0,
    }  # fmt: skip
    return report, kept
