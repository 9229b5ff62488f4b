"""The regression corpus: every kept divergence as a small JSON file, replayed by the tests.

A case file (``tests/regressions/corpus/<name>.json``) holds:

| key           | meaning                                                                     |
|---------------|-----------------------------------------------------------------------------|
| format, version | ``"bushenv-divergence-case"``, 1                                          |
| name          | file stem: ``<model>-<axis>-<env>-<family>-<sha8 of the profile>``          |
| env, axis, dt | ``"rig"`` (prescribed bushing displacement) or ``"quartercar"`` (road       |
|               | height), the bushing axis, the sample time in s                             |
| profile       | ``{"encoding": "f32-diff-zlib-b64", "n_samples": T, "data": ...}``: the     |
|               | sample-to-sample differences as float32, zlib-compressed, base64; decoded   |
|               | by a float64 cumulative sum from 0 (holds stay exactly constant)            |
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

The verdicts in ``expect`` are measured on the DECODED profile when the case is made (float32
rounding cannot make a recorded verdict wrong). ``replay`` re-runs a case on the current
models and reference; ``check`` lists every changed verdict with the case name and says when
the model file or the reference changed since the case was recorded. Cases are never
overwritten unless ``force=True``.
"""

from __future__ import annotations

import base64
import hashlib
import json
import os
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.errors import BadInput
from bushenv.models import (
    BushingModel,
    file_hash,
    get_model,
    get_reference,
    model_file,
    params_sha,
)
from bushenv.models.base import PAPER_DT
from bushenv.persist import write_json
from bushenv.scales import MACHINE, BushingScales
from bushenv.search.corpus_files import KeptFileError, is_model_file, keep, locate
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.targets import TARGETS

CASE_FORMAT = "bushenv-divergence-case"
CASE_VERSION = 1
ENCODING = "f32-diff-zlib-b64"
DEFAULT_CORPUS = Path("tests") / "regressions" / "corpus"


class CorpusError(BadInput):
    """A corrupt or mismatching case file; the message names the file."""


# ----- profile encoding --------------------------------------------------------------------------
def encode_profile(x: np.ndarray) -> dict[str, Any]:
    x = np.asarray(x, dtype=np.float64).reshape(-1)
    diffs = np.diff(np.r_[0.0, x]).astype(np.float32)
    data = base64.b64encode(zlib.compress(diffs.tobytes(), 9)).decode("ascii")
    return {"encoding": ENCODING, "n_samples": int(x.size), "data": data}


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
    x = np.cumsum(diffs.astype(np.float64))
    if not np.all(np.isfinite(x)):
        raise CorpusError(f"{where}: profile holds NaN or inf")
    return x


def profile_sha(x: np.ndarray) -> str:
    return hashlib.sha256(np.asarray(x, dtype=np.float64).tobytes()).hexdigest()


# ----- model and reference identity -------------------------------------------------------------
def model_sha(name: str, axis: str) -> str | None:
    """sha256 of the file behind a model name (a shipped default or a path; None for presets)."""
    path = model_file(name, axis)
    return file_hash(path) if path is not None and path.is_file() else None


def truth_reference(axis: str, dt: float = PAPER_DT) -> BushingModel:
    """The built-in "real" bushing: the rubber specimen alone (``get_reference("rubber")``)."""
    return get_reference("rubber", axis=axis, dt=dt)


def reference_identity(spec: str | None, reference: BushingModel | None, axis: str) -> dict:
    """What a case or report records of its reference: the spec it was given by (a registered
    name or a model file; None: judged without one), the file's and the parameters' sha256."""
    if reference is None:
        return {"spec": None, "file_sha256": None, "params_sha256": None}
    return {
        "spec": spec,
        "file_sha256": model_sha(spec, axis) if spec is not None else None,
        "params_sha256": params_sha(reference),
    }


