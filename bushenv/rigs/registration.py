"""Register every spec in ``envs/`` with Gymnasium (``import bushenv`` calls ``register_all``).

A spec's top-level keys ``id``, ``entry_point`` and (optional) ``vector_entry_point`` go to
``gymnasium.register``; its ``[kwargs]`` table becomes the registered defaults, which
``gym.make(id, key=value)`` overrides. The episode length lives in the spec (``episode_steps``)
and the environments truncate themselves, so no ``TimeLimit`` wrapper is registered.
"""

from __future__ import annotations

import gymnasium as gym

from bushenv.rigs.common import read_spec, spec_files


def register_all() -> list[str]:
    """Register (or re-register) every spec; returns the ids."""
    ids = []
    for path in spec_files():
        spec = read_spec(path)
        env_id = spec["id"]
        if env_id in gym.registry:
            del gym.registry[env_id]
        gym.register(
            id=env_id,
            entry_point=spec["entry_point"],
            vector_entry_point=spec.get("vector_entry_point"),
            kwargs=dict(spec["kwargs"]),
        )
        ids.append(env_id)
    return ids
