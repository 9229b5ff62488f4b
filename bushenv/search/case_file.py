"""The case file of the regression corpus: its format, reading and writing it.

A case file (``tests/regressions/corpus/<name>.json``) holds:

| key           | meaning                                                                     |
|---------------|-----------------------------------------------------------------------------|
| format, version | ``"bushenv-divergence-case"``, 1                                          |
| name          | file stem: ``<model>-<axis>-<env>-<family>-<sha8 of the profile>``          |
| env, axis, dt | ``"rig"`` (prescribed bushing displacement) or ``"quartercar"`` (road       |
|               | height), the bushing axis, the sample time in s                             |
| profile       | ``{"encoding": "f32-diff-zlib-b64", "n_samples": T, "data": ...}``: the     |
|               | sample-to-sample differences as float32, zlib-compressed, base64; decoded   |
|               | by a float64 cumulative sum from 0 (holds stay exactly constant). A (T, k)  |
|               | profile (``rig3``) adds ``"shape": [T, k]``, its columns one after another, |
|               | each from 0; n_samples is then T k                                          |
| family, params| the excitation family and its physical parameters (or the agent's name)     |
| found_by      | searcher, seed, model name and the sha256 of the model file it was found on |
| expect        | per model spec: ``diverged`` (bool), the ``criterion`` it fired (or null),  |
|               | ``sha256`` of the model file the verdict was recorded with, and for a model |
|               | file ``file``: where it was and the copy kept with the case               |
|               | (``corpus_files.py``). A spec is a registered name (its shipped file) or a  |
|               | model file; in cases without ``file`` a relative path is relative to the    |
|               | case's own folder (``../models/old.npz``)                                   |
| reference     | ``spec``: the reference the verdicts were judged against (a registered name |
|               | or a model file; null: judged without one, by the criteria that need none), |
|               | ``file_sha256``, ``params_sha256`` and, for a file, ``file`` as above;      |
|               | replay refuses when it is gone (cases before this field: ``rubber``)        |
| scales        | the bushing's scales the verdicts used (``bushenv/scales.py``; default the  |
|               | papers' machine)                                                            |
| shrink        | what shrinking did (segments / samples / peak before and after)            |

Cases are never overwritten unless ``force=True``; judging and replaying them is in
``corpus.py``.
"""

from __future__ import annotations

import base64
import hashlib
import json
import os
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.errors import BadInput
from bushenv.models import file_hash
from bushenv.persist import write_json
from bushenv.scales import MACHINE, BushingScales
from bushenv.search.corpus_files import KeptFileError, is_model_file, keep, locate
from bushenv.search.targets import TARGETS

CASE_FORMAT = "bushenv-divergence-case"
CASE_VERSION = 1
ENCODING = "f32-diff-zlib-b64"
DEFAULT_CORPUS = Path("tests") / "regressions" / "corpus"


class CorpusError(BadInput):
    """A corrupt or mismatching case file; the message names the file."""


# ----- profile encoding --------------------------------------------------------------------------
def encode_profile(x: np.ndarray) -> dict[str, Any]:
    """A (T,) profile as before; a (T, k) one column after column, with ``"shape": [T, k]``."""
    x = np.asarray(x, dtype=np.float64)
    shape = list(x.shape) if x.ndim == 2 else None
    if shape:  # each column's differences from rest, the columns one after another
        diffs = np.diff(np.concatenate([np.zeros((1, shape[1])), x]), axis=0).T.reshape(-1)
        x = x.T.reshape(-1)
    else:
        x = x.reshape(-1)
        diffs = np.diff(np.r_[0.0, x])
    diffs = diffs.astype(np.float32)
    data = base64.b64encode(zlib.compress(diffs.tobytes(), 9)).decode("ascii")
    out = {"encoding": ENCODING, "n_samples": int(x.size), "data": data}
    if shape:
        out["shape"] = shape
    return out


def decode_profile(d: dict[str, Any], where: str = "profile") -> np.ndarray:
    if not isinstance(d, dict) or d.get("encoding") != ENCODING:
        raise CorpusError(f"{where}: profile encoding must be {ENCODING!r}")
    try:
        raw = zlib.decompress(base64.b64decode(d["data"], validate=True))
    except (KeyError, ValueError, zlib.error) as exc:
        raise CorpusError(f"{where}: profile data is not valid {ENCODING}: {exc}") from None
    diffs = np.frombuffer(raw, dtype=np.float32)
    if diffs.size != d.get("n_samples"):
        raise CorpusError(
            f"{where}: profile has {diffs.size} samples, header says {d.get('n_samples')}"
        )
    shape = d.get("shape")
    if shape is None:
        x = np.cumsum(diffs.astype(np.float64))
    else:
        if (
            not isinstance(shape, list)
            or len(shape) != 2
            or not all(isinstance(n, int) and n > 0 for n in shape)
            or shape[0] * shape[1] != diffs.size
        ):
            raise CorpusError(
                f"{where}: profile shape {shape!r} does not hold its {diffs.size} samples"
            )
        x = np.cumsum(diffs.astype(np.float64).reshape(shape[1], shape[0]), axis=1).T.copy()
    if not np.all(np.isfinite(x)):
        raise CorpusError(f"{where}: profile holds NaN or inf")
    return x


def profile_sha(x: np.ndarray) -> str:
    return hashlib.sha256(np.asarray(x, dtype=np.float64).tobytes()).hexdigest()


