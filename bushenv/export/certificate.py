"""The certificate an FMU carries: run at export (``bushenv.certify``, the same for any number
of coordinates) or read from a file and checked to be the exported model's; its failing holds
become flagged deflection boxes (``flagged``).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.export.flagged import Carried, failing_text, flagged_of_holds, hold_q
from bushenv.models import BushingModel, ModelError

# Certificates agree with the model they are of to rounding: fixed points by bisection to
# machine precision, so 1e-6 of the force (or 1e-6 N) is far above noise and far below a change.
FORCE_MATCH_REL = 1e-6
CHECKED_HOLDS = 5  # the certificate's holds whose fixed points are recomputed to match it


def read_document(path: str | os.PathLike) -> dict:
    """A ``certificate.json`` written by ``bushenv certify``."""
    p = Path(path)
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ModelError(f"{p}: no such certificate file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ModelError(f"{p}: not a certificate (unreadable JSON: {exc})") from None
    if not isinstance(doc, dict) or not all(k in doc for k in ("summary", "holds", "model")):
        raise ModelError(
            f"{p}: not a certificate written by bushenv certify (no summary, holds or model)"
        )
    if any(isinstance(h.get("fixed_points"), int) for h in doc["holds"]):
        raise ModelError(
            f"{p}: a three-axis certificate of the layout before the one certificate (its holds "
            "without free runs); certify the model again (bushenv certify) or drop --certificate"
        )
    return doc


def _forces(h: dict) -> np.ndarray:
    """(P, C) the static forces of a hold's fixed points, sorted by the first coordinate."""
    f = np.array([p["force"] if "force" in p else [p["force_n"]] for p in h["fixed_points"]])
    return f[np.argsort(f[:, 0], kind="stable")] if f.size else f.reshape(0, 1)


def check_belongs(doc: dict, model: BushingModel, path: str | os.PathLike) -> None:
    """Refuse a certificate of another model: its recorded parameters, then the fixed points
    of a few of its holds recomputed on ``model`` (so a retrained network of the same shape
    is told apart), naming what differs."""
    from bushenv.certify.fixed_points import fixed_points
    from bushenv.certify.network import describe, narx_net

    net = narx_net(model)
    mine = doc["model"]
    want = describe(net)
    _same_params(path, mine, {k: v for k, v in want.items() if k in mine or k in ("name", "dt_s")})
    if doc.get("coords", list(model.coords) if model.n_coords == 1 else None) != list(model.coords):
        raise ModelError(
            f"{path}: a certificate over {doc.get('coords')}, not this model's "
            f"{list(model.coords)}; certify this model (bushenv certify) or drop --certificate"
        )
    holds = doc["holds"]
    spread = np.linspace(0, len(holds) - 1, min(CHECKED_HOLDS, len(holds)))
    pick = sorted({int(i) for i in spread})
    if not pick:
        return
    fp = fixed_points(net, np.array([hold_q(holds[i]) for i in pick], dtype=float))
    units = "mm" if model.n_coords == 1 else "mm/mrad"
    for row, i in enumerate(pick):
        got = fp.force[fp.hold == row]
        got = got[np.argsort(got[:, 0], kind="stable")]
        at = np.array(hold_q(holds[i])) * 1e3
        _same_forces(path, at[0] if model.n_coords == 1 else at, units, _forces(holds[i]), got)


def _same_params(path, mine: dict, want: dict) -> None:
    for key, value in want.items():
        had = mine.get(key)
        same = (
            had is not None and np.isclose(float(had), float(value), rtol=1e-12, atol=0.0)
            if isinstance(value, float)
            else had == value
        )
        if not same:
            raise ModelError(
                f"{path}: this certificate is of another model ({key} {had!r}, the model "
                f"exported has {value!r}); certify this model (bushenv certify) or drop "
                "--certificate to certify it at export"
            )


def _same_forces(path, at, unit: str, had: np.ndarray, got: np.ndarray) -> None:
    tol = FORCE_MATCH_REL * np.maximum(1.0, np.abs(had)) if had.shape == got.shape else None
    if tol is None or np.any(np.abs(had - got) > tol):
        had, got = had[:, 0], got[:, 0]
        raise ModelError(
            f"{path}: this certificate is of another model: its fixed points at {at} {unit} "
            f"({np.round(had, 3).tolist()} N) are not this model's ({np.round(got, 3).tolist()} "
            "N); certify this model (bushenv certify) or drop --certificate to certify it at "
            "export"
        )


