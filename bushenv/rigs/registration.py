"""Register every spec in ``envs/`` with Gymnasium (``import bushenv`` calls ``register_all``).

Each spec is registered twice: under its plain id (``BushRig-v0``, as before) and in the
``bushenv/`` namespace (``bushenv/BushRig-v0``), so ``gym.make("bushenv:bushenv/BushRig-v0")``
works in a fresh process: Gymnasium imports ``bushenv`` for the ``module:`` prefix, and the
import registers. The spec's ``id``, ``entry_point``, ``vector_entry_point`` and
``max_episode_steps`` go to ``gymnasium.register``; its ``[kwargs]`` table becomes the
registered defaults, which ``gym.make(id, key=value)`` overrides.
"""

from __future__ import annotations

import gymnasium as gym

from bushenv.rigs.specs import read_spec, spec_files

NAMESPACE = "bushenv"


def register_all() -> list[str]:
    """Register (or re-register) every spec under its id and ``bushenv/<id>``; returns the ids
    (without namespace)."""
    ids = []
    for path in spec_files():
        spec = read_spec(path)
        for env_id in (spec["id"], f"{NAMESPACE}/{spec['id']}"):
            if env_id in gym.registry:
                del gym.registry[env_id]
            gym.register(
                id=env_id,
                entry_point=spec["entry_point"],
                vector_entry_point=spec.get("vector_entry_point"),
                max_episode_steps=spec["max_episode_steps"],
                kwargs=dict(spec["kwargs"]),
            )
        ids.append(spec["id"])
    return ids
