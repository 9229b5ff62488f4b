"""The registry of candidate effects: the one list the diagnosis, the CLI and the docs use.

A new candidate = one ``Effect`` subclass (in ``effects/``) + one line in ``EFFECTS``. The
registry takes an effect under the name its class declares and only when the class keeps
what can be told of the contract without data (``effects.base.contract_problem``); the rest
is ``bushenv.diagnose.checks``, run over every entry by the tests. The diagnosis tries every
registered effect alone and every pair of them, composed with ``+``
(``Relaxation() + Friction()``); ``bushenv diagnose --effects`` chooses among the names, and
the effects table of docs/diagnose.md is ``effects_table()``.
"""

from __future__ import annotations

from itertools import combinations

from bushenv.diagnose.effects.backbone import Hardening
from bushenv.diagnose.effects.base import NULL, Combination, Effect, contract_problem
from bushenv.diagnose.effects.delay import Delay
from bushenv.diagnose.effects.friction import Friction
from bushenv.diagnose.effects.inertia import Inertia
from bushenv.diagnose.effects.relaxation import Relaxation
from bushenv.diagnose.effects.thermal import Thermal
from bushenv.errors import BadInput, BushenvError
from bushenv.registry import Registry


class UnknownEffectError(BadInput):
    """An effect name that is not in the registry; the message lists the known names."""


class EffectContractError(BushenvError):
    """An effect class that cannot be registered as given (a bug in the effect, not input)."""


class EffectRegistry(Registry[type[Effect]]):
    """``Registry`` that refuses an effect breaking its contract, or under another name."""

    def add(self, name: str, entry: type[Effect], *, replace: bool = False) -> type[Effect]:
        problem = contract_problem(name, entry)
        if problem:
            raise EffectContractError(problem)
        return super().add(name, entry, replace=replace)


EFFECTS = EffectRegistry("candidate effect", UnknownEffectError)
for _cls in (Relaxation, Friction, Hardening, Thermal, Delay, Inertia):
    EFFECTS.add(_cls.name, _cls)


def effect_names() -> tuple[str, ...]:
    return tuple(EFFECTS)


def register_effect(cls: type[Effect]) -> type[Effect]:
    """Add ``cls`` under ``cls.name`` (for extensions and tests; the built-ins are listed)."""
    if not cls.name:
        raise ValueError(f"{cls.__name__} has no name")
    return EFFECTS.add(cls.name, cls)


def get_effect(name: str) -> Effect:
    if name not in EFFECTS:
        raise UnknownEffectError(
            f"unknown candidate effect {name!r}; known: {', '.join(effect_names())}"
        )
    return EFFECTS[name]()


def candidate_sets(names: tuple[str, ...] | None = None) -> list[Combination]:
    """Every single effect and every pair among ``names`` (default: all registered)."""
    names = effect_names() if names is None else tuple(names)
    singles = [NULL + get_effect(n) for n in names]
    pairs = [a + b for a, b in combinations(singles, 2)]
    return singles + pairs


def effects_table() -> str:
    """The markdown table of the registered effects (docs/diagnose.md embeds it)."""
    lines = [
        "| effect | form added to the baseline | weights | shapes tried |",
        "|---|---|---|---|",
    ]
    for name, cls in EFFECTS.items():
        lines.append(f"| {name} | {cls.form} | {cls.weights} | {cls.shape_text} |")
    return "\n".join(lines)
