"""The certificate an FMU carries: run at export (``bushenv.certify``) or read from a file and
checked to be the exported model's; its failing holds become flagged deflection boxes.

A hold fails the hold certificate when its free run does not settle on a stable fixed point
(it oscillates, departs, or sits on an unstable one), when its static force has the wrong sign,
or when a fold lies next to it; ``passes_holds`` is false exactly when one does, so a model
fails its certificate exactly when its FMU has a flagged box. Each failing hold stands for the
cell of the grid around it: one coordinate, from half-way to the hold below to half-way to the
hold above (a fold: the cell between the two holds that bracket it), adjacent cells merged into
one range; several coordinates (``certify_vector``'s grid), the box of +- half the grid's
spacing about each failing hold vector. The passivity verdict is a property of frequency
bands, not of deflections: it is carried as a fact, not as a box.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.models import BushingModel, ModelError

# Certificates agree with the model they are of to rounding: fixed points by bisection to
# machine precision, so 1e-6 of the force (or 1e-6 N) is far above noise and far below a change.
FORCE_MATCH_REL = 1e-6
CHECKED_HOLDS = 5  # the certificate's holds whose fixed points are recomputed to match it


@dataclass(frozen=True)
class Flagged:
    """A box of deflections where the model fails its certificate: ``lo``, ``hi`` per
    coordinate (m or rad), ``why`` the failures of its holds ("oscillates, departs")."""

    lo: tuple[float, ...]
    hi: tuple[float, ...]
    why: str

    def contains(self, q: np.ndarray) -> np.ndarray:
        """(T,) whether each deflection of ``q`` (T, C) or (T,) lies in the box (ends in)."""
        q = np.asarray(q, dtype=float).reshape(len(q), -1)
        return np.all((q >= np.array(self.lo)) & (q <= np.array(self.hi)), axis=1)


@dataclass(frozen=True)
class Carried:
    """What an FMU carries of a certificate. ``passes_holds`` None: the kind has none."""

    source: str
    passes_holds: bool | None = None
    passes_passivity: bool | None = None
    flagged: tuple[Flagged, ...] = ()
    failing: str = ""  # the failing checks, one line
    units: tuple[str, ...] = ("m",)
    document: dict | None = field(default=None, compare=False, repr=False)

    @property
    def fails(self) -> bool:
        return self.passes_holds is False

    def ranges_text(self) -> str:
        """The flagged boxes in mm / mrad, e.g. ``-1.81..-0.69 mm (oscillates)``."""
        parts = []
        for b in self.flagged:
            box = " x ".join(
                f"{lo * 1e3:+.5g}..{hi * 1e3:+.5g} {'mrad' if u == 'rad' else 'mm'}"
                for lo, hi, u in zip(b.lo, b.hi, self.units, strict=True)
            )
            parts.append(f"{box} ({b.why})")
        return "; ".join(parts) if parts else "none"

    def verdict(self) -> str:
        """One line: what was certified and how it came out."""
        if self.passes_holds is None:
            return self.source
        holds = "passes" if self.passes_holds else f"FAILS ({self.failing})"
        passivity = {True: "passes", False: "fails", None: "not judged"}[self.passes_passivity]
        return f"{self.source}: holds {holds}; passivity {passivity}"

    def lines(self) -> list[tuple[str, str]]:
        """The facts written into the FMU (modelDescription string constants)."""
        out = [("certificate", self.verdict())]
        if self.passes_holds is not None:
            boxes = [[list(b.lo), list(b.hi)] for b in self.flagged]
            out.append(("certificate_flagged", json.dumps(boxes)))
            out.append(("certificate_flagged_why", json.dumps([b.why for b in self.flagged])))
        return out


def _merge(cells: list[tuple[float, float, set[str]]]) -> list[Flagged]:
    cells = sorted(cells, key=lambda c: c[0])
    out: list[list] = []
    for lo, hi, why in cells:
        if out and lo <= out[-1][1] + 1e-12:
            out[-1][1] = max(out[-1][1], hi)
            out[-1][2] |= why
        else:
            out.append([lo, hi, set(why)])
    order = ("oscillates", "departs", "unstable", "unsettled", "wrong sign", "fold")
    return [Flagged((lo,), (hi,), ", ".join(k for k in order if k in why)) for lo, hi, why in out]


def _hold_why(h: dict) -> set[str]:
    """How a hold of a one-coordinate certificate fails (empty: it passes)."""
    why = set()
    if h["oscillates"]:
        why.add("oscillates")
    if h["departs"]:
        why.add("departs")
    r = h["reached"]
    if not h["oscillates"] and not h["departs"]:
        if r is None:
            why.add("unsettled")
        elif not h["fixed_points"][r]["stable"]:
            why.add("unstable")
    if h["wrong_sign"]:
        why.add("wrong sign")
    return why


def flagged_of_holds(doc: dict) -> list[Flagged]:
    """The flagged ranges of a one-coordinate certificate document (``certify``)."""
    holds = doc["holds"]
    x = np.array([h["x_m"] for h in holds], dtype=float)
    if x.size == 0:
        return []
    edges = np.r_[x[0] - 0.5 * (x[1] - x[0]) if x.size > 1 else x[0], 0.5 * (x[1:] + x[:-1])]
    edges = np.r_[edges, x[-1] + 0.5 * (x[-1] - x[-2]) if x.size > 1 else x[-1]]
    cells = []
    for i, h in enumerate(holds):
        why = _hold_why(h)
        if why:
            cells.append((float(edges[i]), float(edges[i + 1]), why))
    for f in doc.get("folds", []):
        k = int(np.searchsorted(x, f["x_m"]))
        lo, hi = x[max(k - 1, 0)], x[min(k, x.size - 1)]
        cells.append((float(lo), float(hi), {"fold"}))
    return _merge(cells)


def _failing_one(summary: dict, doc: dict) -> str:
    unstable = sum(
        1
        for h in doc["holds"]
        if not h["oscillates"]
        and not h["departs"]
        and (h["reached"] is None or not h["fixed_points"][h["reached"]]["stable"])
    )
    parts = [
        (summary.get("oscillating_holds", 0), "oscillating holds"),
        (summary.get("departing_holds", 0), "departing holds"),
        (unstable, "holds not settling on a stable fixed point"),
        (summary.get("wrong_sign_holds", 0), "wrong-sign holds"),
        (summary.get("folds", 0), "folds"),
    ]
    text = ", ".join(f"{n} {what}" for n, what in parts if n)
    failing = [h for h in doc["holds"] if _hold_why(h)]
    rho = max((p["spectral_radius"] for h in failing for p in h["fixed_points"]), default=None)
    if text and rho is not None and rho >= 1.0:
        text += f" (spectral radius up to {rho:.5g})"
    return text


def flagged_of_vector(doc: dict) -> list[Flagged]:
    """The flagged boxes of a certificate over several coordinates (``certify_vector``): one
    box of +- half the grid's spacing about each hold vector that fails."""
    span = np.array(doc["settings"]["span"], dtype=float)
    half = span / (int(doc["settings"]["per_coordinate"]) - 1)  # half of 2 span / (n - 1)
    wrong = {tuple(q) for q in doc.get("wrong_sign_at", [])}
    out = []
    for h in doc["holds"]:
        q = np.array(h["q"], dtype=float)
        why = []
        if h["fixed_points"] != 1:
            why.append(f"{h['fixed_points']} fixed points")
        if h["stable"] == 0:
            why.append("no stable fixed point")
        elif h["stable"] != h["fixed_points"]:
            why.append("unstable fixed points")
        if tuple(h["q"]) in wrong:
            why.append("wrong sign")
        out.append(Flagged(tuple((q - half).tolist()), tuple((q + half).tolist()), ", ".join(why)))
    return out


