"""The ``halfcar`` target: HalfCar-v0 driven by a manoeuvre, the car with model bushings in its
four arm pivots beside its twin with the reference bushings, judged on the wheel load.

A profile is a (T, 3) array of HalfCar-v0's inputs (road left m, road right m, lateral
acceleration m/s^2); its families are the standard manoeuvres with their parameters free within
the standards' bounds (``bushenv/vehicle/adversary_space.py``, registered here as ``car_*``).
A batch of profiles is driven at once by ``HalfCarBatch`` (HalfCar-v0's car as arrays: within
1 % of each output's peak of the pymunk env, docs/envs.md); the adversary judges the standard
manoeuvres on the same path, so a searched manoeuvre and a standard one are judged alike, and
re-measures its find in the pymunk env (``bushenv/vehicle/adversary_blame.py``).

The judge (``judge_car``): the objective is the peak difference of the dynamic wheel loads (both
wheels) between the model car and its twin, in % of the twin's own peak -- the vehicle study's
``peak_pct``, stated only where the twin's RMS reaches its 10 N floor. Why the wheel load: it is
what the road sees (grip), it exists under every manoeuvre, roads and steering alike, and the
study judged seed 000's finding on it among others. A profile fails on two criteria:

- ``terminated``: the model car left its bounds (HalfCar-v0's), its twin did not;
  robustness min((tol - D) / tol, -fraction of the manoeuvre not run), D over the steps run;
- ``differs``: the car ran to the end and D > ``tolerance_pct`` (default the study's 5 %
  "almost identical"); robustness (tol - D) / tol.

Robustness is negative exactly when a profile fails; the searchers minimise it, so they look
for the largest wheel-load difference. Where the twin itself leaves its bounds at any time in
the manoeuvre (too rough a road), also after the model car ended, the verdict is the
reference's, not the model's: ``reference_unusable``, robustness 1.
The (T, B, 2) forces a batch keeps are the two cars' dynamic wheel loads (N), each held at its
last value after its run ended.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bushenv.divergence import Verdict
from bushenv.rigs.halfcar_params import POSITIONS
from bushenv.scales import MACHINE
from bushenv.search.base import SearchError
from bushenv.search.families import FAMILIES, Family
from bushenv.search.target_base import Responses, Target
from bushenv.vehicle import adversary_space as space
from bushenv.vehicle.study import IDENTICAL_PCT

TARGET = "halfcar"
CRITERIA = ("terminated", "differs")
OBJECTIVE = "wheel_load"  # the output D is taken of (``compare.OUTPUTS``)
JUDGED = ("wheel_load", "roll", "camber", "track_change")  # reported beside D


@dataclass
class CarVerdict(Verdict):
    """A ``Verdict`` of car runs: D per profile and each judged output's peak difference."""

    outputs: list[dict] = field(default_factory=list)
    steps: list[tuple[int, int]] = field(default_factory=list)  # (run, of)
    end_reason: list[str] = field(default_factory=list)

    def row(self, b: int) -> dict:
        t = float(self.first_time_s[b])
        d = float(self.worst_deviation[b])
        return {
            "diverged": bool(self.diverged[b]),
            "criteria": [c for c in CRITERIA if bool(self.flags[c][b])],
            "first_criterion": self.first_criterion[b],
            "first_time_s": None if np.isnan(t) else t,
            "worst_deviation": d if np.isfinite(d) else None,
            "robustness": float(self.robustness[b]),
            "reference_unusable": bool(self.reference_unusable[b]),
            "objective": OBJECTIVE,
            "reference_peak_n": float(self.scale_n[b]),
            "outputs_peak_pct": self.outputs[b],
            "steps": list(self.steps[b]),
            "end": self.end_reason[b],
        }

    def merged_extra(self, parts: list[CarVerdict]) -> dict:
        return {k: [v for p in parts for v in getattr(p, k)]
                for k in ("outputs", "steps", "end_reason")}  # fmt: skip


