"""Targets: what the search needs from one environment, and ``TARGETS``, the one list of them.

A target owns everything env-specific a search touches: its excitation families (``FAMILIES``
entries name their target), the batched simulation that turns a batch of profiles into a
verdict's inputs, the vector env RL agents act in, the env's limits on a profile
(``profile_bounds``) and how a profile is kept within them (``finish``). Searchers, the
evaluator, shrinking, campaigns and the corpus ask the target; none of them compares env names.
``bushenv/search/checks.py`` holds the contract as checks every ``TARGETS`` entry passes.

The rig target over three coordinates (``rig3``): a profile is (T, 3) (axial m, radial m,
rotation rad) within a stroke and rate per coordinate (``limits.CoordinateLimits``: the
rig's, or a user's bushing's, passed as the evaluator's ``scales``); each coordinate's force
(or moment) is judged by ``divergence.judge`` on its own scale: the env's force limit there and
a force floor per coordinate (``reference_floors``: the papers' bushing's -- the one-axis
200 N, and for the rotation that floor scaled by the moment cell's range over the force cell's,
2500 N m / 25 kN -- times the judging reference's static stiffness over the built-in
reference's, as the one-axis judge sets the floor from its reference). A profile fails when any
coordinate fails; the verdict names the coordinate. The static criterion does not run there
(the coupled reference has no static curve yet), nor does RL.

| name       | profile                          | simulation                                       |
|------------|----------------------------------|--------------------------------------------------|
| rig        | bushing displacement, m          | the models' batched kernels on prescribed motion |
| quartercar | road height under the wheel, m   | ``QuarterCarBatch``: the car, model vs twin      |
| rig3       | (T, 3) axial m, radial m, rot rad| the models' batched kernels on prescribed motion |
|            |                                  | in three coordinates, each judged on its own     |
|            |                                  | scale (``target_base.judge_coordinates``)        |
| halfcar    | (T, 3) road left m, road right m,| HalfCar-v0, model car vs reference twin, judged  |
|            | lateral acceleration m/s^2       | on the wheel load (``target_halfcar.py``)        |
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from bushenv import excitation as ex
from bushenv.divergence import judge
from bushenv.identify.static_estimate import STIFFNESS_LEVER_M, coordinate_stiffness
from bushenv.registry import Registry
from bushenv.scales import FLOOR_AMPLITUDE_M, FORCE_FLOOR_N, MACHINE, BushingScales
from bushenv.search.base import SearchError
from bushenv.search.limits import COORDS, UNITS, clip_coords, limits_arrays
from bushenv.search.roads import quarter_car_responses
from bushenv.search.target_base import (  # noqa: F401 (simulate_or_nan: the evaluator's)
    Responses,
    Target,
    judge_coordinates,
    simulate_or_nan,
)
from bushenv.search.target_halfcar import HalfCarTarget

ROTATION_FLOOR_NM = FORCE_FLOOR_N * 2500.0 / 25000.0
MACHINE_FLOORS = np.array([FORCE_FLOOR_N, FORCE_FLOOR_N, ROTATION_FLOOR_NM])


def coordinate_scales(env_id: str, coords: tuple[str, ...], floors) -> list[BushingScales]:
    """One ``BushingScales`` per coordinate: its force floor and the env's force limit there
    (``judge`` reads only those two; the stroke and rate are the target's, not a scale's)."""
    from bushenv.rigs.specs import load_spec

    kw = load_spec(env_id)["kwargs"]
    return [
        BushingScales(
            force_floor_n=floors[i],
            force_limit_n=float(kw["force_limit"][c]),
            source=f"{env_id} spec, {c}",
        )
        for i, c in enumerate(coords)
    ]


@lru_cache(maxsize=8)
def _builtin_stiffness(dt: float) -> np.ndarray:
    from bushenv.rigs.common import resolve_model

    ref = resolve_model("reference", dt=dt, coords=len(COORDS), env_id="BushRig3-v0")
    return coordinate_stiffness(ref)


def reference_floors(reference) -> tuple[np.ndarray, str]:
    """(floors (C,) N or N m; where they come from): over BushRig3-v0's coordinates
    ``MACHINE_FLOORS`` times the reference's static stiffness over the built-in reference's, per
    coordinate. A coordinate whose stiffness is not a positive number keeps the machine's floor
    (the vetting's holds then say why the reference cannot judge). Over other coordinates, with
    no built-in reference of them, the one-axis rule (``scales.scales_of_reference``) on each:
    its static force at the papers' smallest amplitude, 0.5 mm (a rotation: 0.5 mm at the
    stiffness lever, ``static_estimate.STIFFNESS_LEVER_M``)."""
    coords = tuple(getattr(reference, "coords", ()))
    if coords != COORDS:
        return _floors_without_builtin(reference, coords)
    k, k0 = coordinate_stiffness(reference), _builtin_stiffness(reference.dt)
    ratio = np.where(np.isfinite(k) & (k > 0), k / k0, 1.0)
    floors = MACHINE_FLOORS * ratio
    text = ", ".join(f"{c} x{r:.3g}" for c, r in zip(COORDS, ratio, strict=True))
    return (
        floors,
        f"the papers' floors times the reference's static stiffness over the built-in's ({text})",
    )


def _floors_without_builtin(reference, coords: tuple[str, ...]) -> tuple[np.ndarray, str]:
    k = coordinate_stiffness(reference)
    amplitude = np.array(
        [FLOOR_AMPLITUDE_M / (STIFFNESS_LEVER_M if u == "rad" else 1.0) for u in reference.units]
    )
    bad = [c for c, v in zip(coords, k, strict=True) if not (np.isfinite(v) and v > 0)]
    if bad:
        raise SearchError(
            f"the reference's static stiffness in {', '.join(bad)} is not a positive number: "
            "it cannot set the force floor there (a bushing pushes back)"
        )
    floors = k * amplitude
    text = ", ".join(f"{c} {v:.4g}" for c, v in zip(coords, k, strict=True))
    return floors, (
        f"the reference's static stiffness per coordinate ({text}; N/m, N m/rad) x the papers' "
        f"smallest amplitude, {FLOOR_AMPLITUDE_M * 1e3:g} mm (a rotation: at the "
        f"{STIFFNESS_LEVER_M:g} m lever)"
    )


class RigTarget(Target):
    """BushRig-v0: prescribed bushing displacement; model and reference see the same motion."""

    name = "rig"
    env_id = "BushRig-v0"
    profile_label = "deflection [mm]"
    cma_family = "any"
    default_searchers = ("random", "cma", "certificate", "ppo", "sac")
    float32 = True
    paper_step = True
    reference_free = True
    judges_static = True

    def finish(self, x: np.ndarray, dt: float, limits=MACHINE) -> np.ndarray:
        return ex.clip_to_limits(x, dt, limits.stroke_m, limits.velocity_m_per_s)

    def profile_bounds(self, limits=MACHINE) -> tuple[float, float]:
        return limits.stroke_m, limits.velocity_m_per_s

    def responses(
        self, model, reference, x, lengths, dt, axis, dtype="float64", scales=MACHINE
    ) -> Responses:
        """``reference`` is a ``ReferenceRuns`` (its forces are cached by profile)."""
        if dtype == "float32":
            fm = model.simulate(x, dtype="float32").astype(np.float64)
        else:
            fm = simulate_or_nan(model, x)
        fr = reference.forces(x, lengths)
        fs = reference.static_forces(x)
        verdict = judge(x, fm, fr, dt, lengths=lengths, scales=scales, f_static=fs)
        return Responses(verdict, x, fm, fr)

    def rl_env(self, evaluator, n_envs, episode_steps, on_episodes, actions):
        from bushenv.search.rl_rig import rig_agent_env

        return rig_agent_env(evaluator, n_envs, episode_steps, on_episodes, actions)


class QuarterCarTarget(Target):
    """QuarterCar-v0: road height under the wheel; the model's car beside a twin on the
    reference, the verdict on the attacked axis (``roads.py``)."""

    name = "quartercar"
    env_id = "QuarterCar-v0"
    profile_label = "road [mm]"
    cma_family = "bump"
    default_searchers = ("random", "cma")

    def profile_bounds(self, limits=MACHINE) -> tuple[float, float]:
        """The env's road limits (its spec): height, and one road step per sample."""
        from bushenv.rigs.specs import load_spec

        kw = load_spec(self.env_id)["kwargs"]
        return kw["max_road_height_m"], kw["max_road_step_m"] / kw["dt_s"]

    def responses(
        self, model, reference, x, lengths, dt, axis, dtype="float64", scales=MACHINE
    ) -> Responses:
        verdict, xm, fm, fr, _ = quarter_car_responses(
            model, reference.model, x, lengths, dt, axis, scales
        )
        return Responses(verdict, xm, fm, fr)

    def rl_env(self, evaluator, n_envs, episode_steps, on_episodes, actions):
        from bushenv.search.rl_road import road_agent_env

        return road_agent_env(evaluator, n_envs, episode_steps, on_episodes, actions)


