"""Identification: a model from measured records (displacement, force, one sample rate) of a
bushing of any number of coordinates C.

``fit(records, model="nn", options={...}, seed=0)`` reads C from the records (one: the
``time,displacement,force`` files; three: axial, radial, rotation) and calls the identification
the model's registry entry names for C (``bushenv.models.registry.MODELS``: ``fit`` and its
``options`` dataclass, ``ModelEntry.fit_function(C)``); ``bushenv fit`` is its command, which
also writes a model card (``card.py``). Several records train together, each its own history.

| name      | C = 1 (module)                              | C = 3 (module)                      |
|-----------|---------------------------------------------|-------------------------------------|
| linear    | least squares of f on [x, v] (linear)       | the same, 3x3 K and C (linear)      |
| nn        | chosen network, NARX training (neural)      | the MIMO network (mimo)             |
| nn-axis   | -                                           | a network per coordinate (mimo)     |
| hybrid    | least-squares backbone + NARX training      | 3x3 backbone + MIMO network (mimo)  |
| boucwen   | evolution on eq. 6 + polish (global_search) | projection search (vector_boucwen)  |
| hybrid-bw | -                                           | vector Bouc-Wen + MIMO net (mimo)   |

``fit_model(name, x, f, dt, seed=0, progress=True, v=None, **options)`` does the same for one
record given as arrays ((T,) or (T, C)). Every method is deterministic given ``seed`` (budgets
are iterations, generations and evaluations; a wall-clock limit only when asked for,
``time_limit_s``); long ones print progress lines with an estimate of the time left on stderr.
"""

from __future__ import annotations

import inspect
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bushenv.identify.data import IdentificationError, TrainingSet, check_record, training_set
from bushenv.identify.options import options_of
from bushenv.models.base import BushingModel
from bushenv.models.registry import MODELS, coordinate_words, names_for
from bushenv.progress import ProgressSpec


@dataclass
class FitResult:
    """An identified model and how it was made (what a model card records).

    ``records`` are the objects given to ``fit`` (``bushenv.records.Record`` when they came
    from files), ``options`` the options dataclass instance, ``seconds`` the wall time,
    ``info`` the identification's own summary lines for the card (evaluations, a network
    dropped, a certified check; empty where the training log says it all).
    """

    model: BushingModel
    name: str
    options: Any
    records: list
    data: TrainingSet
    seed: int
    seconds: float
    info: dict[str, Any] = field(default_factory=dict)


def fittable_models(coords: int = 1) -> list[str]:
    """Registered models with an identification over ``coords`` coordinates (the choices of
    ``bushenv fit`` on such records)."""
    return list(names_for(coords, fittable=True))


def options_class(name: str, coords: int = 1) -> type:
    """The options dataclass of the registered model ``name`` over ``coords`` coordinates
    (imports no training code)."""
    entry = MODELS[name] if name in MODELS else None
    if entry is not None and entry.fits(coords):
        return entry.options_class(coords)
    known = ", ".join(fittable_models(coords))
    where = [c for c in (entry.coordinate_counts() if entry else ()) if entry.fits(c)]
    if where:
        other = " or ".join(coordinate_words(c).split(":")[0] for c in where)
        raise IdentificationError(
            f"model {name} is {other}, identified from records of {_records_of(where)}, not "
            f"from {_records_of([coords])}: for these records choose one of {known}"
        )
    raise IdentificationError(
        f"no identification for model {name!r}; known for {_records_of([coords])}: {known}"
    )


def _records_of(counts: Sequence[int]) -> str:
    from bushenv.record_columns import columns_of

    return " or ".join(
        f"{'one axis' if c == 1 else f'{c} axes'} (header '{columns_of(c).header_text}')"
        for c in counts
    )


def fit_method(name: str, coords: int = 1) -> tuple[Any, type]:
    """(identification function, options class) of the registered model ``name`` over
    ``coords`` coordinates."""
    cls = options_class(name, coords)
    return MODELS[name].fit_function(coords), cls


def fit(
    records: Sequence,
    model: str = "nn",
    options: Any = None,
    seed: int = 0,
    progress: ProgressSpec = True,
    velocities: Sequence | None = None,
    loss_terms: Sequence = (),
    dt: float | None = None,
) -> FitResult:
    """Identify ``model`` from ``records`` (``bushenv.records.Record`` objects, CSV file paths
    or, with ``dt``, (displacement, force) array pairs; one sample rate, one number of
    coordinates C: the identification is the one ``model`` has over C).

    Parameters
    ----------
    options : dict or the model's options dataclass, optional
        Names as in ``bushenv fit --help`` (``n_past_x`` for ``--n-past-x``); unknown names
        are refused, naming the model's options.
    progress : bool or callable
        Progress lines on stderr (True), none (False), or each line to a callable.
    velocities : sequence of (T,) arrays or None, optional
        Per record, the velocity (shaped as its displacement) instead of the central
        difference.
    loss_terms : sequence, optional
        Extra training losses (NARX models only; ``bushenv.identify.neural.LossTerm``).
    """
    records = [_as_record(r, i, dt) for i, r in enumerate(records)]
    data = training_set(records, velocities)
    fit_function, options_type = fit_method(model, data.n_coords)
    opts = options_of(options_type, options, model)
    extra = {}
    if loss_terms:
        if "loss_terms" not in inspect.signature(fit_function).parameters:
            raise IdentificationError(f"model {model!r} takes no loss terms")
        extra["loss_terms"] = list(loss_terms)
    t0 = time.perf_counter()
    fitted = fit_function(data, opts, seed=seed, progress=progress, **extra)
    seconds = time.perf_counter() - t0
    training = getattr(fitted, "training", None) or {}
    # a method that chooses options itself (the NARX network's size) says which it used
    opts = training.pop("options_used", None) or opts
    info = training.pop("info", None) or {}
    return FitResult(fitted, model, opts, records, data, int(seed), seconds, info)


def _as_record(item: Any, index: int, dt: float | None) -> Any:
    if isinstance(item, str | os.PathLike):
        from bushenv.record_files import load_record

        return load_record(item)
    if isinstance(item, tuple):
        from bushenv.records import Record

        if dt is None:
            raise IdentificationError(
                f"record {index + 1} is a pair of arrays: give its sample time, fit(..., dt=...)"
            )
        return Record.from_arrays(*item, dt=dt, name=f"record {index + 1}")
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
    """Identify model ``name`` from one record sampled every ``dt`` s: x and f (T,) each for
    one coordinate (m, N), (T, C) each for C.

    ``options`` are the fields of the model's options dataclass; ``v`` (shaped as x) replaces
    the central-difference velocity."""
    coords = 1 if np.ndim(x) == 1 else int(np.shape(x)[1])
    try:
        fit_function, options_class = fit_method(name, coords)
    except IdentificationError as exc:
        raise IdentificationError(f"fit_model: {exc}") from None
    opts = options_of(options_class, options, name)
    names = MODELS[name].model_class(coords).coords
    data = TrainingSet((check_record(x, f, dt, v),), float(dt), tuple(names))
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
