"""A vetting's verdicts: one ``Check`` per check (pass, fail, not checked) and the ``Vetting`` of
one reference; the thresholds every check shares (``bushenv.vetting`` states the checks)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv.errors import BadInput

HOLDS = 41
RAMP_S = 0.25
SIGN_FRACTION = 0.1
RECORD_LIMIT = 0.30
CERTIFICATE_HOLDS = 201  # the certificate's grid (``bushenv certify``'s default)
UNVETTED_DWELL_S = 0.5  # a profile this long in all in an unvetted region: its verdict is too


VERDICTS = {True: "pass", False: "FAILED", None: "not checked"}


@dataclass(frozen=True)
class Check:
    """One check: ``passed`` True (pass), False (fail) or None (not checked: ``detail`` says
    what was missing and how to supply it). Where a failed check found the reference failing
    (its verdicts there are unvetted when trusted): one coordinate, ``ranges_m``, displacement
    ranges (lo, hi) m; over C > 1, ``boxes``, each per coordinate (lo, hi) in its unit (m or
    rad), one step of the held grid beyond the holds found failing."""

    name: str
    passed: bool | None
    detail: str
    ranges_m: tuple[tuple[float, float], ...] = ()
    boxes: tuple[tuple[tuple[float, float], ...], ...] = ()

    @property
    def verdict(self) -> str:
        return VERDICTS[self.passed]

    def describe(self) -> dict[str, Any]:
        out: dict[str, Any] = {"check": self.name, "passed": self.passed, "detail": self.detail}
        if self.ranges_m:
            out["ranges_m"] = [list(r) for r in self.ranges_m]
        if self.boxes:
            out["boxes"] = [[list(r) for r in box] for box in self.boxes]
        return out


@dataclass(frozen=True)
class Vetting:
    """The checks of one reference. ``passed``: none failed (it may judge; ``describe()``'s
    "passed" means this too); ``complete``: every check passed; ``verdict``: the headline."""

    reference: str
    checks: tuple[Check, ...]

    @property
    def passed(self) -> bool:
        """No check failed: the reference may judge (some checks may not have run)."""
        return all(c.passed is not False for c in self.checks)

    @property
    def complete(self) -> bool:
        """Every check passed."""
        return all(c.passed is True for c in self.checks)

    @property
    def verdict(self) -> str:
        """The headline: passed (every check passed), FAILED (one failed), not fully checked."""
        return "passed" if self.complete else "FAILED" if not self.passed else "not fully checked"

    @property
    def unvetted_ranges_m(self) -> tuple[tuple[float, float], ...]:
        """Where failed checks found the reference failing, (lo, hi) m."""
        spans = sorted(r for c in self.checks if c.passed is False for r in c.ranges_m)
        out: list[tuple[float, float]] = []
        for a, b in spans:  # their union
            if out and a <= out[-1][1]:
                out[-1] = (out[-1][0], max(b, out[-1][1]))
            else:
                out.append((a, b))
        return tuple(out)

    @property
    def unvetted_boxes(self) -> tuple[tuple[tuple[float, float], ...], ...]:
        """Over C > 1, where failed checks found the reference failing: boxes, per coordinate
        (lo, hi) in its unit (``Check.boxes``), each once."""
        return tuple(dict.fromkeys(b for c in self.checks if c.passed is False for b in c.boxes))

    def summary(self) -> str:
        """One line: the failed checks, else the verdict and the checks not passed."""
        bad = [f"{c.name}: {c.detail}" for c in self.checks if c.passed is False]
        if bad:
            return "; ".join(bad)
        if self.complete:
            return "passed"
        todo = [f"{c.name} not checked ({c.detail})" for c in self.checks if c.passed is None]
        n = sum(c.passed is True for c in self.checks)
        return f"not fully checked: {n} of {len(self.checks)} passed; " + "; ".join(todo)

    def headline(self) -> str:
        """A few words: passed, FAILED (the failed checks) or not fully checked (which)."""
        if self.complete:
            return "passed (every check)"
        failed = [c.name for c in self.checks if c.passed is False]
        if failed:
            return f"FAILED ({', '.join(failed)})"
        todo = [c.name for c in self.checks if c.passed is None]
        n = sum(c.passed is True for c in self.checks)
        return f"not fully checked: {n} of {len(self.checks)} passed, not checked: " + ", ".join(
            todo
        )

    def describe(self) -> dict[str, Any]:
        out = {
            "reference": self.reference,
            "passed": self.passed,
            "checks": [c.describe() for c in self.checks],
        }
        if self.unvetted_boxes:
            out["unvetted_boxes"] = [[list(r) for r in box] for box in self.unvetted_boxes]
        return out

    def lines(self) -> list[str]:
        return [f"{c.name}: {c.verdict} ({c.detail})" for c in self.checks]


def unvetted_regions(vetting: Vetting | None, stroke=None) -> list[np.ndarray]:
    """Where ``vetting`` found its reference failing, for any number of coordinates C: (C, 2)
    boxes of per-coordinate (lo, hi) -- one coordinate: its ``unvetted_ranges_m``, widened by
    one step of the certificate's grid over the judged ``stroke`` (m) as the judge does;
    over C > 1 its ``unvetted_boxes`` (``stroke`` unused). Empty without a vetting."""
    if vetting is None:
        return []
    ranges = vetting.unvetted_ranges_m
    if ranges and stroke is None:
        raise BadInput("one coordinate's unvetted ranges are widened by the judged stroke: give it")
    pad = 2 * float(np.ravel(stroke)[0]) / (CERTIFICATE_HOLDS - 1) if ranges else 0.0
    out = [np.array([[a - pad, b + pad]]) for a, b in ranges]
    return out + [np.array(box, dtype=np.float64) for box in vetting.unvetted_boxes]


def enters_unvetted(vetting: Vetting | None, profile, dt: float, stroke=None) -> bool:
    """Whether ``profile`` ((T,) for one coordinate, (T, C)) dwells ``UNVETTED_DWELL_S`` in all
    inside one region where ``vetting`` found its reference failing (``unvetted_regions``:
    every coordinate within the box), so a verdict on it is unvetted. One coordinate: the
    judge's ``in_unvetted_range`` answer (``stroke``: the judged stroke, m, needed there)."""
    regions = unvetted_regions(vetting, stroke)
    if not regions:
        return False
    q = np.asarray(profile, dtype=np.float64)
    q = q.reshape(q.shape[0], -1)
    for box in regions:
        if box.shape[0] != q.shape[1]:
            raise BadInput(
                f"a profile of {q.shape[1]} coordinates against a vetting of {box.shape[0]}"
            )
        inside = np.all((q >= box[:, 0]) & (q <= box[:, 1]), axis=1)
        if np.count_nonzero(inside) * dt >= UNVETTED_DWELL_S:
            return True
    return False