class Rig3Target(Target):
    """BushRig3-v0: prescribed motion in axial, radial and rotation; model and reference see
    the same motion, each coordinate judged on its own scale."""

    name = "rig3"
    env_id = "BushRig3-v0"
    profile_label = "deflection [mm, mm, mrad]"
    cma_family = "any3"
    default_searchers = ("random", "cma")
    coords = COORDS
    shown_units = UNITS

    def finish(self, x: np.ndarray, dt: float, limits=MACHINE) -> np.ndarray:
        return clip_coords(x, dt, limits)

    def judging_facts(self, reference) -> dict[str, dict[str, float]]:
        floors = reference_floors(reference)[0]
        return {"force_floors": dict(zip(COORDS, floors.tolist(), strict=True))}

    def profile_bounds(self, limits=MACHINE) -> tuple[np.ndarray, np.ndarray]:
        """Per coordinate (3,) arrays: the stroke and rate of ``limits`` when they are
        ``CoordinateLimits``, else BushRig3-v0's (a one-axis bushing's ``BushingScales`` do not
        apply)."""
        return limits_arrays(limits)

    def responses(
        self, model, reference, x, lengths, dt, axis, dtype="float64", scales=MACHINE
    ) -> Responses:
        if x.ndim != 3 or x.shape[2] != 3:
            raise SearchError(f"the rig3 target takes (T, B, 3) profiles, got {x.shape}")
        fm = simulate_or_nan(model, x)
        fr = reference.forces(x, lengths)
        floors = reference.cached("rig3 floors", lambda m: reference_floors(m)[0])
        scales = coordinate_scales(self.env_id, self.coords, floors)
        verdict = judge_coordinates(x, fm, fr, dt, lengths, scales, self.coords, self.shown_units)
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


TARGETS: Registry[Target] = Registry("target", SearchError)
TARGETS.add("rig", RigTarget())
TARGETS.add("quartercar", QuarterCarTarget())
TARGETS.add("rig3", Rig3Target())
TARGETS.add("halfcar", HalfCarTarget())


def get_target(target: str | Target) -> Target:
    return target if isinstance(target, Target) else TARGETS[target]