def case_reference(case: Case, notes: list[str] | None = None) -> BushingModel | None:
    """The reference a case was judged against, resolved today (a file: where it was, else the
    copy kept with the case); refuses (``CorpusError``) when it is gone. Cases written before
    references were explicit name the built-in rubber."""
    ref = case.reference
    spec = ref.get("spec", ref.get("name", "rubber")) if ref else "rubber"
    if spec is None:
        return None
    try:
        path, note = locate(spec, ref.get("file"), ref.get("file_sha256"), _folder(case))
    except KeptFileError as exc:
        raise CorpusError(f"case {case.name}: its reference {exc}") from None
    if note and notes is not None:
        notes.append(note)
    try:
        return get_reference(spec if path is None else str(path), axis=case.axis, dt=case.dt)
    except ValueError as exc:
        raise CorpusError(
            f"case {case.name}: its reference {spec!r} cannot be loaded ({exc}); restore the "
            f"file (sha256 {str(ref.get('file_sha256'))[:12]}) or record the case again"
        ) from None


# ----- cases -------------------------------------------------------------------------------------
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


Resolver = Callable[[str, str, float], BushingModel]


def _default_resolver(name: str, axis: str, dt: float) -> BushingModel:
    return get_model(name, axis=axis, dt=dt)


def _folder(case: Case) -> Path | None:
    return None if case.path is None else case.path.parent


def model_spec(case: Case, spec: str, notes: list[str] | None = None) -> str:
    """The model an ``expect`` key names, to resolve today: a registered name (or any other
    name a resolver knows) as it is; a model file where it was recorded, else the copy kept
    with the case (``corpus_files.locate``; a note for the replay is added to ``notes``)."""
    entry = case.expect.get(spec, {})
    try:
        path, note = locate(spec, entry.get("file"), entry.get("sha256"), _folder(case))
    except KeptFileError as exc:
        raise CorpusError(f"case {case.name}: a model it names cannot be loaded: {exc}") from None
    if note and notes is not None:
        notes.append(note)
    return spec if path is None else str(path)


def judge_profile(
    profile: np.ndarray,
    models: dict[str, BushingModel],
    env: str,
    axis: str,
    reference: BushingModel | None,
    scales: BushingScales = MACHINE,
    static: bool = True,
) -> dict[str, dict[str, Any]]:
    """Verdict row of ``profile`` for each model (prescribed-motion or quarter-car path)."""
    out = {}
    for name, model in models.items():
        ev = BatchEvaluator(model, reference, env, axis=axis, scales=scales, static=static)
        out[name] = ev.evaluate([profile]).verdict.row(0)
    return out


def make_case(
    profile: np.ndarray,
    *,
    env: str,
    axis: str,
    family: str,
    params: Any,
    found_by: dict[str, Any],
    models: dict[str, BushingModel],
    reference: BushingModel | None,
    reference_spec: str | None = "rubber",
    scales: BushingScales = MACHINE,
    static: bool = True,
    shas: dict[str, str | None] | None = None,
    shrink: dict[str, Any] | None = None,
    notes: str = "",
    judge: dict[str, Any] | None = None,
) -> Case:
    """A case whose ``expect`` holds what each model does on the decoded profile now, against
    ``reference`` (given by ``reference_spec``; None: judged without one) at ``scales``."""
    x = decode_profile(encode_profile(profile))
    rows = judge_profile(x, models, env, axis, reference, scales, static)
    shas = shas or {}
    expect = {
        name: {
            "diverged": bool(row["diverged"]),
            "criterion": row["first_criterion"],
            "first_time_s": row["first_time_s"],
            "sha256": shas.get(name),
        }
        for name, row in rows.items()
    }
    target = found_by.get("model", next(iter(models)))
    name = f"{_slug(target)}-{axis}-{env}-{_slug(family)}-{profile_sha(x)[:8]}"
    return Case(
        name=name,
        env=env,
        axis=axis,
        dt=float(next(iter(models.values())).dt),
        profile=x,
        family=family,
        params=params,
        found_by=found_by,
        expect=expect,
        reference=reference_identity(reference_spec, reference, axis),
        shrink=shrink,
        notes=notes,
        scales=scales,
        static=static,
        judge=judge,
    )


