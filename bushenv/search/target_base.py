"""The target base: what every ``TARGETS`` entry provides (``targets.py`` registers them).

Kept apart from ``targets.py`` so a target in its own module (``target_rig3.py``) can subclass
it without an import circle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.divergence import Verdict
from bushenv.scales import MACHINE
from bushenv.search.base import SearchError
from bushenv.search.families import FAMILIES, Family


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
