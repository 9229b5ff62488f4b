"""Reading model files: ``load_model`` and ``file_hash``.

The format is written by ``BushingModel.save`` (see ``base.py``): an ``.npz`` archive read with
``allow_pickle=False`` -- loading never runs code -- whose ``__meta__`` entry names the
registered model (``registry.MODELS``) that rebuilds itself from the arrays.
"""

from __future__ import annotations

import hashlib
import json
import os
import zipfile
from pathlib import Path

import numpy as np

from bushenv.models.base import DT_TOLERANCE, FORMAT_VERSION, BushingModel, ModelError
from bushenv.models.registry import MODELS

ZIP_MAGIC = b"PK\x03\x04"
LEGACY_THREE_AXIS = "bushenv-planar-model"  # three-axis files' tag before the one format
_KNOWN_MAGIC = (
    (b"\x93NUMPY", "a single .npy array, not an .npz archive"),
    (b"\x80", "a Python pickle (bushenv never loads pickles: they can run code)"),
    (b"\x89PNG", "a PNG image"),
    (b"\x1f\x8b", "a gzip file"),
    (b"%PDF", "a PDF document"),
)


def _not_npz_reason(head: bytes) -> str:
    """What a file that is not a zip archive looks like, from its first bytes."""
    if not head:
        return "empty file"
    for magic, what in _KNOWN_MAGIC:
        if head.startswith(magic):
            return what
    if b"\x00" not in head:
        try:
            head.decode("utf-8")
            return "a text file"
        except UnicodeDecodeError:
            pass
    return f"unknown binary data (starts with {head[:8]!r})"


def load_model(
    path: str | os.PathLike,
    dt: float | None = None,
    coords: int | None = None,
    wanted_by: str = "",
) -> BushingModel:
    """Read a model file written by ``BushingModel.save``, of any number of coordinates.

    Refuses with ``ModelError``, naming the file and what was expected: a missing file, a
    folder, anything that is not an npz archive (text, an image, a pickle, a lone .npy), a
    truncated or damaged archive, object (pickled) entries -- never unpickled --, another
    format or version, an unknown model name, a corrupt header, missing, non-numeric or
    wrongly shaped parameters, (when ``dt`` is given) a sample time other than ``dt`` and
    (when ``coords`` is given) a model of another number of coordinates, then naming
    ``wanted_by`` (what needs it) and what takes the model instead. Files of three-axis models
    written under their former format tag load as they always did.
    """
    path = Path(path)
    files = _archive(path)
    meta = _header(path, files)
    name, count = meta["model"], _coordinate_count(path, meta)
    if coords is not None and count != coords:
        raise ModelError(wrong_coordinates(str(path), count, coords, wanted_by))
    try:
        cls = MODELS[name].model_class(count)
    except ModelError as exc:
        raise ModelError(f"{path}: {exc}") from None
    file_dt = _sample_time(path, meta, dt)
    shapes, extra = meta.get("shapes", {}), meta.get("extra", {})
    if not isinstance(shapes, dict) or not isinstance(extra, dict):
        raise ModelError(f"{path}: corrupt __meta__ entry ('shapes' and 'extra' must be objects)")
    for key in cls.param_names:
        if key in files or key not in cls.optional_params:
            _check_parameter(path, name, key, files, shapes.get(key))
    try:
        return cls.from_params(files, file_dt, extra)
    except ModelError as exc:
        raise ModelError(f"{path}: {exc}") from None
    except (TypeError, ValueError, KeyError) as exc:
        raise ModelError(f"{path}: parameters do not fit a {name} model: {exc}") from None


# What takes a model of C coordinates, for the message that refuses it elsewhere.
TAKES = {
    1: "bushenv attack (--env rig or quartercar), certify, export, card, measure, and "
    "gym.make('BushRig-v0' or 'QuarterCar-v0', model=FILE)",
    3: "bushenv attack --env rig3, certify, export, card, measure --axes 3, and "
    "gym.make('BushRig3-v0' or 'HalfCar-v0', model=FILE) or "
    "gym.make('QuarterCar-v0', arm_bushing=FILE)",
}


def wrong_coordinates(label: str, have: int, want: int, wanted_by: str = "") -> str:
    """The message refusing ``label``, a model of ``have`` coordinates, where ``want`` are
    needed: what it is, what needed another, and what takes it."""
    from bushenv.models.registry import coordinate_words

    need = f"{wanted_by} needs" if wanted_by else "this needs"
    takes = TAKES.get(have)
    return f"{label} is {coordinate_words(have)}; {need} {coordinate_words(want).split(':')[0]}" + (
        f". A {have}-coordinate model goes to: {takes}" if takes else ""
    )


def _coordinate_count(path: Path, meta: dict) -> int:
    """C from the header: its ``coords`` list, 3 for the former three-axis tag, else 1."""
    if meta.get("format") == LEGACY_THREE_AXIS:
        return 3
    names = meta.get("coords", ["deflection"])
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise ModelError(f"{path}: corrupt __meta__ entry (coords {names!r}, expected names)")
    return len(names)


