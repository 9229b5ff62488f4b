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


_ORDER = ("oscillates", "departs", "unstable", "unsettled", "several fixed points",
          "unresolved", "wrong sign", "fold")  # fmt: skip


def _merge(boxes: list[tuple[np.ndarray, np.ndarray, set[str]]]) -> list[Flagged]:
    """Boxes merged where two touch along one coordinate and agree in every other (one
    coordinate: touching ranges), until none do."""
    out = [[lo.copy(), hi.copy(), set(why)] for lo, hi, why in boxes]
    merged = True
    while merged:
        merged = False
        out.sort(key=lambda b: tuple(b[0]))
        for a in range(len(out)):
            for b in range(a + 1, len(out)):
                la, ha, _ = out[a]
                lb, hb, _ = out[b]
                same = np.isclose(la, lb, rtol=0, atol=1e-12) & np.isclose(
                    ha, hb, rtol=0, atol=1e-12
                )
                if np.sum(~same) == 1:
                    j = int(np.flatnonzero(~same)[0])
                    if lb[j] <= ha[j] + 1e-12 and la[j] <= hb[j] + 1e-12:
                        la[j], ha[j] = min(la[j], lb[j]), max(ha[j], hb[j])
                        out[a][2] |= out[b][2]
                        del out[b]
                        merged = True
                        break
                elif same.all():
                    out[a][2] |= out[b][2]
                    del out[b]
                    merged = True
                    break
            if merged:
                break
    return [
        Flagged(tuple(lo.tolist()), tuple(hi.tolist()), ", ".join(k for k in _ORDER if k in why))
        for lo, hi, why in out
    ]


def _q(h: dict) -> list[float]:
    """A hold's deflection vector (certificates of one coordinate before the one layout: x_m)."""
    return h["q"] if "q" in h else [h["x_m"]]


def _hold_why(h: dict) -> set[str]:
    """How a hold of a certificate fails (empty: it passes)."""
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
    if "q" in h:  # the one layout's verdict: one fixed point per hold, every root found
        if len(h["fixed_points"]) > 1:
            why.add("several fixed points")
        if h.get("unresolved_cells"):
            why.add("unresolved")
    if h["wrong_sign"]:
        why.add("wrong sign")
    return why


def _cell_edges(values: np.ndarray) -> np.ndarray:
    """(N + 1,) edges half-way between sorted grid values, the ends as far out as the nearest."""
    x = np.unique(values)
    if x.size == 1:
        return np.r_[x, x]
    mid = 0.5 * (x[1:] + x[:-1])
    return np.r_[x[0] - 0.5 * (x[1] - x[0]), mid, x[-1] + 0.5 * (x[-1] - x[-2])]


def flagged_of_holds(doc: dict) -> list[Flagged]:
    """The flagged boxes of a certificate document (``certify``): each failing hold stands for
    its cell of the grid (per coordinate from half-way to the value below to half-way to the
    value above), each fold for the box between the two holds that bracket it; touching boxes
    merged."""
    holds = doc["holds"]
    if not holds:
        return []
    q = np.array([_q(h) for h in holds], dtype=float)
    axes = [np.unique(q[:, j]) for j in range(q.shape[1])]
    edges = [_cell_edges(a) for a in axes]
    boxes = []
    for h, row in zip(holds, q, strict=True):
        why = _hold_why(h)
        if why:
            k = [int(np.searchsorted(a, v)) for a, v in zip(axes, row, strict=True)]
            lo = np.array([e[i] for e, i in zip(edges, k, strict=True)])
            hi = np.array([e[i + 1] for e, i in zip(edges, k, strict=True)])
            boxes.append((lo, hi, why))
    for f in doc.get("folds", []):
        if "q_from" in f:
            a, b = np.array(f["q_from"]), np.array(f["q_to"])
        else:  # one coordinate: the holds that bracket the fold
            x = axes[0]
            k = int(np.searchsorted(x, f["x_m"]))
            a, b = x[[max(k - 1, 0)]], x[[min(k, x.size - 1)]]
        boxes.append((np.minimum(a, b), np.maximum(a, b), {"fold"}))
    return _merge(boxes)


