"""A three-axis model or reference named in an attack or a case, resolved: what the planar
attack and the corpus's replay of planar cases share."""

from __future__ import annotations

from pathlib import Path


def resolve_planar_spec(spec: str, dt: float | None, what: str):
    """A three-axis model by ``MODELS`` name (with a preset) or ``.npz`` file; ``dt`` None:
    a file at its own rate (a fit on 500 Hz records runs at 500 Hz), a preset at the papers'."""
    from bushenv.models import load_model
    from bushenv.models.base import PAPER_DT
    from bushenv.rigs.bushrig3 import resolve_planar

    if dt is None and str(spec).endswith(".npz") and Path(spec).is_file():
        return load_model(spec, coords=3, wanted_by=f"the {what}")
    return resolve_planar(spec, PAPER_DT if dt is None else dt, what)


def resolved_planar(spec: str, dt: float | None, what: str):
    """``resolve_planar_spec`` as a ``ResolvedModel`` (its file and sha256, for cases)."""
    from bushenv.models import file_hash
    from bushenv.resolved import ResolvedModel, report_key

    model = resolve_planar_spec(spec, dt, what)
    path = Path(spec) if str(spec).endswith(".npz") and Path(spec).is_file() else None
    return ResolvedModel(
        key=report_key(spec),
        spec=str(spec),
        model=model,
        file=path,
        sha256=None if path is None else file_hash(path),
        registered=path is None,
    )
