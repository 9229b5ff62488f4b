"""A second effect only when the first's whole family cannot explain it.

A pair ``{A, B}`` that passes the pair rule (``rule.mark_pairs``) is tested once more: each
member is fitted beside the *other's richest admissible form* (``Effect.rich_columns``: a
denser, wider relaxation spectrum; more Dahl elements and amplitude memories; a backbone with
knots every 10 % and its own growth per side; both heating laws on a finer time-constant grid;
a finer delay grid) and must still close a significant share of what that form leaves above
the noise. A partner that only mends the first effect's usual form where it does not fit the
true one exactly (a relaxation spectrum of another shape leaving a structured remainder that
a backbone or a friction soaks up) adds nothing to the richest form and is not named. Each
side is taken at its best judged form: the other alone at the better of its richest and
usual forms, the member beside it at the better of the richest form and the pair itself (a
richer form extrapolates worse to a judged record than the usual one as often as not; a
partner that the usual pair needs is not refused because the richest form beside it
extrapolates badly); the other alone is taken where it fits (``rule.where_it_fits``). A pair
without the best single effect (the *first*) must close the same share of what the first's
richest form leaves: a pair is an answer only where the first's whole family is not. Shares
are read as in the pair rule (``rule.Context.share``: pooled, or on the median run).

The threshold ``BEYOND_RICH_MIN`` is calibrated on single-effect cases whose forms no
candidate shares (``validation/partner_cases.py``); its false-positive rate is measured there
(studies/2026-11-diagnosis-validation).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from bushenv.diagnose.candidates import get_effect
from bushenv.diagnose.effects.base import Combination
from bushenv.diagnose.effects.rich import RichForm
from bushenv.diagnose.evidence import cut_z
from bushenv.diagnose.rule import CLEAR_CUT, Z_NAME, Context, where_it_fits

# A member closes at least this share of what the other's richest form leaves above the noise.
BEYOND_RICH_MIN = 1.0 / 3.0
PAIRS_TRIED = 3  # passing pairs tested, best first; those further down are not named

RowOf = Callable[[Combination], dict[str, Any]]


def _rich(name: str) -> RichForm:
    return RichForm(get_effect(name))


def _better(a: dict, b: dict | None) -> tuple[dict, str]:
    """The row that predicts the judged records better: ``a`` (a richest form) or ``b``."""
    if b is not None and b["gap_after"] < a["gap_after"]:
        return b, "usual"
    return a, "richest"


def member_beyond_rich(
    member: str,
    other: str,
    row_of: RowOf,
    ctx: Context,
    cache: dict,
    pair: dict | None = None,
    alone: dict | None = None,
) -> dict:
    """How much ``member`` adds to ``other``'s whole family: ``z`` of the cut, ``share`` of
    what ``other`` leaves above the noise that ``member`` beside it closes, and the verdict.

    ``other`` alone is its richest form or its usual row ``alone``, whichever predicts better;
    ``member`` beside it is beside the richest form or the usual ``pair``, the same way."""
    if other not in cache:
        cache[other] = row_of(Combination((_rich(other),)))
    usual = None if alone is None else where_it_fits(alone, ctx)
    base, base_form = _better(where_it_fits(cache[other], ctx), usual)
    both, both_form = _better(row_of(Combination((_rich(other), get_effect(member)))), pair)
    z = float(cut_z(ctx.force, base["_pred"], both["_pred"], ctx.edges))
    share = float(ctx.share(both, base))
    adds = bool((z >= Z_NAME or share >= CLEAR_CUT) and share >= BEYOND_RICH_MIN)
    return {
        "member": member,
        "beside_richest": other,
        "richest_gap": float(base["gap_after"]),
        "gap_with_member": float(both["gap_after"]),
        "forms": [base_form, both_form],
        "z": z,
        "share": share,
        "adds": adds,
    }


def pair_beyond_rich(pair: dict, first: str, row_of: RowOf, ctx: Context, cache: dict) -> dict:
    """How much the pair ``pair`` (without ``first``) adds to ``first``'s richest form."""
    if first not in cache:
        cache[first] = row_of(Combination((_rich(first),)))
    base = where_it_fits(cache[first], ctx)
    z = float(cut_z(ctx.force, base["_pred"], pair["_pred"], ctx.edges))
    share = float(ctx.share(pair, base))
    return {
        "member": pair["effect"],
        "beside_richest": first,
        "richest_gap": float(base["gap_after"]),
        "gap_with_member": float(pair["gap_after"]),
        "forms": ["richest", "usual"],
        "z": z,
        "share": share,
        "adds": bool((z >= Z_NAME or share >= CLEAR_CUT) and share >= BEYOND_RICH_MIN),
    }


def check_partners(
    pairs: list[dict],
    row_of: RowOf,
    ctx: Context,
    first: str | None = None,
    singles: list[dict] | None = None,
) -> None:
    """On ranked ``pairs``: the first ``PAIRS_TRIED`` that would pass keep passing only when
    each member adds to the other's whole family (``member_beyond_rich``; ``singles``: the
    usual rows) and, for a pair without ``first`` (the best single), the pair adds to
    ``first``'s richest form (``beyond_richest`` in the row); passing pairs further down are
    not named (``beyond_richest`` None)."""
    usual = {r["effect"]: r for r in singles or []}
    cache: dict[str, dict] = {}
    tried = 0
    for r in pairs:
        r["passes_pair_rule"] = bool(r.get("passes"))
        if not r.get("_passes_unless_lag"):
            continue
        if tried >= PAIRS_TRIED:
            r["beyond_richest"] = None
            r["passes"] = r["_passes_unless_lag"] = False
            continue
        tried += 1
        a, b = r["members"]
        checks = []
        if first is not None and first not in r["members"]:
            checks.append(pair_beyond_rich(r, first, row_of, ctx, cache))
        if all(c["adds"] for c in checks):
            checks.append(member_beyond_rich(b, a, row_of, ctx, cache, r, usual.get(a)))
        if all(c["adds"] for c in checks):
            checks.append(member_beyond_rich(a, b, row_of, ctx, cache, r, usual.get(b)))
        r["beyond_richest"] = checks
        if not all(c["adds"] for c in checks):
            r["passes"] = r["_passes_unless_lag"] = False
        elif r["passes"]:
            break  # the answer's pair: those below it are not needed
