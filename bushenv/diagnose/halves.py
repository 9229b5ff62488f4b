"""A record that alone shows the gap, judged half against half.

Every record is judged by a fit on the others. When one record alone shows a gap (a TRAIN that
heats while the TESTs are too short or too gentle to; ``showing.showing_records``), every fit
it is judged by comes from records without the effect: no candidate can close its gap there,
and ``showing.py`` has no second record to judge on. The record is then split in two halves,
run as one session (the second begins where the first ended: a heat is carried, no new start),
and the diagnosis runs again: each half judged by a fit on the other half and the other
records, each other record still judged by a fit on the rest (a record without a gap of its
own is often what tells one effect from another: thermal from relaxation). What it names
stands; if it names nothing, the first answer stands.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from bushenv.diagnose.evidence import BLOCK_S
from bushenv.diagnose.inputs import MIN_SAMPLES
from bushenv.diagnose.session import Order
from bushenv.records import Record

HALF_BLOCKS = 4  # each half holds at least this many evidence blocks (the z-test's spread)
SUFFIXES = (".half1", ".half2")


def can_split(rec: Any) -> bool:
    """Whether each half of ``rec`` is long enough to be fitted and judged."""
    n = np.asarray(rec.displacement).size // 2
    return n >= MIN_SAMPLES and n * float(rec.dt) >= HALF_BLOCKS * BLOCK_S


def bounds(n: int) -> list[tuple[int, int]]:
    """The samples of each half of a record of ``n`` samples."""
    return [(0, n // 2), (n // 2, n)]


def halves_of(rec: Any, name: str) -> list[Record]:
    """``rec``'s two halves in time, named ``name.half1`` and ``name.half2``."""
    t, x, f = (np.asarray(getattr(rec, k), float) for k in ("time", "displacement", "force"))
    return [
        Record(t[a:b], x[a:b], f[a:b], name=name + s)
        for (a, b), s in zip(bounds(t.size), SUFFIXES, strict=True)
    ]


def parent_of(name: str) -> tuple[str, int] | None:
    """(the record, 0 or 1) for a half's name, else None."""
    for i, s in enumerate(SUFFIXES):
        if name.endswith(s):
            return name[: -len(s)], i
    return None


def runs_of(names: Sequence[str]) -> list[int]:
    """Each record's run, the two halves of a split record one run (one programme run
    once: the median run of ``rule.Context.share`` counts it once)."""
    roots = [parent_of(n)[0] if parent_of(n) else n for n in names]
    first = list(dict.fromkeys(roots))
    return [first.index(r) for r in roots]


def split_records(
    recs: Sequence[Any], names: Sequence[str], name: str
) -> tuple[list[Any], list[str]]:
    """``recs`` with the record ``name`` replaced by its halves, and their names."""
    out, out_names = [], []
    for r, n in zip(recs, names, strict=True):
        parts = halves_of(r, n) if n == name else [r]
        out += parts
        out_names += [p.name for p in parts] if n == name else [n]
    return out, out_names


def order_with_halves(order: Order | None, name: str) -> list[tuple[str, Any]]:
    """The run order with ``name`` run as its two halves, the second without a rest; a record
    not in the order begins a session of its own (its start unknown)."""
    first, second = (name + s for s in SUFFIXES)
    out: list[tuple[str, Any]] = []
    for n, rest in order or []:
        out += [(first, rest), (second, 0.0)] if n == name else [(n, rest)]
    if not any(n == name for n, _ in order or []):
        out += [(first, None), (second, 0.0)]
    return out
