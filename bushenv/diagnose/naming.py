"""The naming rule applied to judged rows, in its order: which pass (none where a stiffness
lost for good explains most of what it leaves), the ranking, the pairs' rule and each partner
beside the other's richest form (``rule.py``, ``lasting.py``, ``partner.py``). Used on
all judged records together (``fit.py``) and on the records that show the gap
(``showing.py``)."""

from __future__ import annotations

from typing import Any

from bushenv.diagnose import lasting, partner, rule


def apply_rule(
    singles: list[dict[str, Any]],
    pairs: list[dict[str, Any]],
    ctx: rule.Context,
    row_of: partner.RowOf,
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """``singles`` and ``pairs`` (``failed_to_fit`` marked) ranked best first, each marked
    ``passes``; a pair's members are put the better single first."""
    rule.mark_passes(singles + pairs, ctx)
    lasting.check_lasting(singles, row_of, ctx)
    singles = rule.rank(singles, [r["effect"] for r in singles], ctx)
    order = [r["effect"] for r in singles]
    for r in pairs:  # the better single first
        r["members"] = sorted(r["members"], key=order.index)
        r["effect"] = "+".join(r["members"])
    rule.mark_pairs(singles, pairs, ctx)
    lasting.check_lasting(pairs, row_of, ctx)
    pairs = rule.rank(pairs, order, ctx)
    first = next((r["effect"] for r in singles if not r["failed_to_fit"]), None)
    partner.check_partners(pairs, row_of, ctx, first, singles)
    return singles, pairs
