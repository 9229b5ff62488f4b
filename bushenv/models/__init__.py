"""Bushing force models behind one protocol (see ``base.py``) and the name resolver.

``get_model("nn", axis="axial")`` gives the default trained model shipped with the package;
``get_model("path/to/file.npz")`` loads a saved file; a model object passes through.
"""

from __future__ import annotations

import importlib
import os
from importlib import resources
from pathlib import Path

from bushenv.models.base import (
    MODEL_REGISTRY,
    PAPER_DT,
    BushingModel,
    ModelError,
    file_hash,
    load_model,
    register,
)

# Modules that register models; imported lazily so a missing optional part cannot break import.
_MODEL_MODULES = (
    "bushenv.models.linear",
    "bushenv.models.narx",
    "bushenv.models.hybrid",
    "bushenv.models.boucwen",
    "bushenv.reference.rubber",
)
AXES = ("axial", "radial")
TRAINED = ("nn", "hybrid", "boucwen")  # names whose defaults are identified files in the package


def _load_registry() -> None:
    for mod in _MODEL_MODULES:
        try:
            importlib.import_module(mod)
        except ModuleNotFoundError as exc:
            if exc.name != mod:  # a real missing dependency, not a model file absent here
                raise


def default_model_path(name: str, axis: str) -> Path:
    """Where the shipped identified model ``name`` for ``axis`` lives inside the package."""
    return Path(str(resources.files("bushenv") / "data" / "models" / f"{axis}_{name}.npz"))


def model_names() -> list[str]:
    _load_registry()
    return sorted(MODEL_REGISTRY)


def get_model(
    spec: str | os.PathLike | BushingModel, axis: str = "axial", dt: float | None = None
) -> BushingModel:
    """Resolve a registered name, a model file or a model object to a ready model."""
    if isinstance(spec, BushingModel):
        if dt is not None and abs(spec.dt - dt) > 1e-9 * dt:
            raise ModelError(f"model {spec.name} runs at dt={spec.dt:.6g} s, expected {dt:.6g} s")
        return spec
    _load_registry()
    if axis not in AXES:
        raise ModelError(f"unknown axis {axis!r}; known: {list(AXES)}")
    text = os.fspath(spec)
    if not text.strip():
        raise ModelError(f"empty model name; known names: {sorted(MODEL_REGISTRY)} or a .npz file")
    if text in MODEL_REGISTRY:
        if text in TRAINED:
            path = default_model_path(text, axis)
            if not path.is_file():
                raise ModelError(
                    f"no default {text!r} model for axis {axis!r} in the package ({path}); "
                    "run scripts/train_default_models.py"
                )
            return load_model(path, dt=dt)
        model = MODEL_REGISTRY[text].preset(axis=axis, dt=dt or PAPER_DT)
        return model
    if text.endswith(".npz") or Path(text).exists():
        return load_model(text, dt=dt)
    raise ModelError(
        f"unknown model {text!r}; known names: {sorted(MODEL_REGISTRY)} or a .npz file"
    )


__all__ = [
    "AXES",
    "MODEL_REGISTRY",
    "PAPER_DT",
    "BushingModel",
    "ModelError",
    "default_model_path",
    "file_hash",
    "get_model",
    "load_model",
    "model_names",
    "register",
]
