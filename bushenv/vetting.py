"""The reference is checked before it judges (``judge.build_judge`` calls ``vet_reference``).

A verdict says "the model departs from the real bushing"; it is worth only what the reference
is. Every check's verdict is *pass*, *fail* or *not checked* (``Check.passed`` True, False or
None; the detail of a "not checked" names what was missing and how to supply it). The vetting
*passed* only when every check passed; it *failed* when one failed (the reference is refused
unless ``--trust-reference``); otherwise it is *not fully checked* and the reference judges,
saying which checks it did not pass. The checks, each with a physical reason and a threshold:

1. **holds** over the judged stroke: ramp to each of ``HOLDS`` displacements in 0.25 s, hold
   ``HOLD_S``. A passive bushing only relaxes in a hold: its force never oscillates, never grows
   away from its value after the first second, and pushes back (``f x > 0``). Flagged
   (``certify.reached_holds.judge_holds``): *oscillating*, *departing*, *wrong sign* (beyond
   ``SIGN_FRACTION`` of the stroke), *not finite*, each against one threshold tied to the
   reference itself (``certify.reached_holds.ring_threshold``: the larger of 3 x its own noise
   in these holds and 1 % of its largest held force), at most the verdicts' force floor.
2. **certificate holds** (NARX references: ``nn``, ``hybrid`` or their files): the reference's
   own certificate (``bushenv certify``, reference-free: wrong sign against the deflection)
   lists the holds where it oscillates, departs or pulls. Each is reached the way a search
   reaches it -- a step at the velocity limit, and sines inside the reference's envelope then
   the hold (``certify.reached_holds.confirm_holds``) -- and judged with the same threshold. A
   confirmed one fails the check; with ``--trust-reference`` every verdict whose profile enters
   its range is marked unvetted (``Vetting.unvetted_ranges_m``).
3. **records**: the reference's RMS ratio on the records its model card names at most
   ``RECORD_LIMIT``: 30 % is beyond every fitted model of the papers (Tables 2-4) and beyond
   any model worth judging with. Not checked without a card or without its records. The
   built-in rubber passes: it is the specimen every record here is measured on.
4. **compatibility** with the model under test: on the records the model's own card names,
   the reference's RMS ratio at most ``RECORD_LIMIT`` (it is a model of the same bushing: a
   reference 3.2 times as stiff is refused). With no such records, the least-squares stiffness
   of both on one random drive within the stroke is compared: within a factor
   ``scales.STIFFNESS_MISMATCH`` (2) it passes; beyond, it is *not checked* (undecided), not a
   refusal -- the model under suspicion is then the only word on which bushing it is, and a
   broken model looks like another bushing; the model's card with its records decides.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.certify.reached_holds import (  # noqa: F401  (the planar vetting's constants)
    DEPART_FRACTION,
    HOLD_S,
    SETTLE_S,
    TAIL_S,
    confirm_holds,
    failing_holds,
    hold_entries,
    judge_holds,
    ranges_of,
    ring_threshold,
)
from bushenv.metrics import rms_ratio
from bushenv.models import BushingModel
from bushenv.scales import STIFFNESS_MISMATCH, BushingScales

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


def vet_reference(
    reference: BushingModel,
    label: str,
    scales: BushingScales,
    card: dict | None = None,
    card_file: Any = None,
    model: BushingModel | None = None,
    model_card: dict | None = None,
    model_file: Any = None,
    envelope: tuple[float, float] | None = None,
    builtin: bool = False,
) -> Vetting:
    """The checks of the module doc on ``reference`` at ``scales``; ``envelope``: the largest
    |x| and |dx/dt| its records cover (default: the judged stroke and velocity); ``builtin``:
    the built-in rubber (the specimen itself)."""
    holds, threshold = hold_check(reference, scales)
    checks = [holds]
    env = envelope or (scales.stroke_m, scales.velocity_m_per_s)
    cert = certificate_check(reference, scales, env, threshold)
    if cert is not None:
        checks.append(cert)
    if builtin:
        checks.append(
            Check(
                "records",
                True,
                "the built-in rubber is the specimen every record here is "
                "measured on (bushenv measure): its records are its own",
            )  # fmt: skip
        )
    else:
        checks.append(records_check(reference, card, card_file, "its own card's records"))
    checks.append(compatibility_check(reference, scales, model, model_card, model_file))
    return Vetting(label, tuple(checks))


def hold_profiles(stroke_m: float, dt: float, holds: int = HOLDS) -> tuple[np.ndarray, np.ndarray]:
    """(T, holds) ramp-and-hold displacements over -stroke..+stroke, and the held values."""
    xs = np.linspace(-stroke_m, stroke_m, holds)
    n_ramp = max(2, int(round(RAMP_S / dt)))
    n_hold = int(round(HOLD_S / dt))
    ramp = np.linspace(0.0, 1.0, n_ramp)[:, None] * xs[None, :]
    return np.vstack([ramp, np.repeat(xs[None, :], n_hold, axis=0)]), xs


def hold_check(reference: BushingModel, scales: BushingScales) -> tuple[Check, float]:
    """Check 1 of the module doc, and the threshold it judged with (N; the certificate check
    uses it too)."""
    dt = reference.dt
    x, xs = hold_profiles(scales.stroke_m, dt)
    try:
        f = reference.copy().simulate(x)
    except Exception as exc:  # a reference that cannot even run its holds
        text = f"the reference raised {type(exc).__name__}: {exc}"
        return Check("holds", False, text), scales.force_floor_n
    th = ring_threshold(f, dt)
    limit = min(th.force_n, scales.force_floor_n)
    how = th.describe()  # capped: never coarser than the verdicts' resolution
    if th.force_n > limit:
        how = f"threshold {limit:.4g} N, the force floor, below the {how}"
    flags = judge_holds(f, xs, int(round(HOLD_S / dt)), limit, dt)
    flags["wrong sign"] &= np.abs(xs) >= SIGN_FRACTION * scales.stroke_m
    step = xs[1] - xs[0]
    span = f"{len(xs)} holds of {HOLD_S:g} s over +-{scales.stroke_m * 1e3:.3g} mm"
    bad = {k: xs[flags[k]] for k in KINDS if flags[k].any()}
    if not bad:
        text = f"{span}: every hold settles, pushes back, stays finite ({how})"
        return Check("holds", True, text), limit
    parts = [
        f"{len(v)} {k} between {v.min() * 1e3:+.3g} and {v.max() * 1e3:+.3g} mm"
        for k, v in bad.items()
    ]
    where = ranges_of([float(v) for vs in bad.values() for v in vs], step)
    return Check("holds", False, f"{span}: " + ", ".join(parts) + f" ({how})", tuple(where)), limit


KINDS = ("not finite", "oscillating", "departing", "wrong sign")


def certificate_check(
    reference: BushingModel,
    scales: BushingScales,
    envelope: tuple[float, float],
    threshold: float,
) -> Check | None:
    """Check 2 of the module doc; None for a reference that is not a NARX network."""
    from bushenv.certify.network import CertifyError

    try:
        entries = hold_entries(reference, None, scales.stroke_m, CERTIFICATE_HOLDS)
    except CertifyError:
        return None
    listed = failing_holds(entries)
    span = f"its certificate, {CERTIFICATE_HOLDS} holds over +-{scales.stroke_m * 1e3:.3g} mm,"
    if not listed:
        return Check("certificate holds", True, f"{span} lists none oscillating, departing or "
                     "wrong-sign")  # fmt: skip
    kinds = sorted({k for h in listed for k in h["kinds"]})
    xl = [h["x_m"] for h in listed]
    said = (
        f"{span} lists {len(listed)} ({', '.join(kinds)}) between {min(xl) * 1e3:+.3g} and "
        f"{max(xl) * 1e3:+.3g} mm"
    )
    confirmed, n = confirm_holds(reference, listed, envelope, threshold)
    reach = (
        f"{n} profiles reaching them after a step or sines inside its envelope (|x| <= "
        f"{envelope[0] * 1e3:.3g} mm, |dx/dt| <= {envelope[1]:.3g} m/s); threshold "
        f"{threshold:.4g} N"
    )
    if not confirmed:
        return Check("certificate holds", True, f"{said}; none confirmed by {reach}")
    worst = max(confirmed, key=lambda c: c.ripple_n)
    found = sorted({k for c in confirmed for k in c.kinds})
    xc = [c.x_m for c in confirmed]
    text = (
        f"{said}; {len(confirmed)} confirmed ({', '.join(found)}) between "
        f"{min(xc) * 1e3:+.3g} and {max(xc) * 1e3:+.3g} mm by {reach}; worst "
        f"{worst.ripple_n:.4g} N p-p at {worst.x_m * 1e3:+.3g} mm after {worst.after}"
    )
    # the listed runs holding a confirmed hold (not every listed hold is simulated)
    step = 2 * scales.stroke_m / (CERTIFICATE_HOLDS - 1)
    runs = [(a, b) for a, b in ranges_of(xl, step) if any(a <= x <= b for x in xc)]
    return Check("certificate holds", False, text, tuple(runs))


def card_records(card: dict | None, card_file: Any) -> tuple[list[Path], list[str]]:
    """The record files a card names that exist (relative paths against the card's folder),
    and the names of those that do not."""
    if not card:
        return [], []
    base = Path(os.fspath(card_file)).parent if card_file is not None else Path(".")
    found, missing = [], []
    for r in card.get("records", []):
        name = r.get("file") or r.get("name")
        if not name:
            continue
        p = Path(name)
        for cand in (p, base / p) if not p.is_absolute() else (p,):
            if cand.is_file():
                found.append(cand)
                break
        else:
            missing.append(str(name))
    return found, missing


def record_errors(paths: list[Path], dt: float, load, error) -> list[tuple[str, float]]:
    """(file name, ``error(record)``) per record file (``load`` reads one); NaN for a record at
    another sample time than ``dt`` (not comparable)."""
    out = []
    for p in paths:
        rec = load(p)
        if abs(rec.dt - dt) > 1e-6 * dt:
            out.append((p.name, float("nan")))
            continue
        out.append((p.name, float(error(rec))))
    return out


def _record_errors(reference: BushingModel, paths: list[Path]) -> list[tuple[str, float]]:
    from bushenv.records import load_csv

    def error(rec) -> float:
        f = reference.copy().simulate(rec.displacement)
        return float(rms_ratio(rec.force, f)) if np.all(np.isfinite(f)) else np.inf

    return record_errors(paths, reference.dt, load_csv, error)


def records_check(reference: BushingModel, card: dict | None, card_file: Any, what: str) -> Check:
    """Check 2: the reference's error on the records its card names."""
    if card is None:
        return Check(
            "records", None, "no model card naming the records it was fitted on: give a "
            "reference file with its card beside it (MODEL.card.json; bushenv fit writes it)",
        )  # fmt: skip
    paths, missing = card_records(card, card_file)
    if not paths:
        where = "" if card_file is None else f" beside {Path(os.fspath(card_file)).parent}"
        return Check(
            "records", None, f"{what} ({', '.join(missing) or 'none named'}) are not there: "
            f"put the record files{where} or at the paths the card names",
        )  # fmt: skip
    errors = _record_errors(reference, paths)
    return judged_errors("records", errors, what, RECORD_LIMIT)


def judged_errors(name: str, errors: list[tuple[str, float]], what: str, limit: float) -> Check:
    text = ", ".join(f"{n} {e:.1%}" if np.isfinite(e) else f"{n} not comparable" for n, e in errors)
    usable = [e for _, e in errors if not np.isnan(e)]
    if not usable:
        return Check(
            name, None, f"{what}: at another sample rate than the reference ({text}); give "
            "records at its rate",
        )  # fmt: skip
    worst = max(usable)
    ok = bool(worst <= limit)
    verdict = "within" if ok else "beyond"
    return Check(name, ok, f"RMS ratio on {what}: {text}, {verdict} {limit:.0%}")


def compatibility_check(
    reference: BushingModel,
    scales: BushingScales,
    model: BushingModel | None,
    model_card: dict | None,
    model_file: Any,
) -> Check:
    """Check 3: the reference and the model under test are models of one bushing."""
    paths, _ = card_records(model_card, model_file)
    if paths:
        errors = _record_errors(reference, paths)
        return judged_errors("compatibility", errors, "the model's card's records", RECORD_LIMIT)
    if model is None:
        return Check("compatibility", None, "no model under test to compare with (a rig judges "
                     "the model's own limits only)")  # fmt: skip
    from bushenv.identify.linear import fitted_linear

    try:
        k_ref = fitted_linear(reference, scales).k_n_per_m
        k_mod = fitted_linear(model, scales).k_n_per_m
    except Exception as exc:
        return Check("compatibility", None, f"no stiffness to compare ({type(exc).__name__}: "
                     f"{exc}); give the model's card with its records")  # fmt: skip
    if not (np.isfinite(k_ref) and np.isfinite(k_mod) and k_ref > 0 and k_mod > 0):
        return Check("compatibility", None, "a stiffness is not finite or not positive; give "
                     "the model's card with its records")  # fmt: skip
    ratio = max(k_ref / k_mod, k_mod / k_ref)
    text = (
        f"dynamic stiffness on a random drive: reference {k_ref / 1e3:.4g} N/mm, model "
        f"{k_mod / 1e3:.4g} N/mm, a factor {ratio:.3g}"
    )
    if ratio <= STIFFNESS_MISMATCH:
        return Check("compatibility", True, f"{text} (within {STIFFNESS_MISMATCH:g}: one bushing)")
    # without records the model is the only word on which bushing it is, and the model is
    # what is under suspicion: another bushing, or a broken model -- records would decide
    return Check(
        "compatibility",
        None,
        f"undecided: {text}, beyond {STIFFNESS_MISMATCH:g}: another bushing, or a broken "
        "model; give the model under test with its card and records (bushenv fit writes "
        "MODEL.card.json beside it) and the reference is compared on those records",
    )