def _failing_vector(summary: dict) -> str:
    parts = [
        (summary["holds"] - summary["holds_settling_stably"], "holds not settling on one stable "
         "fixed point"),
        (summary["fold_crossings"], "fold crossings"),
        (summary["wrong_sign_holds"], "wrong-sign holds"),
        (summary["unresolved_boxes"], "unresolved boxes"),
    ]  # fmt: skip
    return ", ".join(f"{n} {what}" for n, what in parts if n)


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
    return doc


def check_belongs(doc: dict, model: BushingModel, path: str | os.PathLike) -> None:
    """Refuse a certificate of another model: its recorded parameters, then the fixed points
    of a few of its holds recomputed on ``model`` (so a retrained network of the same shape
    is told apart), naming what differs."""
    mine = doc["model"]
    if model.n_coords == 1:
        from bushenv.certify.fixed_points import fixed_points
        from bushenv.certify.network import describe, narx_net

        net = narx_net(model)
        _same_params(path, mine, describe(net))
        holds = doc["holds"]
        spread = np.linspace(0, len(holds) - 1, min(CHECKED_HOLDS, len(holds)))
        pick = sorted({int(i) for i in spread})
        fp = fixed_points(net, np.array([holds[i]["x_m"] for i in pick], dtype=float))
        for row, i in enumerate(pick):
            got = np.sort(fp.force_n[fp.hold == row])
            had = np.sort([p["force_n"] for p in holds[i]["fixed_points"]])
            _same_forces(path, holds[i]["x_m"] * 1e3, "mm", had, got)
        return
    from bushenv.planar.fixed_points import fixed_points as planar_fixed_points

    want = {"name": model.name, "dt_s": model.dt}
    _same_params(path, mine, want)
    if doc.get("coords") != list(model.coords):
        raise ModelError(
            f"{path}: a certificate over {doc.get('coords')}, not this model's "
            f"{list(model.coords)}; certify this model (bushenv certify) or drop --certificate"
        )
    listed = doc["holds"][:CHECKED_HOLDS]
    if listed:
        fp = planar_fixed_points(model, np.array([h["q"] for h in listed], dtype=float))
        for row, h in enumerate(listed):
            got = np.sort(fp.force[fp.hold == row][:, 0])
            had = np.sort(np.array(h["forces"], dtype=float).reshape(-1, model.n_coords)[:, 0])
            _same_forces(path, np.array(h["q"]) * 1e3, "mm/mrad", had, got)


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
    tol = FORCE_MATCH_REL * np.maximum(1.0, np.abs(had)) if had.size == got.size else None
    if tol is None or np.any(np.abs(had - got) > tol):
        raise ModelError(
            f"{path}: this certificate is of another model: its fixed points at {at} {unit} "
            f"({np.round(had, 3).tolist()} N) are not this model's ({np.round(got, 3).tolist()} "
            "N); certify this model (bushenv certify) or drop --certificate to certify it at "
            "export"
        )


