"""Identification: a model from measured records (displacement x m, force f N, one sample rate).

``fit(records, model="nn", options={...}, seed=0)`` calls the identification the model's
registry entry names (``bushenv.models.registry.MODELS``: ``fit`` and its ``options``
dataclass); ``bushenv fit`` is its command (``command.py``), which also writes a model card
(``card.py``). Several records train together, each its own history.

| name      | method                                              | module             |
|-----------|-----------------------------------------------------|--------------------|
| "linear"  | least squares of f on [x, v] (seed 000 §4.1)        | ``linear.py``      |
| "nn"      | network chosen on validation, then the NARX training | ``neural.py``      |
| "hybrid"  | least-squares backbone + the same NARX training     | ``neural.py``      |
| "boucwen" | differential evolution on eq. 6 + Powell polish     | ``global_search.py`` |

``fit_model(name, x, f, dt, seed=0, progress=True, v=None, **options)`` does the same for one
record given as arrays. Every method is deterministic given ``seed`` (budgets are iterations,
generations and evaluations; a wall-clock limit only when asked for, ``time_limit_s``); long
ones print progress lines with an estimate of the time left on stderr.
"""

from __future__ import annotations

import inspect
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv.identify.data import IdentificationError, TrainingSet, check_record, training_set
from bushenv.identify.options import options_of
from bushenv.models.base import BushingModel
from bushenv.models.registry import MODELS
from bushenv.progress import ProgressSpec


@dataclass
class FitResult:
    """An identified model and how it was made (what a model card records).

    ``records`` are the objects given to ``fit`` (``bushenv.records.Record`` when they came
    from files), ``options`` the options dataclass instance, ``seconds`` the wall time.
    """

    model: BushingModel
    name: str
    options: Any
    records: list
    data: TrainingSet
    seed: int
    seconds: float


def fittable_models() -> list[str]:
    """Registered models that have an identification (the choices of ``bushenv fit``)."""
    return [n for n, e in MODELS.items() if e.fit is not None]


def options_class(name: str) -> type:
    """The options dataclass of the registered model ``name`` (imports no training code)."""
    entry = MODELS[name] if name in MODELS else None
    if entry is None or entry.fit is None:
        raise IdentificationError(
            f"no identification for model {name!r}; known: {', '.join(fittable_models())}"
        )
    return entry.options_class()


def fit_method(name: str) -> tuple[Any, type]:
    """(identification function, options class) of the registered model ``name``."""
    cls = options_class(name)
    return MODELS[name].fit_function(), cls


def fit(
    records: Sequence,
    model: str = "nn",
    options: Any = None,
    seed: int = 0,
    progress: ProgressSpec = True,
    velocities: Sequence | None = None,
    loss_terms: Sequence = (),
) -> FitResult:
    """Identify ``model`` from ``records`` (``bushenv.records.Record`` objects or CSV file
    paths, one sample rate).

    Parameters
    ----------
    options : dict or the model's options dataclass, optional
        Names as in ``bushenv fit --help`` (``n_past_x`` for ``--n-past-x``); unknown names
        are refused, naming the model's options.
    progress : bool or callable
        Progress lines on stderr (True), none (False), or each line to a callable.
    velocities : sequence of (T,) arrays or None, optional
        Per record, the velocity (m/s) instead of the central difference of x.
    loss_terms : sequence, optional
        Extra training losses (NARX models only; ``bushenv.identify.neural.LossTerm``).
    """
    fit_function, options_type = fit_method(model)
    opts = options_of(options_type, options, model)
    records = [_as_record(r) for r in records]
    data = training_set(records, velocities)
    extra = {}
    if loss_terms:
        if "loss_terms" not in inspect.signature(fit_function).parameters:
            raise IdentificationError(f"model {model!r} takes no loss terms")
        extra["loss_terms"] = list(loss_terms)
    t0 = time.perf_counter()
    fitted = fit_function(data, opts, seed=seed, progress=progress, **extra)
    seconds = time.perf_counter() - t0
    # a method that chooses options itself (the NARX network's size) says which it used
    opts = (getattr(fitted, "training", None) or {}).pop("options_used", None) or opts
    return FitResult(fitted, model, opts, records, data, int(seed), seconds)


def _as_record(item: Any) -> Any:
    if isinstance(item, str | os.PathLike):
        from bushenv.records import load_csv

        return load_csv(item)
    return item


def fit_model(
    name: str,
    x: np.ndarray,
    f: np.ndarray,
    dt: float,
    seed: int = 0,
    progress: ProgressSpec = True,
    v: np.ndarray | None = None,
    **options: Any,
) -> BushingModel:
    """Identify model ``name`` from one record (x m, f N, (T,) each) sampled every ``dt`` s.

    ``options`` are the fields of the model's options dataclass; ``v`` (m/s) replaces the
    central-difference velocity."""
    try:
        fit_function, options_class = fit_method(name)
    except IdentificationError as exc:
        raise IdentificationError(f"fit_model: {exc}") from None
    opts = options_of(options_class, options, name)
    data = TrainingSet((check_record(x, f, dt, v),), float(dt))
    return fit_function(data, opts, seed=seed, progress=progress)


def __getattr__(name: str) -> Any:
    # The model card reads files and plots; imported on first use only.
    if name in ("load_card", "ModelCard", "CardError"):
        from bushenv.identify import card

        return getattr(card, name)
    raise AttributeError(f"module 'bushenv.identify' has no attribute {name!r}")


__all__ = [
    "CardError",
    "FitResult",
    "IdentificationError",
    "ModelCard",
    "fit",
    "fit_method",
    "fit_model",
    "fittable_models",
    "load_card",
    "options_class",
]
