"""Model files kept with a corpus, so that a case replays from any working folder and after its
folder is moved or copied to another machine.

When a case is saved (``corpus.save_case``), every model file it names -- the models in
``expect`` and a reference given as a file -- is copied into the case's folder as
``models/<first 16 hex of its sha256>/<file name>``, with its model card
(``<stem>.card.json`` / ``.card.md``) beside it when it has one. The case records, per file,

    "file": {"source": "../my_nn.npz", "kept": "models/0123456789abcdef/my_nn.npz"}

both relative to the case's folder (``source`` stays absolute when no relative path exists).
Replay takes ``source`` while it is there (a model refitted in place is judged as it is now, and
the changed sha256 is named) and otherwise the kept copy, whose sha256 must be the recorded one.
Registered names (``nn``, ``rubber``, ...) are the package's own files and are not copied.

Cases written before this (no ``file``) name files relative to the case's folder; a name that is
not there is tried relative to the working folder (older versions wrote paths relative to it),
and the replay says so.
"""

from __future__ import annotations

import os
from pathlib import Path

from bushenv.errors import BadInput
from bushenv.models import MODELS, file_hash
from bushenv.persist import copy_file

KEPT_DIR = "models"


class KeptFileError(BadInput):
    """A model a case names is neither where it was nor kept with the case (or was altered)."""


def is_model_file(spec: str | None) -> bool:
    """Whether a spec names a model file (not a registered name or a test's own label)."""
    if spec is None or spec in MODELS:
        return False
    return spec.endswith(".npz") or "/" in spec or os.sep in spec


def keep(source: Path, directory: Path, sha: str) -> dict[str, str]:
    """Copy ``source`` (and its card) into ``directory/models/<sha16>/``; the ``file`` entry."""
    from bushenv.identify.card import card_paths

    kept = directory / KEPT_DIR / sha[:16] / source.name
    for src, dst in zip((source, *card_paths(source)), (kept, *card_paths(kept)), strict=True):
        if src.is_file() and not dst.is_file():
            copy_file(src, dst)
    if file_hash(kept) != sha:  # a half-copied or altered earlier copy: never trust it silently
        copy_file(source, kept)
    return {"source": _relative(source, directory), "kept": kept.relative_to(directory).as_posix()}


def _relative(path: Path, directory: Path) -> str:
    try:
        return Path(os.path.relpath(os.path.abspath(path), os.path.abspath(directory))).as_posix()
    except ValueError:  # another drive: no relative path exists
        return str(Path(os.path.abspath(path)))


def locate(
    label: str, file: dict | None, sha: str | None, folder: Path | None
) -> tuple[Path | None, str | None]:
    """Where the model a case calls ``label`` is today, and a note for the replay (or None).

    ``file`` is the case's ``file`` entry (None for cases written before it), ``sha`` the
    recorded sha256, ``folder`` the case's folder (None for a case not read from a file).
    Returns (None, None) for a registered name. Raises ``KeptFileError`` when the model is
    gone, or when the kept copy is not the file the case was recorded with.
    """
    if file:
        if folder is None:
            raise KeptFileError(f"{label}: a case with kept files must be read from its folder")
        source = Path(os.path.normpath(folder / file["source"]))
        if source.is_file():
            return source, None
        kept = Path(os.path.normpath(folder / file["kept"]))
        if not kept.is_file():
            raise KeptFileError(
                f"{label}: neither at {source} nor kept with the case at {kept}; restore the "
                f"file (sha256 {str(sha)[:12]}) or record the case again"
            )
        now = file_hash(kept)
        if sha and now != sha:
            raise KeptFileError(
                f"{kept}: the copy kept with the case has sha256 {now[:12]}, the case was "
                f"recorded with {sha[:12]}: it was altered; restore it or record the case again"
            )
        return kept, f"{label}: not at {source}; replayed the copy kept with the corpus ({kept})"
    if not is_model_file(label):
        return None, None
    path = Path(label)
    if path.is_absolute() or folder is None:
        return path, None
    if (folder / path).is_file() or not path.is_file():
        return folder / path, None
    return path, (
        f"{label}: not in the case's folder {folder}; found relative to the working folder "
        "(the case predates corpora that keep their models: record it again to keep them)"
    )
