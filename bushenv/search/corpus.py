"""The regression corpus: every kept divergence as a small JSON file, replayed by the tests.

The case file (``case_file.py`` gives every field) holds a profile, the verdict each model
gave on it (``expect``), the reference and the scales they were judged at. The verdicts in
``expect`` are measured on the DECODED profile when the case is made (float32 rounding cannot
make a recorded verdict wrong). ``replay`` re-runs a case on the current models and reference
(``resolve_case`` resolves everything it names once, ``replayed`` judges); ``check`` lists
every changed verdict with the case name and says when the model file or the reference
changed since the case was recorded.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.models import BushingModel, file_hash, get_reference, model_file, params_sha
from bushenv.models.base import PAPER_DT
from bushenv.resolved import ResolvedModel, resolve_model
from bushenv.scales import MACHINE, BushingScales
from bushenv.search.case_file import (  # noqa: F401 (the case file, as corpus gave it)
    CASE_FORMAT,
    CASE_VERSION,
    DEFAULT_CORPUS,
    ENCODING,
    Case,
    CorpusError,
    case_files,
    case_folder,
    decode_profile,
    encode_profile,
    load_case,
    profile_sha,
    save_case,
)
from bushenv.search.corpus_files import KeptFileError, locate
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.targets import TARGETS, get_target


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
    """The reference a case was judged against, resolved today (``resolved_reference``)."""
    ref = resolved_reference(case, notes)
    return None if ref is None else ref.model


def resolved_reference(case: Case, notes: list[str] | None = None) -> ResolvedModel | None:
    """The reference a case was judged against, resolved today (a file: where it was, else the
    copy kept with the case); refuses (``CorpusError``) when it is gone. Cases written before
    references were explicit name the built-in rubber."""
    ref = case.reference
    spec = ref.get("spec", ref.get("name", "rubber")) if ref else "rubber"
    if spec is None:
        return None
    try:
        path, note = locate(spec, ref.get("file"), ref.get("file_sha256"), case_folder(case))
    except KeptFileError as exc:
        raise CorpusError(f"case {case.name}: its reference {exc}") from None
    if note and notes is not None:
        notes.append(note)
    given = spec if path is None else str(path)
    try:
        return _resolve(case, given, reference=True)
    except ValueError as exc:
        raise CorpusError(
            f"case {case.name}: its reference {spec!r} cannot be loaded ({exc}); restore the "
            f"file (sha256 {str(ref.get('file_sha256'))[:12]}) or record the case again"
        ) from None


Resolver = Callable[[str, str, float], BushingModel]


def _resolve(case: Case, spec: str, reference: bool = False) -> ResolvedModel:
    """A model a case names, resolved for its target: over as many coordinates as the
    target's profiles have columns (one for a (T,) profile; the rig over three drives models of
    three, the half car's three inputs its pivots of three)."""
    coords = len(TARGETS[case.env].coords) or 1
    what = f"the case {case.name}'s {'reference' if reference else 'model'}"
    return resolve_model(
        spec, axis=case.axis, dt=case.dt, reference=reference, coords=coords, wanted_by=what
    )


def model_spec(case: Case, spec: str, notes: list[str] | None = None) -> str:
    """The model an ``expect`` key names, to resolve today: a registered name (or any other
    name a resolver knows) as it is; a model file where it was recorded, else the copy kept
    with the case (``corpus_files.locate``; a note for the replay is added to ``notes``)."""
    entry = case.expect.get(spec, {})
    try:
        path, note = locate(spec, entry.get("file"), entry.get("sha256"), case_folder(case))
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
    reference_record: dict[str, Any] | None = None,
) -> Case:
    """A case whose ``expect`` holds what each model does on the decoded profile now, against
    ``reference`` (given by ``reference_spec``; None: judged without one) at ``scales``.
    ``reference_record``: what the case records of a reference resolved already (default:
    ``reference_identity``, which hashes its file)."""
    x = decode_profile(encode_profile(profile))
    rows = judge_profile(x, models, env, axis, reference, scales, static)
    if reference is not None:  # what else of the judge follows from the reference (floors)
        judge = {**(judge or {}), **get_target(env).judging_facts(reference)} or judge
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
        reference=reference_record or reference_identity(reference_spec, reference, axis),
        shrink=shrink,
        notes=notes,
        scales=scales,
        static=static,
        judge=judge,
    )


def _slug(text: str) -> str:
    keep = "".join(c if c.isalnum() else "_" for c in Path(str(text)).stem)
    return keep.strip("_") or "model"


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


