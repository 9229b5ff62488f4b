"""Identification: a model from one measured record (displacement x, force f, sample time dt).

``fit_model(name, x, f, dt, seed=0, progress=True, **options)`` calls the identification the
model's registry entry names (``bushenv.models.registry.MODELS``):

| name      | method                                              | module             |
|-----------|-----------------------------------------------------|--------------------|
| "linear"  | least squares of f on [x, v] (seed 000 §4.1)        | ``linear.py``      |
| "nn"      | torch: one step ahead, then free-run fine-tuning    | ``neural.py``      |
| "hybrid"  | least-squares backbone + the same NARX training     | ``neural.py``      |
| "boucwen" | differential evolution on eq. 6 + Powell polish     | ``global_search.py`` |

``v`` (velocity, m/s) may be passed in ``options``; it defaults to the central difference of x.
Every method is deterministic given ``seed``; long ones print a progress line every few seconds.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.identify.linear import IdentificationError
from bushenv.models.base import BushingModel
from bushenv.models.registry import MODELS


def fit_model(
    name: str,
    x: np.ndarray,
    f: np.ndarray,
    dt: float,
    seed: int = 0,
    progress: bool = True,
    **options: Any,
) -> BushingModel:
    """Identify model ``name`` from the record (x m, f N) sampled every ``dt`` s.

    The method is the registry entry's ``fit`` (``bushenv.models.registry.MODELS``)."""
    fit = MODELS[name].fit_function() if name in MODELS else None
    if fit is None:
        known = [n for n, e in MODELS.items() if e.fit is not None]
        raise IdentificationError(
            f"fit_model: no identification for model {name!r}; known: {', '.join(known)}"
        )
    return fit(x, f, dt, seed=seed, progress=progress, **options)


__all__ = ["IdentificationError", "fit_model"]