def is_narx(model: BushingModel) -> bool:
    """Whether ``model`` has a NARX recurrence to certify (nn, hybrid; over several coordinates
    also nn-axis). The classes' own modules: the certificate's are not imported for a kind
    without one (they cost a linear model's export half a second)."""
    from bushenv.models.narx import NarxBushing
    from bushenv.models.planar_narx import PlanarNarx

    return isinstance(model, NarxBushing | PlanarNarx)


def carried_certificate(
    model: BushingModel,
    spec: Any,
    axis: str,
    *,
    path: str | os.PathLike | None = None,
    reference: Any = None,
    stroke_m: float | None = None,
) -> Carried:
    """The certificate the FMU of ``model`` carries. ``path``: a ``certificate.json`` to read
    (checked to be ``model``'s); else run as ``bushenv certify`` runs it, against
    ``reference`` (None: none, wrong sign judged against the deflection) over the span
    ``bushenv certify`` takes for any number of coordinates (``Judge.span``: the card's
    records' range, the machine's; ``stroke_m`` on the translations on top). A kind without
    a recurrence (linear, Bouc-Wen) has none: a ``Carried`` that says so (a ``path`` given
    for one is refused)."""
    units = tuple(getattr(model, "units", ("m",)))
    if not is_narx(model):
        if path is not None:
            raise ModelError(
                f"--certificate {path}: a {model.name!r} model has no certificate (certificates "
                "are of NARX networks: nn, hybrid); drop --certificate"
            )
        if reference is not None:
            raise ModelError(
                f"--reference {reference}: a {model.name!r} model has no certificate to "
                "compare with a reference; drop --reference"
            )
        return Carried(
            f"none: a {model.name!r} model has no recurrence to certify (certificates are of "
            "NARX networks: nn, hybrid)",
            units=units,
        )
    if path is not None and reference is not None:
        raise ModelError(
            f"--reference {reference} with --certificate {path}: the reference is for the "
            "certificate run at export; a given certificate was made against its own"
        )
    if path is not None:
        doc = read_document(path)
        check_belongs(doc, model, path)
        source = f"{Path(path).name}, given"
    else:
        doc, source = _run(model, spec, axis, reference, stroke_m)
    s = doc["summary"]
    return Carried(
        source,
        bool(s["passes_holds"]),
        bool(s["passes_passivity"]),
        tuple(flagged_of_holds(doc)),
        failing_text(s, doc),
        units,
        doc,
    )


def _run(model, spec, axis, reference, stroke_m) -> tuple[dict, str]:
    """The certificate as ``bushenv certify`` runs it: the judge of the attack's resolve stage
    at the rig (``resolve_target`` at ``judge.RIG``, the same for any number of coordinates)
    gives the holds' span (``Judge.span``) and the vetted reference."""
    from bushenv.certify.certificate import certify
    from bushenv.certify.options import CertifyOptions, per_coordinate, span_text
    from bushenv.judge import NO_REFERENCE, RIG, ScaleFlags
    from bushenv.resolved import resolved
    from bushenv.search.campaign_resolve import resolve_target

    given = spec if isinstance(spec, str | os.PathLike) else model
    flags = ScaleFlags(stroke_mm=None if stroke_m is None else stroke_m * 1e3)
    one = resolve_target(
        resolved(given, model, axis, card=True), NO_REFERENCE if reference is None else reference,
        axis=axis, target=RIG, flags=flags,
    )  # fmt: skip
    judge = one.judge
    ref, ref_spec, span, span_source = (
        judge.reference, judge.reference_spec, judge.span, judge.scales.source
    )  # fmt: skip
    opts = CertifyOptions(span=span)
    doc = certify(model, ref, opts).document
    against = (
        "no reference (wrong sign judged against the deflection: q . f < 0)"
        if ref is None
        else f"reference {ref_spec}"
    )
    shown = span_text(model.coords, model.units, span)
    n = per_coordinate(opts.holds, model.n_coords)
    grid = f"{n} holds" if model.n_coords == 1 else f"{n}^{model.n_coords} hold vectors"
    return doc, f"certified at export, {grid} over {shown} ({span_source}), {against}"