def judge_run(run, samples: int, tolerance_pct: float) -> dict:
    """One car run's verdict (plain values): D (%), the criterion, robustness, the outputs'
    peak differences, when it failed; ``run`` a ``compare.CarRun`` of a manoeuvre of
    ``samples`` steps."""
    from bushenv.vehicle.compare import vehicle_differences

    diff = vehicle_differences(run.model, run.reference, run.dt_s)
    peaks = {k: diff[k]["peak_pct"] for k in JUDGED}
    d = peaks[OBJECTIVE] or 0.0
    tol = float(tolerance_pct)
    out = {"d_pct": d, "outputs": peaks, "criterion": None, "time_s": np.nan,
           "robustness": (tol - d) / tol, "unusable": False, "reason": ""}  # fmt: skip
    end = run.end
    if end.get("reason") and not end.get("reference_left_bounds"):
        left = (samples - run.steps) / samples
        out.update(criterion="terminated", time_s=float(end["time_s"]), reason=end["reason"],
                   robustness=min(out["robustness"], -left))  # fmt: skip
    elif end.get("reference_left_bounds"):
        out.update(unusable=True, robustness=1.0, reason=end["reason"])
    elif d > tol:
        base = run.reference[OBJECTIVE]
        over = np.abs(run.model[OBJECTIVE] - base).max(axis=1) > tol / 100 * np.abs(base).max()
        out.update(criterion="differs", time_s=float(run.dt_s * (1 + np.argmax(over))))
    return out


def judge_car(runs: list, samples: list[int], tolerance_pct: float) -> CarVerdict:
    """``CarVerdict`` of car runs (one per profile)."""
    rows = [judge_run(r, n, tolerance_pct) for r, n in zip(runs, samples, strict=True)]
    crit = [r["criterion"] for r in rows]
    rob = np.array([r["robustness"] for r in rows])
    t = np.array([r["time_s"] for r in rows], dtype=np.float64)
    flags = {c: np.array([k == c for k in crit]) for c in CRITERIA}
    return CarVerdict(
        diverged=rob < 0,
        flags=flags,
        first_time_s=t,
        first_criterion=crit,
        worst_deviation=np.array([r["d_pct"] / 100 for r in rows]),
        robustness=rob,
        criterion_robustness={c: np.where(flags[c], rob, np.inf) for c in CRITERIA},
        scale_n=np.array([float(np.abs(r.reference[OBJECTIVE]).max(initial=0.0)) for r in runs]),
        criteria_run=CRITERIA,
        reference_unusable=np.array([r["unusable"] for r in rows]),
        criterion_first_s={c: np.where(flags[c], t, np.nan) for c in CRITERIA},
        outputs=[r["outputs"] for r in rows],
        steps=[(int(r.steps), int(n)) for r, n in zip(runs, samples, strict=True)],
        end_reason=[r["reason"] for r in rows],
    )


@dataclass
class BatchRun:
    """One column of a ``HalfCarBatch`` run as ``judge_run`` reads a ``compare.CarRun``."""

    model: dict[str, np.ndarray]
    reference: dict[str, np.ndarray]
    dt_s: float
    steps: int
    end: dict


def car_runs(model, reference, x: np.ndarray, lengths: np.ndarray, dt: float) -> list[BatchRun]:
    """(T, B, 3) profiles driven by ``HalfCarBatch`` (the model car beside its twin, all B at
    once); each column cut where its manoeuvre ends or its model car left its bounds."""
    from bushenv.rigs.halfcar_batch import HalfCarBatch
    from bushenv.vehicle.compare import OUTPUTS

    B = x.shape[1]
    keys = [k for o in OUTPUTS for k in o.keys]
    pivots = [f"deflection_{k}_{c}_m" for k in POSITIONS for c in ("axial", "radial")]
    cars = HalfCarBatch(B, model=model, reference=reference,
                        max_lateral_accel_step_m_per_s2=space.AY_STEP_M_PER_S2)  # fmt: skip
    p = cars.params
    out = cars.simulate(x[:, :, 0], x[:, :, 1], x[:, :, 2],
                        keys=[*keys, *("reference_" + k for k in keys), *pivots])  # fmt: skip
    runs = []
    for b in range(B):
        n, first = int(lengths[b]), int(out["divergence_step"][b])
        ended = bool(out["diverged"][b]) and 0 <= first < n
        steps = first if ended else n
        end = {"reason": "", "reference_left_bounds": False}
        if bool(out["physical_limit"][b]):
            end.update(reason="the reference car left its bounds", reference_left_bounds=True)
        elif ended:
            defl = max(abs(float(out[k][first, b])) for k in pivots)
            why = (f"bushing deflection {1e3 * defl:.4g} mm exceeds {1e3 * p.max_deflection:.4g} "
                   "mm" if defl > p.max_deflection else "the model car left its bounds (a "
                   "force, travel, roll or displacement limit)")  # fmt: skip
            end.update(reason=why, time_s=(first + 1) * dt)
        runs.append(BatchRun(
            {o.name: np.stack([out[k][:steps, b] for k in o.keys], axis=1)
             - (p.tyre_static_n if o.name == "wheel_load" else 0.0) for o in OUTPUTS},
            {o.name: np.stack([out["reference_" + k][:steps, b] for k in o.keys], axis=1)
             - (p.tyre_static_n if o.name == "wheel_load" else 0.0) for o in OUTPUTS},
            dt, steps, end))  # fmt: skip
    return runs


