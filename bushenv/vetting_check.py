"""A vetting's verdicts: one ``Check`` per check (pass, fail, not checked) and the ``Vetting`` of
one reference; the thresholds every check shares (``bushenv.vetting`` states the checks)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

HOLDS = 41
RAMP_S = 0.25
SIGN_FRACTION = 0.1
RECORD_LIMIT = 0.30
CERTIFICATE_HOLDS = 201  # the certificate's grid (``bushenv certify``'s default)


VERDICTS = {True: "pass", False: "FAILED", None: "not checked"}


@dataclass(frozen=True)
class Check:
    """One check: ``passed`` True (pass), False (fail) or None (not checked: ``detail`` says
    what was missing and how to supply it). ``ranges_m``: displacement ranges where a failed
    check found the reference failing (its verdicts there are unvetted when trusted)."""

    name: str
    passed: bool | None
    detail: str
    ranges_m: tuple[tuple[float, float], ...] = ()

    @property
    def verdict(self) -> str:
        return VERDICTS[self.passed]

    def describe(self) -> dict[str, Any]:
        out: dict[str, Any] = {"check": self.name, "passed": self.passed, "detail": self.detail}
        if self.ranges_m:
            out["ranges_m"] = [list(r) for r in self.ranges_m]
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
        return {
            "reference": self.reference,
            "passed": self.passed,
            "checks": [c.describe() for c in self.checks],
        }

    def lines(self) -> list[str]:
        return [f"{c.name}: {c.verdict} ({c.detail})" for c in self.checks]
