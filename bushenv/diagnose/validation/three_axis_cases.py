"""Three-axis validation cases: the coupled reference rubber with one effect withheld from the
linear baseline, on one coordinate (or, for the coupled ones, on several).

``make_case(spec, seed)`` builds a ``bushenv.reference.planar.PlanarRubber`` whose only
physical effect is the spec's (its load-cell noise always on), with a magnitude drawn from
``seed``, and measures a TRAIN record (random on every coordinate, independent drives, n = 1,
20 s) and a TEST record (random, correlated drives, n = 1.5, 20 s), each with its own noise
seed. ``score(result, spec)`` says whether ``diagnose`` named the right coordinate and effect.

| spec               | the reference                                                     |
|--------------------|-------------------------------------------------------------------|
| none               | linear, coupling off: the baseline explains it down to the noise  |
| relaxation@c       | Maxwell branches (preset times) on c only, 0.3..1 x preset weight |
| friction@c         | Iwan friction on c only (yield per coordinate), 0.3..1 x F_max    |
| hardening@c        | cubic stiffening on c only, 5..25 % extra force at TEST's peak    |
| friction_vector    | Iwan friction on all three, the vector yield surface (coupled)    |
| coupling           | the elastic coupling only (no one-axis candidate holds it)        |
| relaxation+coupling| relaxation on all three (of the coupled elastic force) + coupling |

The magnitudes are the preset's (``PlanarRubber.preset``) scaled, so each effect stands clear
of the preset noise on its coordinate.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv.models.base import PAPER_DT
from bushenv.models.planar_base import COORDS
from bushenv.motions import PEAK_AT_N1, random_correlated, random_independent
from bushenv.records import Record
from bushenv.reference.planar import PlanarRubber

N_TRAIN, N_TEST = 1.0, 1.5
DURATION_S = 20.0
OFF = 1e-9  # a friction force that is no friction (the reference needs one per coordinate)


@dataclass(frozen=True)
class Spec:
    """A case kind: the effect, the coordinates it acts on, what a right answer names."""

    name: str
    effect: str  # the reference's effect switched on ("none": none)
    coords: tuple[str, ...]  # where it acts
    expected: tuple[str, ...]  # the effects a right answer names on those coordinates


SPECS = (
    Spec("none", "none", (), ("none",)),
    *(
        Spec(f"{e}@{c}", e, (c,), (e,))
        for e in ("relaxation", "friction", "hardening")
        for c in COORDS
    ),
    Spec("friction_vector", "friction", COORDS, ("friction",)),
    Spec("coupling", "coupling", COORDS, ("coupling",)),
    Spec("relaxation+coupling", "relaxation", COORDS, ("relaxation", "coupling")),
)
FAST = ("none", "friction@radial", "relaxation@rotation", "hardening@axial")  # the tests' subset


def get_spec(name: str) -> Spec:
    for s in SPECS:
        if s.name == name:
            return s
    raise KeyError(f"three-axis case {name!r}; known: {', '.join(s.name for s in SPECS)}")


def reference(spec: Spec, seed: int, dt: float = PAPER_DT) -> tuple[dict[str, Any], tuple]:
    """(the preset's overrides, the effects switched on) for ``spec``, magnitudes drawn."""
    rng = np.random.default_rng([seed, SPECS.index(spec)])
    base = PlanarRubber.preset(dt=dt)
    on = [COORDS.index(c) for c in spec.coords]
    mask = np.zeros(3, bool)
    mask[on] = True
    if spec.effect == "relaxation":
        w = np.array(base.relax_weight) * rng.uniform(0.3, 1.0)
        w[:, ~mask] = 0.0
        coupled = ("coupling",) if "coupling" in spec.name else ()
        return {"relax_weight": w}, ("relaxation", *coupled)
    if spec.effect == "friction":
        fmax = np.where(mask, base.friction_fmax * rng.uniform(0.3, 1.0), OFF)
        x2 = np.where(mask, base.friction_x2, 1.0)
        yield_ = "vector" if spec.name == "friction_vector" else "axis"
        return {"friction_fmax": fmax, "friction_x2": x2, "friction_yield": yield_}, ("friction",)
    if spec.effect == "hardening":
        share = np.exp(rng.uniform(np.log(0.05), np.log(0.25)))  # extra force at TEST's peak
        length = N_TEST * PEAK_AT_N1 / np.sqrt(share)
        return {"hardening_m": np.where(mask, length, 0.0)}, ("hardening",)
    if spec.effect == "coupling":
        return {}, ("coupling",)
    return {}, ()


def make_case(
    spec: Spec | str, seed: int, dt: float = PAPER_DT, duration_s: float = DURATION_S
) -> tuple[Record, Record]:
    """(TRAIN, TEST) records of the case ``spec`` drawn from ``seed``."""
    spec = get_spec(spec) if isinstance(spec, str) else spec
    overrides, effects = reference(spec, seed, dt)
    motions = (
        ("train", random_independent(N_TRAIN, duration_s, dt, 2 * seed + 1)),
        ("test", random_correlated(N_TEST, duration_s, dt, 2 * seed + 2)),
    )
    out = []
    for k, (name, q) in enumerate(motions):
        model = PlanarRubber.preset(effects=effects, seed=1000 * seed + k, dt=dt, **overrides)
        f = np.asarray(model.simulate(q), float).reshape(q.shape)
        out.append(Record(np.arange(q.shape[0]) * dt, q, f, name))
    return out[0], out[1]


def score(result: dict[str, Any], spec: Spec | str) -> dict[str, Any]:
    """Whether the answer is right. ``hit``: the answer's coordinate is one the effect acts on
    and its effect an expected one (``none``: nothing named); ``every_coordinate``: each
    coordinate it acts on answers an expected effect; ``false_coordinates``: coordinates
    where an effect is named although none acts there; ``wrong_effects``: coordinates it acts
    on that name an effect it is not."""
    spec = get_spec(spec) if isinstance(spec, str) else spec
    named = result["effects"]
    false = [c for c, e in named.items() if c not in spec.coords and e != "none"]
    wrong = [c for c in spec.coords if named[c] not in (*spec.expected, "none")]
    top = result["coordinate"]
    if not spec.coords:
        hit = result["effect"] == "none"
    else:
        hit = top in spec.coords and result["effect"] in spec.expected
    return {
        "case": spec.name,
        "hit": bool(hit),
        "every_coordinate": all(named[c] in spec.expected for c in spec.coords),
        "wrong_effects": wrong,
        "coordinate_right": (top is None) if not spec.coords else top in spec.coords,
        "answer": result["answer"],
        "effects": named,
        "false_coordinates": false,
        "shrink": result["shrink"],
        "gaps": {r["coordinate"]: r["gap_before"] for r in result["coordinates"]},
    }
