"""Env spec files: ``envs/<id>.toml``, one per registered id, read with ``tomllib``.

Shipped in the wheel as the resource package ``bushenv.envs``; in a source checkout read from
``envs/`` beside the package. A spec's top level mirrors Gymnasium's ``EnvSpec`` (``id``,
``entry_point``, ``vector_entry_point``, ``max_episode_steps``); ``[kwargs]`` holds every
default an environment takes, and the constructors refuse keys it does not name.

A spec is parsed once per id and kept frozen (``_frozen_spec``); every caller gets its own
plain copy, so an env that edits its kwargs cannot change the next one's.
"""

from __future__ import annotations

import tomllib
from functools import cache
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from bushenv.rigs.errors import RigError

SPEC_PACKAGE = "bushenv.envs"
SOURCE_SPEC_DIR = Path(__file__).resolve().parents[2] / "envs"


def spec_directory() -> Any:
    """The folder holding the env specs: the installed ``bushenv.envs`` resource package, or
    ``envs/`` of a source checkout. Returns a ``Traversable`` (``Path`` in a checkout)."""
    try:
        root = resources.files(SPEC_PACKAGE)
        if any(p.name.endswith(".toml") for p in root.iterdir()):
            return root
    except (ModuleNotFoundError, FileNotFoundError, NotADirectoryError, TypeError):
        pass
    return SOURCE_SPEC_DIR


def spec_files() -> list[Any]:
    """Every ``*.toml`` spec, sorted by name."""
    root = spec_directory()
    return sorted((p for p in root.iterdir() if p.name.endswith(".toml")), key=lambda p: p.name)


# Top-level keys of a spec: Gymnasium's EnvSpec fields the project uses, and the kwargs table.
SPEC_KEYS = ("id", "entry_point", "vector_entry_point", "max_episode_steps", "kwargs")
REQUIRED_KEYS = ("id", "entry_point", "max_episode_steps", "kwargs")
# The episode length is Gymnasium's ``max_episode_steps`` (the TimeLimit of gym.make, the vector
# envs' own truncation); the name it had as a kwarg is refused with this hint.
RENAMED = {
    "episode_steps": "the episode length is Gymnasium's max_episode_steps: pass "
    "gym.make(id, max_episode_steps=N) (N = -1: no limit) or make_vec(id, ..., "
    "max_episode_steps=N)"
}


def read_spec(source: Any) -> dict[str, Any]:
    """Parse one spec file (a path or ``Traversable``) and check its keys."""
    name = getattr(source, "name", str(source))
    try:
        spec = tomllib.loads(source.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise RigError(f"{name}: not valid TOML: {exc}") from None
    for key in REQUIRED_KEYS:
        if key not in spec:
            raise RigError(f"{name}: spec lacks the required key {key!r}")
    unknown = sorted(set(spec) - set(SPEC_KEYS))
    if unknown:
        raise RigError(f"{name}: unknown top-level key(s) {unknown}; a spec has {list(SPEC_KEYS)}")
    if name != f"{spec['id']}.toml":
        raise RigError(f"{name}: file name does not match its id {spec['id']!r}")
    steps = spec["max_episode_steps"]
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise RigError(f"{name}: max_episode_steps must be a positive integer, got {steps!r}")
    return spec


def _freeze(value: Any) -> Any:
    if isinstance(value, dict):
        return MappingProxyType({k: _freeze(v) for k, v in value.items()})
    if isinstance(value, list):
        return tuple(_freeze(v) for v in value)
    return value


def _thaw(value: Any) -> Any:
    if isinstance(value, MappingProxyType):
        return {k: _thaw(v) for k, v in value.items()}
    if isinstance(value, tuple):
        return [_thaw(v) for v in value]
    return value


@cache
def _frozen_spec(env_id: str) -> MappingProxyType:
    """The spec of ``env_id``, parsed on first use and kept read-only."""
    for f in spec_files():
        if f.name == f"{env_id}.toml":
            return _freeze(read_spec(f))
    raise RigError(f"no spec file {env_id}.toml in {spec_directory()}")


def load_spec(env_id: str) -> dict[str, Any]:
    """The parsed spec of ``env_id`` (e.g. ``"BushRig-v0"``): a fresh plain copy of the one
    parse per id (``clear_spec_cache`` forgets them, for specs edited while running)."""
    return _thaw(_frozen_spec(env_id))


def clear_spec_cache() -> None:
    _frozen_spec.cache_clear()


def spec_kwargs(env_id: str, overrides: dict[str, Any]) -> dict[str, Any]:
    """The spec's ``[kwargs]`` updated by ``overrides``; an unknown key is refused."""
    kwargs = dict(load_spec(env_id)["kwargs"])
    unknown = sorted(set(overrides) - set(kwargs))
    if unknown:
        hints = "".join(f"; {k}: {RENAMED[k]}" for k in unknown if k in RENAMED)
        raise RigError(
            f"{env_id}: unknown argument(s) {unknown}; the spec knows {sorted(kwargs)}{hints}"
        )
    kwargs.update(overrides)
    return kwargs


def max_episode_steps(env_id: str, value: Any = None) -> int:
    """``value`` checked as a positive integer, or the spec's ``max_episode_steps``."""
    if value is None:
        return int(load_spec(env_id)["max_episode_steps"])
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise RigError(f"max_episode_steps must be a positive integer, got {value!r}")
    return int(value)
