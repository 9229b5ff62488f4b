"""The rules every record file and record array meets, for C coordinates: finite values, time
strictly increasing with a uniform step, plausible magnitudes per kind of column, a dynamic
test's sample rate, and the one-axis header with units in brackets (``bushenv.records``
states the format; the reader and the writer call these)."""

from __future__ import annotations

import difflib
import re

import numpy as np

from bushenv.record_columns import (
    HINT,
    NAME_UNIT,
    ONE_AXIS,
    PLAUSIBLE,
    SI,
    Columns,
    RecordError,
)

HEADER = ("time", "displacement", "force")
HEADER_TEXT = ",".join(HEADER)
STEP_RTOL = 0.01  # a step may differ from dt by 1 % of dt ...
STEP_ATOL_S = 1e-9  # ... plus 1 ns (printed times lose digits)
MAX_PLAUSIBLE_DISPLACEMENT_M = 0.1
MAX_PLAUSIBLE_FORCE_N = 1.0e6
# Sample rates of a dynamic bushing test under a plain "time" header; outside, the unit is
# almost always wrong (ms read as s) and must be stated in the header.
PLAUSIBLE_RATE_HZ = (10.0, 100e3)
MAX_RECORD_BYTES = 256 * 2**20
# units a header may state per column, and their factor to SI
UNITS = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6},
    "displacement": {"m": 1.0, "mm": 1e-3, "um": 1e-6},
    "force": {"N": 1.0, "kN": 1e3},
}


# ----- checks shared by load and save ----------------------------------------------------------
def check_columns(
    t: np.ndarray,
    x: np.ndarray,
    f: np.ndarray,
    label: str,
    where,
    max_displacement_m: float = MAX_PLAUSIBLE_DISPLACEMENT_M,
    max_force_n: float = MAX_PLAUSIBLE_FORCE_N,
    cols: Columns = ONE_AXIS,
    stated: np.ndarray | None = None,
) -> None:
    """Semantic checks; ``where(i)`` names sample i (a file line or a sample index). ``cols``:
    the record's columns (several coordinates: (T, C) ``x`` and ``f``, each column against the
    plausibility limit of its kind unless ``stated``, per column, says its unit was written)."""
    if t.size < 2:
        raise RecordError(f"{label}: {t.size} sample(s); need at least 2 to know the sample time")
    c = len(cols.coords)
    named = [("time", "time", t)]  # (column, kind, values) in the header's order
    for names, kinds, a in (
        (cols.displacement, cols.displacement_kinds, x.reshape(len(t), c)),
        (cols.force, cols.force_kinds, f.reshape(len(t), c)),
    ):
        named += [(n, k, a[:, i]) for i, (n, k) in enumerate(zip(names, kinds, strict=True))]
    for key, _, a in named:
        bad = ~np.isfinite(a)
        if bad.any():
            i = int(np.argmax(bad))
            raise RecordError(f"{where(i)}: {key} is {float(a[i])!r}, expected a finite number")
    steps = np.diff(t)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0)) + 1
        if t[i] == t[i - 1]:
            raise RecordError(f"{where(i)}: time repeats ({float(t[i])!r} twice)")
        raise RecordError(
            f"{where(i)}: time goes backwards ({float(t[i])!r} after {float(t[i - 1])!r})"
        )
    dt = float(np.median(steps))
    tol = STEP_RTOL * dt + STEP_ATOL_S
    off = np.abs(steps - dt) > tol
    if off.any():
        i = int(np.argmax(off)) + 1
        raise RecordError(
            f"{where(i)}: time step {float(steps[i - 1])!r} s "
            f"({float(t[i - 1])!r} to {float(t[i])!r}) differs from the record's step "
            f"{dt!r} s by more than the tolerance {tol:.3g} s "
            f"({STEP_RTOL:.0%} of dt + {STEP_ATOL_S:g} s); records must be uniformly sampled"
        )
    plausible = [
        (key, a, np.inf if stated is not None and stated[j] else PLAUSIBLE[kind], SI[kind],
         HINT[kind])
        for j, (key, kind, a) in enumerate(named) if j > 0
    ]  # fmt: skip
    if cols is ONE_AXIS:  # the one-axis columns' own limits (overridable) and hints
        plausible = _one_axis_limits(x, f, max_displacement_m, max_force_n)
    for key, a, limit, unit, hint in plausible:
        i = int(np.argmax(np.abs(a)))
        if abs(a[i]) > limit:
            raise RecordError(
                f"{where(i)}: {key} {float(a[i])!r} {unit} exceeds {limit:g} {unit}; {hint}"
            )


def _one_axis_limits(x, f, max_displacement_m: float, max_force_n: float) -> tuple:
    return (
        (
            "displacement",
            x,
            max_displacement_m,
            "m",
            "looks like millimetres (the column must be metres). If it really is metres, say "
            "so: raise the limit (bushenv diagnose --max-displacement 0.5; "
            "load_csv(..., max_displacement_m=0.5)) or write the unit in the header: "
            "'displacement [m]' ('displacement [mm]' converts millimetres)",
        ),
        (
            "force",
            f,
            max_force_n,
            "N",
            "that is 40 times the test machine's 25 kN: wrong units (the column must be "
            "newtons) or a diverged run. If it is right, raise the limit (bushenv diagnose "
            "--max-force; load_csv(..., max_force_n=...)) or write the unit in the header: "
            "'force [N]' or 'force [kN]'",
        ),
    )