def is_narx(model: BushingModel) -> bool:
    """Whether ``model`` has a NARX recurrence to certify (nn, hybrid; over three axes nn,
    nn-axis, hybrid). The classes' own modules: the certificate's are not imported for a kind
    without one (they cost a linear model's export half a second)."""
    if model.n_coords == 1:
        from bushenv.models.narx import NarxBushing

        return isinstance(model, NarxBushing)
    from bushenv.models.planar_narx import PlanarNarx

    return isinstance(model, PlanarNarx)


def carried_certificate(
    model: BushingModel,
    spec: Any,
    axis: str,
    *,
    path: str | os.PathLike | None = None,
    reference: Any = None,
    stroke_m: float | None = None,
    spans: tuple[float, ...] = (),
) -> Carried:
    """The certificate the FMU of ``model`` carries. ``path``: a ``certificate.json`` to read
    (checked to be ``model``'s); else run as ``bushenv certify`` runs it, against
    ``reference`` (None: none, wrong sign judged against the deflection) over the stroke
    ``bushenv certify`` takes (the card's, the machine's; ``stroke_m`` on top). Several
    coordinates: ``certify_vector`` over ``spans``. A kind without a recurrence (linear,
    Bouc-Wen) has none: a ``Carried`` that says so (a ``path`` given for one is refused)."""
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
    elif model.n_coords == 1:
        doc, source = _run_one(model, spec, axis, reference, stroke_m)
    else:
        if reference is not None:
            raise ModelError(
                f"--reference {reference}: a three-axis certificate compares with no reference "
                "yet (wrong sign is judged against the deflection); drop --reference"
            )
        doc, source = _run_vector(model, spans)
    s = doc["summary"]
    if model.n_coords == 1:
        flagged, failing = flagged_of_holds(doc), _failing_one(s, doc)
    else:
        flagged, failing = flagged_of_vector(doc), _failing_vector(s)
    return Carried(
        source,
        bool(s["passes_holds"]),
        bool(s["passes_passivity"]),
        tuple(flagged),
        failing,
        units,
        doc,
    )


def _run_one(model, spec, axis, reference, stroke_m) -> tuple[dict, str]:
    from bushenv.certify.certificate import CertifyOptions, certify
    from bushenv.judge import NO_REFERENCE, ScaleFlags, build_judge

    judge = build_judge(
        spec if isinstance(spec, str | os.PathLike) else None,
        NO_REFERENCE if reference is None else reference,
        axis=axis,
        dt=model.dt,
        flags=ScaleFlags(stroke_mm=None if stroke_m is None else stroke_m * 1e3),
        model_object=model,
    )
    opts = CertifyOptions(stroke_m=judge.scales.stroke_m)
    doc = certify(model, judge.reference, opts).document
    against = (
        "no reference (wrong sign judged against the deflection)"
        if judge.reference is None
        else f"reference {judge.reference_spec}"
    )
    return doc, (
        f"certified at export, {opts.holds} holds over +-{opts.stroke_m * 1e3:.4g} mm "
        f"({judge.scales.source}), {against}"
    )


def _run_vector(model, spans: tuple[float, ...]) -> tuple[dict, str]:
    from bushenv.planar.certificate import VectorOptions, certify_vector, per_coordinate

    opts = VectorOptions(tuple(spans), per_coordinate(201, model.n_coords))
    doc, _ = certify_vector(model, opts)
    shown = ", ".join(
        f"{c} +-{s * 1e3:.4g} {'mrad' if u == 'rad' else 'mm'}"
        for c, u, s in zip(model.coords, model.units, spans, strict=True)
    )
    return doc, (
        f"certified at export, {opts.per_coordinate}^{model.n_coords} hold vectors over {shown} "
        "(the three-axis test machine's), no reference (wrong sign: q . f < 0)"
    )