@dataclass(frozen=True)
class ResolvedCase:
    """A case with everything it names resolved today, once: the reference, and per
    ``expect`` name the model and the sha256 of its file now."""

    case: Case
    reference: ResolvedModel | None
    models: dict[str, BushingModel]
    shas: dict[str, str | None]


def resolve_case(
    case: Case,
    resolve: Resolver | None = None,
    sha_of: Callable[[str, str], str | None] | None = None,
    notes: list[str] | None = None,
) -> ResolvedCase:
    """``case``'s reference and models, resolved (``resolve(name, axis, dt)`` gives a model,
    default ``resolve_model``; ``sha_of(name, axis)`` its file's sha256 today, default the
    resolved file's). Where a kept copy stood in for a moved file, a line goes to ``notes``."""
    reference = resolved_reference(case, notes)
    specs = {name: model_spec(case, name, notes) for name in case.expect}
    models, shas = {}, {}
    try:
        for name, spec in specs.items():
            if resolve is None:
                given = _resolve(case, spec)
                models[name], shas[name] = given.model, given.sha256
            else:
                models[name], shas[name] = resolve(spec, case.axis, case.dt), None
            if sha_of is not None or resolve is not None:
                shas[name] = (sha_of or model_sha)(spec, case.axis)
    except ValueError as exc:
        raise CorpusError(f"case {case.name}: a model it names cannot be loaded: {exc}") from None
    return ResolvedCase(case, reference, models, shas)


def replayed(resolved: ResolvedCase) -> list[Replay]:
    """The case's profile judged on every model it names; one ``Replay`` per model."""
    case = resolved.case
    reference = None if resolved.reference is None else resolved.reference.model
    rows = judge_profile(
        case.profile, resolved.models, case.env, case.axis, reference, case.scales, case.static
    )
    return [
        Replay(
            model=name,
            expected=bool(case.expect[name]["diverged"]),
            diverged=bool(rows[name]["diverged"]),
            row=rows[name],
            sha_recorded=case.expect[name].get("sha256"),
            sha_now=resolved.shas[name],
        )
        for name in case.expect
    ]


def replay(
    case: Case,
    resolve: Resolver | None = None,
    sha_of: Callable[[str, str], str | None] | None = None,
    notes: list[str] | None = None,
) -> list[Replay]:
    """Run the case on every model it names, today's files (``resolve_case``, then
    ``replayed``); one ``Replay`` per model."""
    return replayed(resolve_case(case, resolve, sha_of, notes))


def check(
    case: Case,
    resolve: Resolver | None = None,
    sha_of: Callable[[str, str], str | None] | None = None,
    notes: list[str] | None = None,
) -> list[str]:
    """Messages for every changed verdict (empty when the case still holds); ``notes`` gets
    the kept copies replayed and the model files that changed with their verdicts holding."""
    problems = []
    resolved = resolve_case(case, resolve, sha_of, notes)
    results = replayed(resolved)
    ref_now = None if resolved.reference is None else params_sha(resolved.reference.model)
    ref_changed = case.reference.get("params_sha256") not in (None, ref_now)
    judge_changes = judge_changed(case, resolved)
    if judge_changes and notes is not None and all(r.ok for r in results):
        notes.append(f"case {case.name}: {'; '.join(judge_changes)}; its verdicts hold")
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
        msg += "".join(f"; {c}" for c in judge_changes)
        problems.append(msg)
    return problems


def judge_changed(case: Case, resolved: ResolvedCase) -> list[str]:
    """What of the judge, beyond the reference's parameters, differs today from what the case
    recorded (``Target.judging_facts``: the rig3 force floors), or was not recorded."""
    if resolved.reference is None:
        return []
    now = get_target(case.env).judging_facts(resolved.reference.model)
    out = []
    for key, value in now.items():
        then = (case.judge or {}).get(key)
        if then is None:
            out.append(f"the case does not record the judge's {key} (recorded before they "
                       f"were kept); judged at today's: {_shown(value)}")  # fmt: skip
        else:
            moved = [
                f"{k} {then.get(k)} -> {v:.4g}"
                for k, v in value.items()
                if then.get(k) is None or not np.isclose(then[k], v, rtol=1e-9, atol=0.0)
            ]
            if moved:
                out.append(f"the judge's {key} changed since the case was recorded: "
                           f"{', '.join(moved)}")  # fmt: skip
    return out


def _shown(value: dict[str, float]) -> str:
    return ", ".join(f"{k} {v:.4g}" for k, v in value.items())