def check_rate(t: np.ndarray, label: str, where) -> None:
    """Refuse a plain ``time`` column whose sample rate no dynamic test has (``where(1)``
    names the second sample); the message says which unit the column looks like."""
    step = float(np.median(np.diff(t)))
    rate = 1.0 / step
    low, high = PLAUSIBLE_RATE_HZ
    if is_plausible_rate(t):
        return
    looks = [
        (name, unit)
        for name, unit in (("milliseconds", "ms"), ("microseconds", "us"))
        if low <= rate / UNITS["time"][unit] <= high
    ]
    if rate < low and looks:
        name, unit = looks[0]
        fix = (
            f"the time column looks like {name} ({rate / UNITS['time'][unit]:.6g} Hz if it "
            f"is): write its unit in the header, 'time [{unit}]'"
        )
    elif rate < low:
        fix = "if the time column is not in seconds, write its unit in the header ('time [ms]')"
    else:
        fix = "check the time column: no bushing test machine samples this fast"
    raise RecordError(
        f"{where(1)}: time step {step!r} s is {rate:.6g} Hz sampling, implausible for a dynamic "
        f"test ({low:g} Hz to {high / 1e3:g} kHz); {fix}, or 'time [s]' if it really is "
        "seconds"
    )


def is_plausible_rate(t: np.ndarray) -> bool:
    """Within ``PLAUSIBLE_RATE_HZ``, give or take the time step's own 1 % tolerance."""
    rate = 1.0 / float(np.median(np.diff(t)))
    low, high = PLAUSIBLE_RATE_HZ
    return low * (1 - STEP_RTOL) <= rate <= high * (1 + STEP_RTOL)


def units_row_problem(row: list[str], header: list[str]) -> str | None:
    """What to say when the first data row holds units (``s,mm,kN``), else None."""
    units = [re.sub(r"^[\[(]\s*|\s*[\])]$", "", s.strip()) for s in row]
    for text in units:
        try:
            float(text)
            return None  # a number: not a units row
        except ValueError:
            pass
    known = {u.lower() for table in UNITS.values() for u in table} | {"sec", "µm", "μm", "kn"}
    if not any(u.lower() in known for u in units):
        return None
    shown = ",".join(s.strip() for s in row)
    names, factors, _ = header_units(header)
    if factors:
        return f"'{shown}' looks like a row of units; the header already states them: delete it"
    suggestion = ",".join(f"{n.strip()} [{u}]" for n, u in zip(names, units, strict=False))
    listed = "; ".join(f"{n} {', '.join(table)}" for n, table in UNITS.items())
    return (
        f"'{shown}' looks like a row of units under the header; put each unit in the header "
        f"instead, '{suggestion}', and delete this row (units: {listed})"
    )


def header_units(fields: list[str]) -> tuple[list[str], dict[str, float], str | None]:
    """(names without units, {column: factor to SI} for stated units, problem or None)."""
    names, factors = [], {}
    for text in fields:
        m = NAME_UNIT.match(text)
        if m is None:
            names.append(text.strip())
            continue
        name, unit = m.group(1), m.group(2)
        names.append(name)
        known = UNITS.get(name)
        if known is not None and unit not in known:
            shown = ",".join(fields)
            problem = f"unknown unit {unit!r} for {name} in header '{shown}'; known: "
            return names, factors, problem + ", ".join(known)
        if known is not None:
            factors[name] = known[unit]
    return names, factors, None


def header_problem(fields: list[str]) -> str | None:
    """None if ``fields`` is the header (units allowed), else what is wrong with it."""
    names, _, problem = header_units(fields)
    if problem:
        return problem
    if tuple(n.strip() for n in names) == HEADER:
        return None
    shown = ",".join(fields)
    expected = f"expected exactly '{HEADER_TEXT}'"
    if len(names) == 1 and ";" in names[0]:
        return f"header '{shown}' looks ';'-separated; {expected} (comma separated)"
    if len(names) == 1 and "\t" in names[0]:
        return f"header '{shown}' looks tab-separated; {expected} (comma separated)"
    numeric = 0
    for s in names:
        try:
            float(s)
            numeric += 1
        except ValueError:
            pass
    if numeric == len(names) and names:
        return f"the first line '{shown}' is data, not a header; {expected}"
    missing = [h for h in HEADER if h not in names]
    unknown = [s for s in names if s not in HEADER]
    if missing and unknown:
        parts = []
        for s in unknown:
            close = difflib.get_close_matches(s.lower(), missing, n=1, cutoff=0.6)
            if close:
                parts.append(f"column '{s}' should be '{close[0]}'")
            else:
                parts.append(f"unknown column '{s}'")
        still_missing = [
            m
            for m in missing
            if not any(difflib.get_close_matches(s.lower(), [m], n=1, cutoff=0.6) for s in unknown)
        ]
        parts += [f"missing column '{m}'" for m in still_missing]
        return f"header '{shown}': {'; '.join(parts)}; {expected}"
    if missing:
        return (
            f"header '{shown}': missing column(s) {', '.join(repr(m) for m in missing)}; {expected}"
        )
    if unknown:
        return (
            f"header '{shown}': extra column(s) {', '.join(repr(u) for u in unknown)} "
            f"(extra columns are not allowed); {expected}"
        )
    return f"header '{shown}': columns repeated or out of order; {expected}"