def _slug(text: str) -> str:
    keep = "".join(c if c.isalnum() else "_" for c in Path(str(text)).stem)
    return keep.strip("_") or "model"


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
            source, _ = locate(spec, file, sha, _folder(case))
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


@dataclass
class Replay:
    model: str
    expected: bool
    diverged: bool
    row: dict[str, Any]
    sha_recorded: str | None
    sha_now: str | None

    @property
    def ok(self) -> bool:
        return self.expected == self.diverged


def replay(
    case: Case,
    resolve: Resolver | None = None,
    sha_of: Callable[[str, str], str | None] | None = None,
    notes: list[str] | None = None,
) -> list[Replay]:
    """Run the case on every model it names, today's files; one ``Replay`` per model.

    ``resolve(name, axis, dt)`` gives the model (default: ``get_model``); ``sha_of(name,
    axis)`` the sha256 of its file today (default: the shipped file, ``model_sha``). Where a
    kept copy stood in for a moved file, a line is added to ``notes``.
    """
    resolve = resolve or _default_resolver
    sha_of = sha_of or model_sha
    reference = case_reference(case, notes)
    specs = {name: model_spec(case, name, notes) for name in case.expect}
    try:
        models = {name: resolve(spec, case.axis, case.dt) for name, spec in specs.items()}
    except ValueError as exc:
        raise CorpusError(f"case {case.name}: a model it names cannot be loaded: {exc}") from None
    rows = judge_profile(
        case.profile, models, case.env, case.axis, reference, case.scales, case.static
    )
    return [
        Replay(
            model=name,
            expected=bool(case.expect[name]["diverged"]),
            diverged=bool(rows[name]["diverged"]),
            row=rows[name],
            sha_recorded=case.expect[name].get("sha256"),
            sha_now=sha_of(specs[name], case.axis),
        )
        for name in case.expect
    ]


def check(
    case: Case,
    resolve: Resolver | None = None,
    sha_of: Callable[[str, str], str | None] | None = None,
    notes: list[str] | None = None,
) -> list[str]:
    """Messages for every changed verdict (empty when the case still holds); ``notes`` gets
    the kept copies replayed and the model files that changed with their verdicts holding."""
    problems = []
    results = replay(case, resolve, sha_of, notes)
    reference = case_reference(case)
    ref_now = None if reference is None else params_sha(reference)
    ref_changed = case.reference.get("params_sha256") not in (None, ref_now)
    for r in results:
        changed = bool(r.sha_recorded and r.sha_now and r.sha_recorded != r.sha_now)
        if r.ok:
            if changed and notes is not None:
                notes.append(
                    f"case {case.name}: the {r.model} model file changed since the case was "
                    f"recorded (sha256 {r.sha_recorded[:12]} -> {r.sha_now[:12]}); its "
                    "verdict holds"
                )
            continue
        want = "diverge" if r.expected else "stay bounded"
        got = (
            f"diverged ({r.row['first_criterion']} at {r.row['first_time_s']:.3f} s)"
            if r.diverged
            else f"stayed bounded (robustness {r.row['robustness']})"
        )
        msg = f"case {case.name}: {r.model} was expected to {want} but {got}"
        if changed:
            msg += (
                f"; the {r.model} model file changed since the case was recorded "
                f"(sha256 {r.sha_recorded[:12]} -> {r.sha_now[:12]})"
            )
        elif r.sha_recorded and r.sha_recorded == r.sha_now:
            msg += f"; the {r.model} model file is the one the case was recorded with"
        if ref_changed:
            msg += "; the reference's parameters changed since the case was recorded"
        problems.append(msg)
    return problems