def _archive(path: Path) -> dict[str, np.ndarray]:
    """Every array of the ``.npz`` at ``path``, read without unpickling anything."""
    if not path.exists():
        raise ModelError(f"{path}: no such model file")
    if not path.is_file():
        raise ModelError(f"{path}: not a regular file; expected a bushenv model file (.npz)")
    with open(path, "rb") as fh:
        head = fh.read(16)
    if not head.startswith(ZIP_MAGIC):
        raise ModelError(
            f"{path}: not a bushenv model file: {_not_npz_reason(head)}; expected an .npz "
            "archive written by BushingModel.save"
        )
    try:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except ValueError as exc:
        if "allow_pickle" in str(exc) or "pickled" in str(exc):
            raise ModelError(
                f"{path}: holds pickled (object) data, which bushenv never loads (it could run "
                "code); expected numeric arrays written by BushingModel.save"
            ) from None
        raise ModelError(f"{path}: damaged .npz archive: {exc}") from None
    except (zipfile.BadZipFile, OSError, EOFError, KeyError, TypeError) as exc:
        raise ModelError(
            f"{path}: damaged or truncated .npz archive ({type(exc).__name__}: {exc}); "
            "expected a file written by BushingModel.save"
        ) from None
    except Exception as exc:  # zlib.error and the like from a damaged member
        raise ModelError(f"{path}: damaged .npz archive ({type(exc).__name__}: {exc})") from None


def _header(path: Path, files: dict[str, np.ndarray]) -> dict:
    """The ``__meta__`` JSON (removed from ``files``), checked: format, version, model name."""
    if "__meta__" not in files:
        raise ModelError(f"{path}: not a bushenv model file (no __meta__ entry)")
    raw = files.pop("__meta__")
    if raw.shape != () or raw.dtype.kind != "U":
        raise ModelError(
            f"{path}: corrupt __meta__ entry (a {raw.dtype} array of shape {list(raw.shape)}, "
            "expected one JSON string)"
        )
    try:
        meta = json.loads(str(raw))
    except json.JSONDecodeError as exc:
        raise ModelError(f"{path}: corrupt __meta__ entry: {exc}") from None
    if not isinstance(meta, dict) or meta.get("format") not in ("bushenv-model", LEGACY_THREE_AXIS):
        got = meta.get("format") if isinstance(meta, dict) else None
        tag = "format tag missing" if got is None else f"format tag {got!r}"
        raise ModelError(f"{path}: not a bushenv model file ({tag}, expected 'bushenv-model')")
    if meta.get("version") != FORMAT_VERSION:
        raise ModelError(
            f"{path}: model file format version {meta.get('version')!r}, "
            f"this bushenv reads version {FORMAT_VERSION}"
        )
    name = meta.get("model")
    if not isinstance(name, str) or name not in MODELS:
        raise ModelError(f"{path}: {MODELS.unknown_message(name)}")
    return meta


def _sample_time(path: Path, meta: dict, dt: float | None) -> float:
    file_dt = meta.get("dt")
    if isinstance(file_dt, bool) or not isinstance(file_dt, int | float):
        raise ModelError(f"{path}: invalid dt {file_dt!r} in the header, expected seconds")
    file_dt = float(file_dt)
    if not (np.isfinite(file_dt) and file_dt > 0):
        raise ModelError(f"{path}: invalid dt {meta.get('dt')!r}")
    if dt is not None and abs(file_dt - dt) > DT_TOLERANCE * dt:
        raise ModelError(
            f"{path}: model sampled at {1 / file_dt:.6g} Hz (dt={file_dt:.6g} s), "
            f"expected {1 / dt:.6g} Hz (dt={dt:.6g} s)"
        )
    return file_dt


def _check_parameter(path: Path, name: str, key: str, files: dict, want) -> None:
    """Parameter ``key`` is present, real, finite and of the shape the header states."""
    if key not in files:
        raise ModelError(f"{path}: {name} model file lacks parameter {key!r}")
    a = files[key]
    if a.dtype.kind not in "biuf":
        raise ModelError(f"{path}: parameter {key!r} holds {a.dtype} data, expected real numbers")
    if want is not None and not (
        isinstance(want, list) and all(type(n) is int and n >= 0 for n in want)
    ):
        raise ModelError(
            f"{path}: corrupt __meta__ entry (shape of {key!r} is {want!r}, "
            "expected a list of sizes)"
        )
    if want is not None and list(a.shape) != list(want):
        raise ModelError(
            f"{path}: parameter {key!r} has shape {list(a.shape)}, the file's header says {want}"
        )
    if not np.all(np.isfinite(a)):
        raise ModelError(f"{path}: parameter {key!r} holds NaN or inf")


def file_hash(path: str | os.PathLike) -> str:
    """sha256 of a model file (regression cases record which model they judged)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def params_sha(model: BushingModel) -> str:
    """sha256 of a model's parameters and settings (for presets such as the reference)."""
    blob = {
        "class": type(model).__name__,
        "dt": model.dt,
        "params": {k: np.asarray(v, dtype=np.float64).tolist() for k, v in model.params.items()},
        "extra": model.extra_meta(),
    }
    return hashlib.sha256(json.dumps(blob, sort_keys=True, default=str).encode()).hexdigest()
