"""No candidate is a stiffness lost for good.

A stiffness lost at the largest deflection reached and never recovered (a Mullins softening,
a damage) is none of the candidates, yet each can soak it up: friction's Payne term follows
the recent amplitude, a heat builds up while the amplitude is high, a softening backbone loses
stiffness at the large deflections. A row that would pass is refused when the same row with
such a stiffness beside it (``Effect.lasting_columns``: a saturating loss with the largest
deflection so far) fits clearly better: the added column's cut is significant (``Z_NAME``,
or ``CLEAR_CUT`` of the row's excess gap), it closes at least ``LASTS_MIN`` of what the row
leaves above the noise (the lost stiffness, not the row, explains most of what is left) and
at least ``SHRINK_MIN`` of the null's excess gap, as much as a single effect must close to be
named (a sliver of a row that leaves all but noise is no evidence). Where the stiffness
recovers (a Payne softening, a heat that cools) or nothing is lost, the column adds little.
What it leaves is read pooled and on the median run, the smaller (``rule.Context.share``):
a stiffness lost for good is the specimen's and shows beside the row on most runs; a column
that mends the one run where the row's fit extrapolates far (a heat carried to a programme
faster than those it was fitted on) refuses nothing.

``LASTS_MIN`` and ``SHRINK_MIN`` lean to keeping a real effect (the diagnosis-validation
study, ninth revision): every answer on the own cases in forms no candidate shares and
on both development sets was kept. The closest calls: an own thermal single whose column
closes 37 % of what it leaves (4 % of the null's gap), a delay left all but at the noise
(57 %, 0.6 % of the null's). The outside set's Mullins softenings, named friction or thermal
before, closed 69-85 % of what their rows leave and 27-61 % of the null's gap.
"""

from __future__ import annotations

from typing import Any

from bushenv.diagnose.candidates import get_effect
from bushenv.diagnose.effects.base import Combination
from bushenv.diagnose.effects.rich import LastingForm
from bushenv.diagnose.evidence import cut_z
from bushenv.diagnose.partner import RowOf
from bushenv.diagnose.rule import CLEAR_CUT, SHRINK_MIN, Z_NAME, Context

LASTS_MIN = 0.5  # the lost stiffness, not the row, explains most of what the row leaves


def lasting_evidence(r: dict[str, Any], row_of: RowOf, ctx: Context) -> dict[str, Any]:
    """How much a stiffness lost for good, fitted beside row ``r``'s effects, adds to it."""
    members = [get_effect(n) for n in r["members"]]
    members[0] = LastingForm(members[0])  # one lost-for-good column beside the row
    lasting = row_of(Combination(tuple(members)))
    z = float(cut_z(ctx.force, r["_pred"], lasting["_pred"], ctx.edges))
    share = ctx.share(lasting, r, pick=min)
    gap, null = lasting["gap_after"], ctx.gap_null
    of_null = ctx.closes(gap, null) - ctx.closes(r["gap_after"], null)  # of the null's excess
    lasts = (z >= Z_NAME or share >= CLEAR_CUT) and share >= LASTS_MIN and of_null >= SHRINK_MIN
    return {"gap_with_it": float(gap), "z": z, "share": share,
            "of_null": float(of_null), "refuses": bool(lasts)}  # fmt: skip


def check_lasting(rows: list[dict[str, Any]], row_of: RowOf, ctx: Context) -> None:
    """Rows that would pass are refused where a stiffness lost for good explains most of what
    they leave (``lasting_softening`` in the row)."""
    for r in rows:
        if not r.get("_passes_unless_lag"):
            continue
        r["lasting_softening"] = ev = lasting_evidence(r, row_of, ctx)
        if ev["refuses"]:
            r["passes"] = r["_passes_unless_lag"] = False
