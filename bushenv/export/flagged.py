"""What an FMU carries of a certificate: the flagged deflection boxes and the verdict.

A hold fails the hold certificate when its free run does not settle on a stable fixed point
(it oscillates, departs, or sits on an unstable one), when it has more than one fixed point or
one the search left unresolved, when its static force has the wrong sign, or when a fold lies
next to it; ``passes_holds`` is false exactly when one does, so a model fails its certificate
exactly when its FMU has a flagged box. Each failing hold stands for its cell of the grid: per
coordinate from half-way to the value below to half-way to the value above; a fold for the box
between the two holds that bracket it; touching boxes merged (one coordinate: ranges). The
passivity verdict is a property of frequency bands, not of deflections: it is carried as a
fact, not as a box. Certificates of one coordinate written before the one layout (no ``q``)
read as they did then.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np


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


def hold_q(h: dict) -> list[float]:
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
    q = np.array([hold_q(h) for h in holds], dtype=float)
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


def failing_text(summary: dict, doc: dict) -> str:
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
