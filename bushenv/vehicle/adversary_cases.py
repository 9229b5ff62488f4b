"""The adversary's finds as regression cases: the corpus's own format (``search/case_file.py``),
``env`` "halfcar", replayed by ``bushenv replay`` like every other case.

Per bushing kind, the manoeuvre found with the largest wheel-load difference, and where the
search ended the model car, the manoeuvre that ended it earliest. Each case records what every
kind's car does on it (``expect``: the halfcar judge's verdict, ``terminated`` or ``differs``
beyond the registered 5 % or neither) against the rubber reference, with each model file's
sha256 and a copy kept beside the case.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from bushenv.models import params_sha
from bushenv.rigs.halfcar_params import REFERENCE
from bushenv.search.corpus import make_case, profile_sha, save_case


def _cases_wanted(kind: str, kept: dict[str, Any]) -> list[tuple[str, dict]]:
    out = []
    if kept["found"] is not None:
        out.append(("largest wheel-load difference that ran to the end", kept["found"]))
    ended = [e for e in kept["entries"] if e["criterion"] == "terminated"]
    if ended:
        out.append(("ended the model car earliest", min(ended, key=lambda e: e["time_s"])))
    return out


def save_cases(
    kept: dict[str, dict[str, Any]],
    bushings: dict[str, Any],
    reference,
    seed: int,
    directories: list[Path],
) -> list[dict[str, Any]]:
    """Write every kind's cases into each of ``directories``; what was written, per case.

    ``bushings``: kind -> ``VehicleBushing`` (its model and file); ``reference``: the resolved
    rubber the verdicts are judged against."""
    models = {b.file: b.model for b in bushings.values()}
    shas = {b.file: b.sha256 for b in bushings.values()}
    record = {"spec": REFERENCE, "file_sha256": None, "params_sha256": params_sha(reference)}
    written, seen = [], set()
    for kind, k in kept.items():
        for why, e in _cases_wanted(kind, k):
            sha = profile_sha(e["profile"])
            if sha in seen:  # one profile found for two kinds: its case records every kind
                continue
            seen.add(sha)
            case = make_case(
                e["profile"], env="halfcar", axis="planar", family=e["params"]["family"],
                params=e["params"],
                found_by={"searcher": e["searcher"], "seed": seed, "model": kind,
                          "model_sha256": bushings[kind].sha256, "evaluation": e["evaluation"]},
                models=models, reference=reference, reference_spec=REFERENCE, shas=shas,
                reference_record=record,
                notes=f"bushenv vehicle --search: {why} for the {kind} car (D "
                f"{e['d_pct']:.1f} % of the reference car's peak wheel load)",
            )  # fmt: skip
            paths = [save_case(case, d, force=True) for d in directories]
            written.append({"kind": kind, "why": why, "name": case.name,
                            "files": [str(p) for p in paths],
                            "expect": {Path(s).stem: v["criterion"] or "passes"
                                       for s, v in case.expect.items()}})  # fmt: skip
    return written
