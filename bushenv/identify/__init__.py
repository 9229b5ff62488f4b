"""Identification: a model from one measured record (displacement x, force f, sample time dt).

``fit_model(name, x, f, dt, seed=0, progress=True, **options)`` dispatches on the registry name:

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

from bushenv.identify.linear import IdentificationError, fit_linear
from bushenv.models.base import BushingModel


def fit_model(
    name: str,
    x: np.ndarray,
    f: np.ndarray,
    dt: float,
    seed: int = 0,
    progress: bool = True,
    **options: Any,
) -> BushingModel:
    """Identify model ``name`` from the record (x m, f N) sampled every ``dt`` s."""
    if name == "linear":
        return fit_linear(x, f, dt, seed=seed, progress=progress, **options)
    if name in ("nn", "hybrid"):
        from bushenv.identify.neural import fit_narx  # torch only when needed

        return fit_narx(name, x, f, dt, seed=seed, progress=progress, **options)
    if name == "boucwen":
        from bushenv.identify.global_search import fit_boucwen

        return fit_boucwen(x, f, dt, seed=seed, progress=progress, **options)
    raise IdentificationError(
        f"fit_model: no identification for model {name!r}; known: linear, nn, hybrid, boucwen"
    )


__all__ = ["IdentificationError", "fit_model"]
