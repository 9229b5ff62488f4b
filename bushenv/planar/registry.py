"""``PLANAR_MODELS``: the one list of planar (three-coordinate) bushing models, and their files.

Entries are ``"module:Class"`` strings, imported on first use (``model_class``), so this module
imports no model. Adding a planar model = one module + one line here.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from bushenv.models.base import ModelError
from bushenv.models.files import _archive, _check_parameter, _sample_time
from bushenv.planar.base import FORMAT, FORMAT_VERSION, PlanarModel, PlanarModelError
from bushenv.registry import Registry, load_entry_point

PLANAR_MODELS: Registry[str | type] = Registry("planar model", PlanarModelError)
PLANAR_MODELS.add("reference", "bushenv.planar.reference:PlanarRubber")
PLANAR_MODELS.add("linear", "bushenv.planar.linear:PlanarLinear")
PLANAR_MODELS.add("nn", "bushenv.planar.narx:PlanarNarx")
PLANAR_MODELS.add("nn-axis", "bushenv.planar.narx:PlanarNarxPerAxis")
PLANAR_MODELS.add("hybrid", "bushenv.planar.narx:PlanarHybrid")
PLANAR_MODELS.add("boucwen", "bushenv.planar.boucwen:PlanarBoucWen")
PLANAR_MODELS.add("hybrid-bw", "bushenv.planar.hybrid_bw:PlanarBoucWenHybrid")


def model_class(name: str) -> type:
    """The class registered as ``name`` (``PlanarModelError`` listing the known names)."""
    entry = PLANAR_MODELS[name]
    return load_entry_point(entry) if isinstance(entry, str) else entry


def load_planar_model(path: str | os.PathLike, dt: float | None = None) -> PlanarModel:
    """Read a file written by ``PlanarModel.save``; refuses, naming the file and the problem,
    anything else (one-axis model files included) with ``PlanarModelError``."""
    path = Path(path)
    try:
        files = _archive(path)
    except ModelError as exc:
        raise PlanarModelError(str(exc).replace("BushingModel.save", "PlanarModel.save")) from None
    meta = _meta(path, files)
    name = meta["model"]
    cls = model_class(name)
    try:
        file_dt = _sample_time(path, meta, dt)
        shapes, extra = meta.get("shapes", {}), meta.get("extra", {})
        if not isinstance(shapes, dict) or not isinstance(extra, dict):
            raise ModelError(f"{path}: corrupt __meta__ entry ('shapes', 'extra' must be objects)")
        for key in cls.param_names:
            if key in files or key not in cls.optional_params:
                _check_parameter(path, name, key, files, shapes.get(key))
    except ModelError as exc:
        raise PlanarModelError(str(exc)) from None
    try:
        return cls.from_params(files, file_dt, extra)
    except PlanarModelError as exc:
        raise PlanarModelError(f"{path}: {exc}") from None
    except (TypeError, ValueError, KeyError) as exc:
        raise PlanarModelError(
            f"{path}: parameters do not fit a planar {name} model: {exc}"
        ) from None


def _meta(path: Path, files: dict[str, np.ndarray]) -> dict:
    raw = files.pop("__meta__", None)
    if raw is None or raw.shape != () or raw.dtype.kind != "U":
        raise PlanarModelError(f"{path}: not a bushenv planar model file (no __meta__ string)")
    try:
        meta = json.loads(str(raw))
    except json.JSONDecodeError as exc:
        raise PlanarModelError(f"{path}: corrupt __meta__ entry: {exc}") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        got = meta.get("format") if isinstance(meta, dict) else None
        hint = (
            "; a one-axis model file: load it with bushenv.models.load_model"
            if (got == "bushenv-model")
            else ""
        )
        raise PlanarModelError(f"{path}: not a bushenv planar model file (format {got!r}){hint}")
    if meta.get("version") != FORMAT_VERSION:
        raise PlanarModelError(
            f"{path}: planar model file format version {meta.get('version')!r}, "
            f"this bushenv reads version {FORMAT_VERSION}"
        )
    name = meta.get("model")
    if not isinstance(name, str) or name not in PLANAR_MODELS:
        raise PlanarModelError(f"{path}: {PLANAR_MODELS.unknown_message(name)}")
    return meta
