"""A session: records in the order the rig ran them, with the rests between.

A specimen carries a heat from one record to the next; run in an unknown order, every record
needs a start of its own, and on one record a start, the spring and the heating are one family
(``fitting.fit``). Given the order, a record's start is what the records before it left, cooled
over the rests, and a session has one unknown start (none if it began cold).

The order is ``[(name, rest), ...]``: ``name`` a record's name (its file stem), ``rest`` the
rest in seconds since the row before ended; ``None`` begins a session whose start is unknown
(the specimen may have run before it), ``"cold"`` one that begins at rest. Records not listed
are each a session of their own with an unknown start, as without an order.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from bushenv.diagnose.design import Prepared
from bushenv.diagnose.errors import DiagnoseError

COLD = "cold"
HEADER = ("record", "rest_before_s")
Order = Sequence[tuple[str, float | str | None]]


class OrderFile(list):
    """A run order read from a file: its rows, and where each came from (for messages)."""

    def __init__(self, rows, path: Path, lines: list[int]) -> None:
        super().__init__(rows)
        self.path, self.lines = path, lines


def _where(order: Order, i: int) -> str:
    """Row ``i`` of ``order`` in a message: its file and line if read from one."""
    if isinstance(order, OrderFile):
        return f"{order.path} line {order.lines[i]}"
    return f"run order row {i + 1}"


def read_order(path: str | Path) -> OrderFile:
    """The run order from a CSV file ``record,rest_before_s``: one row per record in the order
    run; an empty rest (or ``cold``) begins a session (unknown start, or at rest)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise DiagnoseError(f"{path}: cannot read the run order ({e.strerror})") from None
    rows = [(i, r) for i, r in enumerate(csv.reader(text.splitlines()), 1) if any(r)]
    if not rows or tuple(c.strip() for c in rows[0][1]) != HEADER:
        raise DiagnoseError(
            f"{path} line 1: expected the header {','.join(HEADER)} (one row per record, in "
            "the order run; an empty rest begins a session)"
        )
    order: list[tuple[str, float | str | None]] = []
    lines = [line for line, _ in rows[1:]]
    for line, row in rows[1:]:
        if len(row) != 2 or not row[0].strip():
            raise DiagnoseError(
                f"{path} line {line}: expected a record name and a rest in s, got {row}"
            )
        name, rest = row[0].strip(), row[1].strip()
        if rest == "":
            order.append((name, None))
        elif rest.lower() == COLD:
            order.append((name, COLD))
        else:
            try:
                order.append((name, float(rest)))
            except ValueError:
                raise DiagnoseError(
                    f"{path} line {line}: rest {rest!r} is not a number of seconds (or empty, "
                    f"or {COLD!r}, to begin a session)"
                ) from None
    return OrderFile(order, path, lines)


def link(preps: Sequence[Prepared], order: Order) -> list[list[str]]:
    """Tell each record of ``order`` what ran before it (``Signals.before``, the session's
    time and start); returns the sessions as lists of names."""
    by_name = {p.name: p for p in preps}
    if len(by_name) != len(preps):
        twice = sorted({p.name for p in preps if sum(q.name == p.name for q in preps) > 1})
        raise DiagnoseError(
            f"a run order needs every record's name (file stem) distinct; {', '.join(twice)} "
            "name more than one record: rename the files"
        )
    seen: set[str] = set()
    sessions: list[list[str]] = []
    first: Prepared | None = None
    prev: Prepared | None = None
    for i, (name, rest) in enumerate(order):
        if name not in by_name:
            raise DiagnoseError(
                f"{_where(order, i)}: no record named {name!r}; the records are "
                + ", ".join(sorted(by_name))
            )
        if name in seen:
            raise DiagnoseError(f"{_where(order, i)}: record {name!r} is listed twice")
        seen.add(name)
        p = by_name[name]
        if rest is None or rest == COLD:
            first, prev = p, p
            p.signals.session_cold = rest == COLD
            sessions.append([name])
            continue
        if isinstance(rest, str) or not (np.isfinite(rest) and rest >= 0):
            raise DiagnoseError(
                f"{_where(order, i)}: rest {rest!r} of {name!r} is not a time in s >= 0"
            )
        if prev is None or first is None:
            raise DiagnoseError(
                f"{_where(order, i)}: {name!r} has a rest but no record before it; the "
                f"first row begins a session (an empty rest, or {COLD!r})"
            )
        s, before = p.signals, prev.signals
        s.before = (before, float(rest))
        s.session_time_s = before.session_time_s + before.x.size * before.dt + float(rest)
        s.session_cold = first.signals.session_cold
        p.start_of = first.uid
        sessions[-1].append(name)
        prev = p
    return sessions
