"""A model or reference resolved once, where it enters: ``ResolvedModel``.

A user names a bushing model by a registered name (``"nn"``), a model file (``my.npz``) or an
object. ``resolve_model`` turns that into one immutable value -- the key a report files it
under, the spec it records, the ready model, the file behind it with its sha256, and the model
card beside that file -- and everything after takes the value: nothing resolves the name, hashes
the file or reads the card again. (As stable-baselines3's ``maybe_make_env`` turns an id into
an env once.)
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bushenv.models import (
    MODELS,
    BushingModel,
    file_hash,
    get_model,
    get_reference,
    model_file,
)


@dataclass(frozen=True)
class ResolvedModel:
    """A model as resolved at the edge (see the module doc)."""

    key: str  # the report key: a registered name, a model file's stem, an object's label
    spec: str  # as recorded: the name, the file as given, or "<name object>"
    model: BushingModel = field(repr=False, compare=False)
    file: Path | None  # the file behind it (a shipped default or the file given); else None
    sha256: str | None  # of that file's bytes
    card: dict | None = field(default=None, repr=False, compare=False)  # see ``read_card``
    card_file: Path | None = None  # where the card was read (``MODEL.card.json``)
    registered: bool = False  # given by a name in ``MODELS``


def is_file_spec(spec: Any) -> bool:
    """A spec that names a file (not a registered name, not an object)."""
    return isinstance(spec, str | os.PathLike) and str(spec) not in MODELS


def spec_label(spec: Any) -> str:
    """How a spec is recorded: the name or the path as given; an object as ``<name object>``."""
    if isinstance(spec, BushingModel):
        return f"<{spec.name or type(spec).__name__} object>"
    return os.fspath(spec)


def report_key(spec: Any) -> str:
    """The key a model goes by in a report: a name, or a model file's stem."""
    if isinstance(spec, BushingModel):
        return spec.name or type(spec).__name__
    text = os.fspath(spec)
    return Path(text).stem if text.endswith((".npz", ".fmu")) else text


def read_card(spec: Any):
    """The ``ModelCard`` beside a model file (checked against the file), or None: read from
    disk here and nowhere else in an attack (``resolve_model(..., card=True)``)."""
    if not is_file_spec(spec) or not Path(spec).is_file():
        return None
    from bushenv.identify.card import card_paths, load_card

    if not card_paths(spec)[0].is_file():
        return None
    return load_card(spec)


def resolved(
    spec: Any,
    model: BushingModel,
    axis: str,
    *,
    card: bool = False,
    key: str | None = None,
) -> ResolvedModel:
    """The value for a model already built from ``spec`` (the one place that hashes its file
    and, with ``card``, reads its card). ``key`` overrides the report key."""
    path = None if isinstance(spec, BushingModel) else model_file(spec, axis)
    if path is not None and not path.is_file():
        path = None
    model_card = read_card(spec) if card else None
    return ResolvedModel(
        key=report_key(spec) if key is None else key,
        spec=spec_label(spec),
        model=model,
        file=path,
        sha256=file_hash(path) if path is not None else None,
        card=None if model_card is None else model_card.data,
        card_file=None if model_card is None else model_card.path,
        registered=isinstance(spec, str) and spec in MODELS,
    )


def resolve_model(
    spec: Any,
    axis: str = "axial",
    dt: float | None = None,
    *,
    reference: bool = False,
    card: bool = False,
    coords: int = 1,
    wanted_by: str = "",
) -> ResolvedModel:
    """``spec`` (a registered name, a model file or an object) resolved over ``coords``
    coordinates: loaded (as a reference with ``reference``: ``get_reference``), its file hashed
    and, with ``card``, its card read. Only the model under test and the reference need their
    cards (they set the scales and are vetted), so the others do not read theirs. Over several
    coordinates a registered name is its preset's reference form (without load-cell noise),
    whatever its role, and ``dt`` None takes a file at its own rate (a name at the papers');
    a file of another number of coordinates is refused, naming ``wanted_by``."""
    if coords == 1:
        model = (get_reference if reference else get_model)(spec, axis=axis, dt=dt)
    else:
        preset = MODELS[spec].reference_preset if isinstance(spec, str) and spec in MODELS else None
        model = get_model(spec, dt=dt, preset=preset, coords=coords, wanted_by=wanted_by)
    return resolved(spec, model, axis, card=card)
