"""Bushing force models behind one protocol (``base.py``), their registry and the resolvers.

``get_model("nn", axis="axial")`` gives the default trained model shipped with the package;
``get_model("path/to/file.npz")`` loads a saved file; a model object is copied (or passed
through with ``copy=False``). ``get_reference`` resolves the model a verdict is judged against.
Nothing falls back silently: an unknown name or a missing file is a ``ModelError``.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

from bushenv.models.base import (
    AXES,
    DT_TOLERANCE,
    PAPER_DT,
    BushingModel,
    ModelError,
    has_preset,
)
from bushenv.models.files import file_hash, load_model, params_sha, wrong_coordinates
from bushenv.models.registry import MODELS, Form, ModelEntry, coordinate_words, names_for
from bushenv.registry import Registry, load_entry_point

# Model files other than bushenv's own .npz, by suffix: a loader living above the models (the
# FMU's, in bushenv.export) is named by its "module:attribute" and imported on first use.
MODEL_FILES: Registry = Registry("model file type", ModelError)
MODEL_FILES.add(".fmu", "bushenv.export.fmu_model:load_fmu")

ModelSpec = str | os.PathLike | BushingModel


def default_model_path(name: str, axis: str) -> Path:
    """Where the shipped identified model ``name`` for ``axis`` lives inside the package."""
    return Path(str(resources.files("bushenv") / "data" / "models" / f"{axis}_{name}.npz"))


def model_names() -> list[str]:
    return list(MODELS.names())


def check_axis(axis: str) -> str:
    if axis not in AXES:
        raise ModelError(f"unknown axis {axis!r}; known: {', '.join(AXES)}")
    return axis


def model_file(spec: ModelSpec, axis: str) -> Path | None:
    """The file behind ``spec``: a shipped default for a registered name, the path itself for a
    file, None for presets and objects."""
    if isinstance(spec, BushingModel):
        return None
    text = os.fspath(spec)
    if text in MODELS:
        return default_model_path(text, axis) if MODELS[text].shipped else None
    return Path(text)


def get_model(
    spec: ModelSpec,
    axis: str = "axial",
    dt: float | None = None,
    copy: bool = True,
    preset: dict | None = None,
    coords: int | None = 1,
    wanted_by: str = "",
) -> BushingModel:
    """Resolve a registered name, a model file or a model object to a ready model.

    Parameters
    ----------
    spec : str, path or BushingModel
        A name in ``MODELS`` (shipped defaults load their file for ``axis``; others build their
        ``preset``), a ``.npz`` model file, an ``.fmu`` (co-simulation, through FMPy), or a
        model object.
    axis : {"axial", "radial"}
    dt : float, optional
        Required sample time, s; a model at another rate is refused, naming both rates.
    copy : bool
        A model object is copied (its own state) unless False.
    preset : dict, optional
        Extra keyword arguments of a registered preset (e.g. ``{"measurement": False}``).
    coords : int or None
        The number of coordinates wanted (1 by default; 3 for axial, radial and rotation); a
        name builds its form of that many, a file or an object of another count is refused,
        naming ``wanted_by`` and what takes it. None: any (a name then means one coordinate).
    """
    if isinstance(spec, BushingModel):
        if coords is not None and spec.n_coords != coords:
            label = f"model {spec.name}"
            raise ModelError(wrong_coordinates(label, spec.n_coords, coords, wanted_by))
        if dt is not None and abs(spec.dt - dt) > DT_TOLERANCE * dt:
            raise ModelError(
                f"model {spec.name} runs at {1 / spec.dt:.6g} Hz (dt={spec.dt:.6g} s), "
                f"expected {1 / dt:.6g} Hz (dt={dt:.6g} s)"
            )
        return spec.copy() if copy else spec
    check_axis(axis)
    text = os.fspath(spec)
    if not text.strip():
        raise ModelError(f"empty model name; {MODELS.unknown_message(text)} or a .npz file")
    if text in MODELS:
        entry = MODELS[text]
        if coords not in (None, 1):
            try:
                cls = entry.model_class(coords)
            except ModelError as exc:
                raise ModelError(f"model {text!r}: {exc}") from None
            return _preset(text, cls, dt, {**entry.preset, **(preset or {})}, wanted_by)
        if entry.entry_point is None:
            raise ModelError(
                f"model {text!r} exists for {coordinate_words(entry.coordinate_counts()[0])} "
                f"only; {wanted_by or 'this'} needs a one-axis model ("
                f"{', '.join(names_for(1))} or a one-axis .npz file)"
            )
        if entry.shipped:
            path = default_model_path(text, axis)
            if not path.is_file():
                raise ModelError(
                    f"no default {text!r} model for axis {axis!r} in the package ({path}); "
                    "run scripts/train_default_models.py"
                )
            return load_model(path, dt=dt)
        options = {**entry.preset, **(preset or {})}
        return entry.model_class().preset(axis=axis, dt=dt or PAPER_DT, **options)
    suffix = Path(text).suffix.lower()
    if suffix in MODEL_FILES:  # e.g. an FMU, run through FMPy
        loader = MODEL_FILES[suffix]
        return (load_entry_point(loader) if isinstance(loader, str) else loader)(text, dt=dt)
    if text.endswith(".npz") or Path(text).exists():
        return load_model(text, dt=dt, coords=coords, wanted_by=wanted_by)
    raise ModelError(f"{MODELS.unknown_message(text)} or a .npz model file")


def _preset(name: str, cls: type, dt: float | None, options: dict | None, wanted_by: str):
    """The preset of a kind over several coordinates; a network without one says what to give."""
    if not has_preset(cls):
        raise ModelError(
            f"model {name!r} over {cls.coordinate_count()} coordinates has no preset (a network "
            f"must be trained): {wanted_by + ' needs' if wanted_by else 'give'} its .npz file "
            "(bushenv fit on records of as many coordinates writes one)"
        )
    return cls.preset(dt=dt or PAPER_DT, **(options or {}))


def get_reference(
    spec: ModelSpec = "rubber",
    axis: str = "axial",
    dt: float | None = None,
    coords: int | None = 1,
    wanted_by: str = "",
) -> BushingModel:
    """The model a verdict is judged against: as ``get_model``, with a registered name built
    with its entry's ``reference_preset`` (``"rubber"``: the specimen without the load cell's
    delay, inertia and noise)."""
    preset = None
    if not isinstance(spec, BushingModel) and os.fspath(spec) in MODELS:
        preset = MODELS[os.fspath(spec)].reference_preset
    return get_model(spec, axis=axis, dt=dt, preset=preset, coords=coords, wanted_by=wanted_by)


__all__ = [
    "AXES",
    "MODELS",
    "PAPER_DT",
    "BushingModel",
    "Form",
    "ModelEntry",
    "ModelError",
    "ModelSpec",
    "check_axis",
    "default_model_path",
    "file_hash",
    "get_model",
    "get_reference",
    "has_preset",
    "load_model",
    "model_file",
    "model_names",
    "names_for",
    "params_sha",
]
