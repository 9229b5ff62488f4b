"""Files bushenv writes: the atomic write, JSON encoding and profile archives, in one place.

Every file is written to a temporary file in the same folder and renamed over the target, so a
reader (or an interrupted run) sees the old file or the new one, never half of one; the
temporary file is removed if writing fails. Files get the usual permissions (0666 minus the
umask), not ``mkstemp``'s private 0600.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

import numpy as np


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write(
    path: str | os.PathLike, write: Callable[[IO[bytes]], None], replace: bool = True
) -> Path:
    """Create or replace ``path`` with what ``write(binary_file)`` writes, atomically.

    ``replace=False``: never replace an existing file, not even one that appeared while
    writing (``FileExistsError``; the data are linked in, not renamed over)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix="." + path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
        os.chmod(tmp, 0o666 & ~_umask())
        if replace:
            os.replace(tmp, path)
        else:
            os.link(tmp, path)
            Path(tmp).unlink()
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_text(path: str | os.PathLike, text: str) -> Path:
    """``path`` holds ``text`` (UTF-8), written atomically."""
    data = text.encode("utf-8")
    return atomic_write(path, lambda fh: fh.write(data))


def save_figure(fig: Any, path: str | os.PathLike, dpi: int = 110) -> Path:
    """Write a matplotlib figure as PNG, atomically (a reader never sees half a picture)."""
    return atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=dpi))


def write_figure(fig: Any, path: str | os.PathLike, dpi: int = 110) -> Path:
    """``save_figure``, then close the figure (a report draws dozens; pyplot keeps them all)."""
    try:
        return save_figure(fig, path, dpi)
    finally:
        import matplotlib.pyplot as plt

        plt.close(fig)


def copy_file(source: str | os.PathLike, path: str | os.PathLike) -> Path:
    """A copy of ``source`` at ``path``, written atomically."""
    with open(source, "rb") as src:
        return atomic_write(path, lambda fh: shutil.copyfileobj(src, fh))


def json_default(o: Any) -> Any:
    """JSON for the values bushenv's reports hold: numpy scalars and arrays, paths."""
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def json_text(obj: Any, indent: int | None = 1, sort_keys: bool = False) -> str:
    return json.dumps(obj, indent=indent, sort_keys=sort_keys, default=json_default) + "\n"


def write_json(path: str | os.PathLike, obj: Any, indent: int | None = 1) -> Path:
    """``obj`` as JSON in ``path``, atomically (numpy values become plain numbers)."""
    return write_text(path, json_text(obj, indent))


def plain(obj: Any) -> Any:
    """``obj`` with numpy values, tuples and paths turned into plain JSON values."""
    return json.loads(json.dumps(obj, default=json_default))


def save_profiles(path: str | os.PathLike, profiles: list[np.ndarray], meta: list[dict]) -> Path:
    """Profiles of any lengths in one ``.npz`` (padded + lengths) with JSON metadata; atomic.
    Each profile is (T_i,) or (T_i, C) (C coordinates, the same for all); ``load_profiles``
    gives them back so."""
    n = len(profiles)
    T = max((p.shape[0] for p in profiles), default=1)
    trailing = profiles[0].shape[1:] if profiles else ()
    arr = np.zeros((T, max(n, 1), *trailing))
    lengths = np.zeros(max(n, 1), dtype=np.int64)
    for i, p in enumerate(profiles):
        arr[: p.shape[0], i] = p
        lengths[i] = p.shape[0]

    def write(fh: IO[bytes]) -> None:
        np.savez_compressed(
            fh,
            profiles=arr,
            lengths=lengths,
            count=np.array(n),
            meta=np.array(json.dumps(meta, default=json_default)),
        )

    return atomic_write(path, write)


def load_profiles(path: str | os.PathLike) -> tuple[list[np.ndarray], list[dict]]:
    """What ``save_profiles`` wrote: the profiles (each its own length) and their metadata."""
    with np.load(path, allow_pickle=False) as z:
        n = int(z["count"])
        arr, lengths = z["profiles"], z["lengths"]
        meta = json.loads(str(z["meta"]))
    return [arr[: lengths[i], i].copy() for i in range(n)], meta