def _held(a: np.ndarray, n: int) -> np.ndarray:
    """(n, 2) of ``a`` (k, 2), each column held at its last value past k (zeros if k = 0)."""
    out = np.zeros((n, 2))
    if len(a):
        out[: len(a)] = a[:n]
        out[len(a) :] = a[-1]
    return out


class HalfCarTarget(Target):
    """HalfCar-v0: a manoeuvre's inputs; the model car beside its reference twin, judged on
    the wheel-load difference (module docstring)."""

    name = TARGET
    env_id = "HalfCar-v0"
    profile_label = "road [m, m], lateral acceleration [m/s^2]"
    cma_family = "car_any"
    default_searchers = ("random", "cma")
    coords = ("road_left", "road_right", "lateral_accel")
    # what runs a search here: the campaign of ``bushenv attack`` judges one bushing on a rig
    command = "bushenv vehicle --search"

    def __init__(self, tolerance_pct: float = IDENTICAL_PCT) -> None:
        if not tolerance_pct > 0:
            raise SearchError(f"the half car's tolerance must be > 0 %, got {tolerance_pct}")
        self.tolerance_pct = float(tolerance_pct)

    def finish(self, x: np.ndarray, dt: float, limits=MACHINE) -> np.ndarray:
        return space.clip_inputs(x, dt)

    def profile_bounds(self, limits=MACHINE) -> tuple[np.ndarray, np.ndarray]:
        """(3,) largest |input| and |rate|: HalfCar-v0's roads (5 % inside its step) and
        lateral acceleration (the step this target's runs accept)."""
        from bushenv.rigs.halfcar_params import ENV_ID
        from bushenv.rigs.specs import spec_kwargs

        dt = float(spec_kwargs(ENV_ID, {})["dt_s"])
        height = np.array([space.ROAD_MAX_M, space.ROAD_MAX_M, space.AY_MAX_M_PER_S2])
        rate = np.array([space.ROAD_STEP_M, space.ROAD_STEP_M, space.AY_STEP_M_PER_S2]) / dt
        return height, rate

    def judging_facts(self, reference) -> dict[str, dict[str, float]]:
        return {"tolerance": {f"{OBJECTIVE}_peak_pct": self.tolerance_pct}}

    def responses(
        self, model, reference, x, lengths, dt, axis, dtype="float64", scales=MACHINE
    ) -> Responses:
        if x.ndim != 3 or x.shape[2] != 3:
            raise SearchError(f"the halfcar target takes (T, B, 3) profiles, got {x.shape}")
        runs = car_runs(model, reference.model, x, lengths, dt)
        samples = [int(n) for n in lengths]
        verdict = judge_car(runs, samples, self.tolerance_pct)
        T = x.shape[0]
        fm = np.stack([_held(r.model[OBJECTIVE], T) for r in runs], axis=1)
        fr = np.stack([_held(r.reference[OBJECTIVE], T) for r in runs], axis=1)
        return Responses(verdict, x, fm, fr)

    def check_models(self, kind: str):
        """(model, reference) the contract checks run: the planar linear preset as the
        reference; ``active`` with negative damping, ``passive`` 20 % softer."""
        from bushenv.models.planar_linear import PlanarLinear

        ref = PlanarLinear.preset()
        if kind == "active":
            return PlanarLinear(ref.k_matrix, -0.5 * ref.c_matrix, ref.dt), ref
        return PlanarLinear(0.8 * ref.k_matrix, ref.c_matrix, ref.dt), ref

    def rl_env(self, evaluator, n_envs, episode_steps, on_episodes, actions):
        raise SearchError("the halfcar target has no RL env for the search yet (HalfCar-v0 "
                          "itself is one: gym.make('bushenv/HalfCar-v0'))")  # fmt: skip


def _family(name: str, dim: int) -> Family:
    def build(u, dt, max_s, limits):
        return space.build(name, u, dt)

    return Family(name, dim, TARGET, build, random=name != "car_any")


for _name, (_dim, _, _) in space.BUILDERS.items():
    FAMILIES.add(_name, _family(_name, _dim))
FAMILIES.add("car_any", _family("car_any", space.ANY_DIM))
