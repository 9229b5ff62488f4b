"""Targets: what the search needs from one environment, and ``TARGETS``, the one list of them.

A target owns everything env-specific a search touches: its excitation families (``FAMILIES``
entries name their target), the batched simulation that turns a batch of profiles into a
verdict's inputs, the vector env RL agents act in, the env's limits on a profile
(``profile_bounds``) and how a profile is kept within them (``finish``). Searchers, the
evaluator, shrinking, campaigns and the corpus ask the target; none of them compares env names.
``bushenv/search/checks.py`` holds the contract as checks every ``TARGETS`` entry passes.

| name       | profile                          | simulation                                       |
|------------|----------------------------------|--------------------------------------------------|
| rig        | bushing displacement, m          | the models' batched kernels on prescribed motion |
| quartercar | road height under the wheel, m   | ``QuarterCarBatch``: the car, model vs twin      |
| rig3       | (T, 3) axial m, radial m, rot rad| planar model vs the coupled planar reference,    |
|            |                                  | judged per coordinate (``target_rig3.py``)       |
| halfcar    | (T, 3) road left m, road right m,| HalfCar-v0, model car vs reference twin, judged  |
|            | lateral acceleration m/s^2       | on the wheel load (``target_halfcar.py``)        |
"""

from __future__ import annotations

import numpy as np

from bushenv import excitation as ex
from bushenv.divergence import judge
from bushenv.errors import DIVERGENCE_RAISES, ModelRaised
from bushenv.models.base import BushingModel, velocity_of
from bushenv.registry import Registry
from bushenv.scales import MACHINE
from bushenv.search.base import SearchError
from bushenv.search.roads import quarter_car_responses
from bushenv.search.target_base import Responses, Target
from bushenv.search.target_halfcar import HalfCarTarget
from bushenv.search.target_rig3 import Rig3Target


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


TARGETS: Registry[Target] = Registry("target", SearchError)
TARGETS.add("rig", RigTarget())
TARGETS.add("quartercar", QuarterCarTarget())
TARGETS.add("rig3", Rig3Target())
TARGETS.add("halfcar", HalfCarTarget())


def get_target(target: str | Target) -> Target:
    return target if isinstance(target, Target) else TARGETS[target]


def simulate_or_nan(model: BushingModel, x: np.ndarray) -> np.ndarray:
    """``model.simulate(x)`` for (T, B) ``x``; a model that refuses (``ModelRefused``, e.g.
    Bouc-Wen's step-size control, or an ``ArithmeticError``) gives NaN from the sample it
    refused on, in the histories that made it refuse -- a non-finite output, which ``judge``
    calls a divergence. Anything else it raises is its own bug: ``ModelRaised``, never a
    verdict."""
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
        for t in range(col.size):
            try:
                out[t, b] = model.step(col[t], v[t])
            except DIVERGENCE_RAISES:
                break
            except Exception as exc:
                raise ModelRaised(model.name, exc) from exc
    return out