def _failing(summary: dict, doc: dict) -> str:
    """The failing checks of a certificate, one line."""
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
        (summary.get("holds_with_more_than_one", 0), "holds with more than one fixed point"),
        (summary.get("wrong_sign_holds", 0), "wrong-sign holds"),
        (summary.get("folds", 0), "folds"),
        (summary.get("unresolved_cells", 0) if "q" in doc["holds"][0] else 0, "unresolved cells"),
    ]
    text = ", ".join(f"{n} {what}" for n, what in parts if n)
    failing = [h for h in doc["holds"] if _hold_why(h)]
    rho = max((p["spectral_radius"] for h in failing for p in h["fixed_points"]), default=None)
    if text and rho is not None and rho >= 1.0:
        text += f" (spectral radius up to {rho:.5g})"
    return text


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
    fp = fixed_points(net, np.array([_q(holds[i]) for i in pick], dtype=float))
    units = "mm" if model.n_coords == 1 else "mm/mrad"
    for row, i in enumerate(pick):
        got = fp.force[fp.hold == row]
        got = got[np.argsort(got[:, 0], kind="stable")]
        at = np.array(_q(holds[i])) * 1e3
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
    spans: tuple[float, ...] = (),
) -> Carried:
    """The certificate the FMU of ``model`` carries. ``path``: a ``certificate.json`` to read
    (checked to be ``model``'s); else run as ``bushenv certify`` runs it, against
    ``reference`` (None: none, wrong sign judged against the deflection) over the span
    ``bushenv certify`` takes (one coordinate: the card's stroke, the machine's; ``stroke_m``
    on top; several: ``spans``, the test machine's). A kind without a recurrence (linear,
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
    else:
        doc, source = _run(model, spec, axis, reference, stroke_m, spans)
    s = doc["summary"]
    return Carried(
        source,
        bool(s["passes_holds"]),
        bool(s["passes_passivity"]),
        tuple(flagged_of_holds(doc)),
        _failing(s, doc),
        units,
        doc,
    )


def _judged(model, spec, axis, reference, stroke_m) -> tuple[Any, float, str, str]:
    """One coordinate: (reference, stroke, where the stroke comes from, the reference's
    description) from the judging setup (``bushenv.judge``, one coordinate's)."""
    from bushenv.judge import NO_REFERENCE, ScaleFlags, build_judge

    judge = build_judge(
        spec if isinstance(spec, str | os.PathLike) else None,
        NO_REFERENCE if reference is None else reference,
        axis=axis,
        dt=model.dt,
        flags=ScaleFlags(stroke_mm=None if stroke_m is None else stroke_m * 1e3),
        model_object=model,
    )
    return judge.reference, judge.scales.stroke_m, judge.scales.source, judge.reference_spec


def _run(model, spec, axis, reference, stroke_m, spans) -> tuple[dict, str]:
    from bushenv.certify.certificate import CertifyOptions, certify, per_coordinate
    from bushenv.models import get_model

    if model.n_coords == 1:
        ref, stroke, span_source, ref_spec = _judged(model, spec, axis, reference, stroke_m)
        span = (stroke,)
    else:
        span, span_source, ref_spec = tuple(spans), "the three-axis test machine's", reference
        ref = None
        if reference is not None:
            ref = get_model(reference, axis=axis, dt=model.dt, coords=model.n_coords,
                            wanted_by="bushenv export --reference")  # fmt: skip
    opts = CertifyOptions(span=span)
    doc = certify(model, ref, opts).document
    against = (
        "no reference (wrong sign judged against the deflection: q . f < 0)"
        if ref is None
        else f"reference {ref_spec}"
    )
    shown = ", ".join(
        f"{c} +-{s * 1e3:.4g} {'mrad' if u == 'rad' else 'mm'}"
        for c, u, s in zip(model.coords, model.units, span, strict=True)
    )
    n = per_coordinate(opts.holds, model.n_coords)
    grid = f"{n} holds" if model.n_coords == 1 else f"{n}^{model.n_coords} hold vectors"
    return doc, f"certified at export, {grid} over {shown} ({span_source}), {against}"
