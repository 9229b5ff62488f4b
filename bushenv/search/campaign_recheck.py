"""Stage 3 of an attack, recheck: every other model of the attack runs every profile that broke
the target (the hybrid and the control must say whether they fail where it failed)."""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from bushenv.progress import Progress
from bushenv.search.campaign_resolve import Resolved
from bushenv.search.campaign_search import Searched

SHOWN_FAILURES = 20  # failures listed per model; the count is of all


@dataclass(frozen=True)
class Rechecked:
    """How many profiles broke the target, and per other model what it did on them:
    ``{"diverged", "failures", "worst_robustness", "worst_deviation"}``."""

    profiles: int
    models: Mapping[str, Mapping[str, Any]]

    def to_json(self) -> dict[str, Any]:
        return {"profiles": self.profiles, **{k: dict(v) for k, v in self.models.items()}}

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> Rechecked:
        models = {k: v for k, v in d.items() if k != "profiles"}
        return cls(int(d.get("profiles", 0)), MappingProxyType(models))


def recheck(resolved: Resolved, searched: Searched, threads: int, progress: Progress) -> Rechecked:
    """Run every model but the target on every profile that broke the target."""
    target = resolved.target_key
    profiles, meta = searched.failures(target)
    out: dict[str, Any] = {}
    for key in resolved.models:
        if key == target:
            continue
        out[key] = _recheck_one(resolved, key, profiles, meta, threads)
        progress.say(
            f"recheck: {key} diverged on {out[key]['diverged']} of {len(profiles)} profiles "
            f"that broke {target}"
        )
    return Rechecked(len(profiles), MappingProxyType(out))


def _recheck_one(
    resolved: Resolved, key: str, profiles: list, meta: list[dict], threads: int
) -> dict[str, Any]:
    entry: dict[str, Any] = {"diverged": 0, "failures": []}
    if not profiles:
        return entry
    with resolved.evaluator(key, threads) as ev:
        v = ev.evaluate(profiles).verdict
    entry["diverged"] = int(v.diverged.sum())
    entry["worst_robustness"] = float(np.min(v.robustness))
    entry["worst_deviation"] = float(np.max(v.worst_deviation))
    first_axis = getattr(v, "first_axis", None)  # over several coordinates: which failed
    if first_axis is not None:
        failed = [str(a) for a, d in zip(first_axis, v.diverged, strict=True) if d]
        entry["by_axis"] = dict(Counter(failed).most_common())
    for b in np.flatnonzero(v.diverged)[:SHOWN_FAILURES]:
        entry["failures"].append(
            {
                **v.row(int(b)),
                "family": meta[b]["family"],
                "searcher": meta[b]["searcher"],
                "index": int(b),
            }
        )
    return entry