@dataclass
class Case:
    name: str
    env: str
    axis: str
    dt: float
    profile: np.ndarray
    family: str
    params: Any
    found_by: dict[str, Any]
    expect: dict[str, dict[str, Any]]
    reference: dict[str, Any]
    shrink: dict[str, Any] | None = None
    notes: str = ""
    scales: BushingScales = MACHINE
    static: bool = True  # the static criterion judged (the reference's static is trusted)
    judge: dict[str, Any] | None = None  # the judge that made it (``Judge.describe``), if known
    path: Path | None = field(default=None, compare=False)

    def to_json(self) -> dict[str, Any]:
        return {
            "format": CASE_FORMAT,
            "version": CASE_VERSION,
            "name": self.name,
            "env": self.env,
            "axis": self.axis,
            "dt": self.dt,
            "profile": encode_profile(self.profile),
            "family": self.family,
            "params": self.params,
            "found_by": self.found_by,
            "expect": self.expect,
            "reference": self.reference,
            "scales": self.scales.to_json(),
            "static": self.static,
            "judge": self.judge,
            "shrink": self.shrink,
            "notes": self.notes,
        }


def case_folder(case: Case) -> Path | None:
    return None if case.path is None else case.path.parent


def save_case(case: Case, directory: str | os.PathLike, force: bool = False) -> Path | None:
    """Write ``case`` atomically as ``directory/<name>.json``; None if it exists (unless force).

    Every model file the case names (and a reference file) is kept in ``directory/models/``
    (``corpus_files.py``), so the case replays from any working folder and after ``directory``
    moves. A case made in memory names its files relative to the working folder (as
    ``bushenv attack`` was given them) or, failing that, relative to ``directory``."""
    directory = Path(directory)
    path = directory / f"{case.name}.json"
    if path.exists() and not force:
        return None
    d = case.to_json()
    for spec, entry in case.expect.items():
        kept = _kept(case, spec, entry.get("file"), entry.get("sha256"), directory)
        if kept is not None:
            d["expect"][spec] = {**entry, "sha256": kept[1], "file": kept[0]}
    ref = case.reference or {}
    kept = _kept(case, ref.get("spec"), ref.get("file"), ref.get("file_sha256"), directory)
    if kept is not None:
        d["reference"] = {**ref, "file_sha256": kept[1], "file": kept[0]}
    write_json(path, d)
    case.path, case.expect, case.reference = path, d["expect"], d["reference"]
    return path


def _kept(
    case: Case, spec: str | None, file: dict | None, sha: str | None, directory: Path
) -> tuple[dict, str] | None:
    """The ``file`` entry of a model file kept in ``directory`` and its sha256 (None: not a
    model file)."""
    if not is_model_file(spec):
        return None
    if file or case.path is not None:
        try:
            source, _ = locate(spec, file, sha, case_folder(case))
        except KeptFileError as exc:
            raise CorpusError(f"case {case.name}: {exc}") from None
    else:
        given = Path(spec)
        # lexically: ``directory`` may not exist yet, and ``..`` inside it would not resolve
        source = given if given.is_file() else Path(os.path.normpath(directory / given))
    if source is None or not source.is_file():
        return None  # a name only a resolver knows; replay resolves it as before
    now = file_hash(source)
    if sha and now != sha:
        raise CorpusError(
            f"case {case.name}: {source} changed since its verdict was recorded (sha256 "
            f"{sha[:12]} -> {now[:12]}); judge the case again"
        )
    return keep(source, directory, now), now


def load_case(path: str | os.PathLike) -> Case:
    path = Path(path)
    if path.suffix in (".npz", ".fmu"):
        raise CorpusError(
            f"{path}: a model file, not a divergence case; replay takes corpus folders or "
            "case files (CASE.json, as bushenv attack writes them)"
        )
    try:
        d = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise CorpusError(f"{path}: not a readable JSON case file: {exc}") from None
    if not isinstance(d, dict) or d.get("format") != CASE_FORMAT:
        raise CorpusError(f"{path}: not a bushenv divergence case (format tag missing)")
    if d.get("version") != CASE_VERSION:
        raise CorpusError(f"{path}: case version {d.get('version')!r}, expected {CASE_VERSION}")
    for key in ("name", "env", "axis", "dt", "profile", "expect", "found_by"):
        if key not in d:
            raise CorpusError(f"{path}: case lacks {key!r}")
    if d["env"] not in TARGETS:
        raise CorpusError(f"{path}: env {d['env']!r}: {TARGETS.unknown_message(d['env'])}")
    if not isinstance(d["expect"], dict) or not d["expect"]:
        raise CorpusError(f"{path}: 'expect' must name at least one model")
    for name, e in d["expect"].items():
        if not isinstance(e, dict) or not isinstance(e.get("diverged"), bool):
            raise CorpusError(f"{path}: expect[{name!r}] needs a boolean 'diverged'")
    return Case(
        name=d["name"],
        env=d["env"],
        axis=d["axis"],
        dt=float(d["dt"]),
        profile=decode_profile(d["profile"], where=str(path)),
        family=d.get("family", ""),
        params=d.get("params"),
        found_by=d["found_by"],
        expect=d["expect"],
        reference=d.get("reference", {}),
        scales=_scales(d.get("scales"), path),
        static=bool(d.get("static", True)),
        judge=d.get("judge"),
        shrink=d.get("shrink"),
        notes=d.get("notes", ""),
        path=path,
    )


def _scales(d: Any, path: Path) -> BushingScales:
    if d is None:
        return MACHINE
    try:
        return BushingScales(**d)
    except (TypeError, ValueError) as exc:
        raise CorpusError(f"{path}: 'scales' is not valid: {exc}") from None


def case_files(directory: str | os.PathLike = DEFAULT_CORPUS) -> list[Path]:
    return sorted(Path(directory).glob("*.json"))
