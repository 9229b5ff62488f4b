"""The naming rule: which candidate is named, and the two effects ranked first.

Gaps are ``rms_ratio(measured, predicted)`` (seed 000 eq. 8) over all judged samples; the
*null* is the baseline with its spring and damper refitted. A candidate set ``S`` with ``p``
extra parameters, judged mean squared error ``MSE_S`` and fitted on ``N`` samples:

1. **passes** when it shrinks the null's gap by at least ``SHRINK_MIN`` and its cut in judged
   MSE exceeds what fitting ``p`` weights to noise could explain,
   ``MSE_null - MSE_S > NOISE_MARGIN p MSE_S / N`` (``MSE_S`` bounds the noise variance);
2. a **pair** ``{A, B}`` is named when the best single effect leaves more than
   ``PAIR_TRY_IF_LEFT`` of the null's gap (or none passes), the pair passes, closes at least
   ``PAIR_GAIN_MIN`` of the gap the best single leaves, and **each member adds** more than
   the noise margin to the other alone (``MSE_A - MSE_AB > NOISE_MARGIN p_B MSE_AB / N``,
   and the same for B): a single effect does not gain a second one that fits noise;
3. otherwise the best single is named if it passes, else ``none``.

Ranking: by judged gap; but of two rows whose judged errors the data cannot tell apart
(gaps within ``TIE_GAP`` of each other, and the mean difference of their MSE over
``BLOCKS`` contiguous blocks of the judged samples within ``TIE_T`` standard errors), the
one with fewer parameters goes first.

``top_two``: a named pair's members (the better single first); for a named single ``A``,
``A`` and the effect whose pair with ``A`` is best (of pairs the data cannot tell apart from
the best, the better single); for ``none``, the two best singles.
"""

from __future__ import annotations

from typing import Any

import numpy as np

SHRINK_MIN = 0.05
NOISE_MARGIN = 2.0
PAIR_GAIN_MIN = 0.25
PAIR_TRY_IF_LEFT = 0.10  # a pair is not named for the last tenth of the null's gap
MOSTLY_UNEXPLAINED = 0.5  # the best candidates leave more than this share of the gap
BLOCKS = 20  # contiguous blocks of the judged samples, for the spread of an MSE difference
TIE_T = 2.0  # a difference within TIE_T standard errors cannot tell two rows apart ...
TIE_GAP = 0.1  # ... if their gaps are also within 10 % of each other

RULE_TEXT = (
    f"A candidate passes when it shrinks the held-out gap of the baseline with its spring and "
    f"damper refitted (the null) by at least {100 * SHRINK_MIN:.0f} % and its cut in held-out "
    f"mean squared error exceeds {NOISE_MARGIN:g} x (extra parameters) x (remaining MSE) / "
    f"(samples fitted), the most that fitting noise could explain. A pair is named when it "
    f"passes, the best single effect leaves more than {100 * PAIR_TRY_IF_LEFT:.0f} % of the "
    f"null's gap, the pair closes at least {100 * PAIR_GAIN_MIN:.0f} % of what it leaves, and "
    f"each of its effects adds more than that noise margin to the other alone; "
    f"otherwise the best single effect if it passes; otherwise 'none'."
)


def margin(n_extra: int, mse_after: float, n_fit: int) -> float:
    """The most a cut in MSE from fitting ``n_extra`` weights to noise could be."""
    return NOISE_MARGIN * max(n_extra, 1) * mse_after / max(n_fit, 1)


def mark_passes(rows: list[dict[str, Any]], mse_null: float, n_fit: int) -> None:
    """Set ``beats_noise_margin`` and ``passes`` (rule 1) on every row."""
    for r in rows:
        r["beats_noise_margin"] = bool(
            mse_null - r["_mse"] > margin(r["n_extra_parameters"], r["_mse"], n_fit)
        )
        r["passes"] = bool(r["shrink_vs_null"] >= SHRINK_MIN and r["beats_noise_margin"])


def mark_pairs(
    singles: list[dict[str, Any]], pairs: list[dict[str, Any]], n_fit: int, gap_null: float
) -> None:
    """Rule 2 on every pair row: ``members_add`` and ``passes``."""
    by_name = {r["effect"]: r for r in singles}
    best_gap = singles[0]["gap_after"] if singles else float("inf")
    open_for_pairs = not (singles and singles[0]["passes"]) or (
        best_gap > PAIR_TRY_IF_LEFT * gap_null
    )
    for r in pairs:
        adds = []
        for m in r["members"]:
            alone = by_name[m]
            extra = r["n_extra_parameters"] - alone["n_extra_parameters"]
            adds.append(alone["_mse"] - r["_mse"] > margin(extra, r["_mse"], n_fit))
        r["members_add"] = bool(all(adds))
        closes = r["gap_after"] <= (1.0 - PAIR_GAIN_MIN) * best_gap
        r["passes"] = bool(open_for_pairs and r["passes"] and r["members_add"] and closes)


def indistinguishable(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Whether the judged errors of two rows differ by less than their spread explains.

    Their gaps must be within TIE_GAP of each other, and the mean of their MSE differences
    over BLOCKS contiguous blocks of the judged samples (neighbouring residuals are
    correlated) within TIE_T standard errors.
    """
    lo, hi = sorted((a["gap_after"], b["gap_after"]))
    if hi > (1.0 + TIE_GAP) * lo:
        return False
    d = a["_block_mse"] - b["_block_mse"]
    se = float(np.std(d, ddof=1)) / np.sqrt(d.size)
    return bool(abs(float(np.mean(d))) <= TIE_T * se)


def rank(rows: list[dict[str, Any]], order: list[str]) -> list[dict[str, Any]]:
    """Best first: by judged gap (then fitting error, then the members' single ranks); a row
    with fewer extra parameters whose judged error is indistinguishable from a better row's
    goes before it -- of two explanations the data cannot tell apart, the simpler."""

    def key(r: dict[str, Any]):
        return (r["gap_after"], r["gap_train"], [order.index(m) for m in r["members"]])

    ranked = sorted(rows, key=key)
    for i in range(1, len(ranked)):
        j = i
        while (
            j > 0
            and ranked[j]["n_extra_parameters"] < ranked[j - 1]["n_extra_parameters"]
            and indistinguishable(ranked[j], ranked[j - 1])
        ):
            ranked[j - 1], ranked[j] = ranked[j], ranked[j - 1]
            j -= 1
    return ranked


def runner_up(first: str, with_first: list[dict], singles: list[dict]) -> str:
    """The effect that adds most to ``first``: the partner in its best pair; among pairs the
    data cannot tell apart from that one, the partner that is the better single effect."""
    order = [r["effect"] for r in singles]
    close = [r for r in with_first if r is with_first[0] or indistinguishable(r, with_first[0])]
    partners = [next(m for m in r["members"] if m != first) for r in close]
    return min(partners, key=order.index)


def named_and_top_two(
    singles: list[dict[str, Any]], pairs: list[dict[str, Any]]
) -> tuple[dict[str, Any] | None, list[str]]:
    """(the named row or None, top_two). ``singles`` and ``pairs`` are ranked best first."""
    winners = [r for r in pairs if r["passes"]]
    if winners:
        return winners[0], list(winners[0]["members"])
    if singles and singles[0]["passes"]:
        first = singles[0]["effect"]
        with_first = [r for r in pairs if first in r["members"]]
        if with_first:
            return singles[0], [first, runner_up(first, with_first, singles)]
        return singles[0], [first] + [r["effect"] for r in singles[1:2]]
    return None, [r["effect"] for r in singles[:2]]
