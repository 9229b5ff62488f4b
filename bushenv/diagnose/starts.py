"""An effect whose records start in a state of their own is named for what it shares.

Thermal lets each record start warm (``Effect.nuisance_columns``: a heat that cools with the
leak, the stiffness and damping lost at the start of that record its own; a judged record
gets one scale of its own along them). Those starts alone change a record's stiffness slowly
through it -- as a relaxation under a hold does, or an amplitude-dependent stiffness from one
record to the next. What only thermal does is a loss that follows the energy dissipated, in
every record and in the order it runs: its shared heating weights. So a row holding such an
effect passes only when it adds, beyond the same row with that effect's starts alone
(``effects.rich.StartsAlone``), a significant cut closing ``BEYOND_STARTS_MIN`` of what the
starts leave above the noise -- the share a pair's partner must close (``rule.PARTNER_MIN``),
not tuned.
"""

from __future__ import annotations

from typing import Any

from bushenv.diagnose.candidates import get_effect
from bushenv.diagnose.effects.base import Combination
from bushenv.diagnose.effects.rich import StartsAlone
from bushenv.diagnose.evidence import cut_z
from bushenv.diagnose.partner import RowOf
from bushenv.diagnose.rule import CLEAR_CUT, PARTNER_MIN, Z_NAME, Context

BEYOND_STARTS_MIN = PARTNER_MIN


def starts_alone(members: list[str]) -> Combination | None:
    """``members`` with each effect that starts per record left as its starts alone (None:
    no member does)."""
    effects = [get_effect(n) for n in members]
    if not any(e.starts_per_record for e in effects):
        return None
    return Combination(tuple(StartsAlone(e) if e.starts_per_record else e for e in effects))


def beyond_starts(r: dict[str, Any], row_of: RowOf, ctx: Context) -> dict | None:
    """How much row ``r`` adds to the same row with its starts alone (None: nothing starts)."""
    combo = starts_alone(r["members"])
    if combo is None:
        return None
    base = row_of(combo)
    z = float(cut_z(ctx.force, base["_pred"], r["_pred"], ctx.edges))
    share = float(ctx.closes(r["gap_after"], base["gap_after"]))
    return {
        "starts_gap": float(base["gap_after"]),
        "z": z,
        "share": share,
        "adds": bool((z >= Z_NAME or share >= CLEAR_CUT) and share >= BEYOND_STARTS_MIN),
    }


def check_beyond_starts(rows: list[dict[str, Any]], row_of: RowOf, ctx: Context) -> None:
    """On rows that would pass: refuse those whose effect's shared weights add nothing beyond
    its per-record starts (``beyond_starts`` in the row)."""
    for r in rows:
        if not r.get("_passes_unless_lag"):
            continue
        check = beyond_starts(r, row_of, ctx)
        if check is None:
            continue
        r["beyond_starts"] = check
        if not check["adds"]:
            r["passes"] = r["_passes_unless_lag"] = False
