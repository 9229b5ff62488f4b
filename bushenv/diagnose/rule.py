"""The naming rule: which candidate is named, when the answer abstains, and the two effects
ranked first.

Gaps are ``rms_ratio(measured, predicted)`` (seed 000 eq. 8) over all judged samples; the
*null* is the baseline with its spring and damper refitted; ``gap_noise`` the force's
measurement noise as a gap (``evidence.noise_variance``). What a model explains is judged
above the noise: ``excess(g) = sqrt(max(g^2 - gap_noise^2, 0))``.

1. A candidate **failed to fit** when its judged gap exceeds ``FAIL_RATIO`` x the null's (it
   makes the gap much worse: extrapolated beyond what it was fitted on): it is listed apart,
   never ranked or named.
2. A single effect **passes** when its cut in judged squared error against the null is
   significant (``evidence.cut_z`` >= ``Z_NAME``, its spread summed over
   ``evidence.BLOCK_S`` blocks; or a cut of ``CLEAR_CUT`` of the excess gap) and it closes at
   least ``SHRINK_MIN`` of the null's excess gap. A **delay** must also be *seen*
   (``lag.py``: a phase lag linear in frequency at unchanged gain), whatever it fits. An
   effect whose evidence is the energy it dissipates (``Effect.shows_dissipation``: friction)
   is refused when it leaves more than ``DISSIPATION_LEFT_MAX`` of the dissipation the null
   misses and the records hold less than ``DISSIPATION_SHOWN_MIN`` of the dissipation it claims
   (``dissipation_evidence``): a loop the records do not show is a surrogate fitted to
   something else (an amplitude-dependent stiffness, a drift), however much error it cuts.
   An effect that is a law of the deflection and its history (``Effect.holds_its_law``:
   hardening, friction) is refused when that law does not hold through the records: a smooth
   law refitted on each third of every record explains more than ``LAW_DRIFT_MAX`` of its cut
   beyond one law per record (``law_drift``: a zero drifting in time, a stiffness lost for
   good, a stiffness lost to heat, fitted as a backbone or a friction). Any row is refused
   where a stiffness lost for good at the largest deflection, fitted beside it, explains most
   of what it leaves (pooled and on the median run) and a part of the gap that counts
   (``lasting.py``: a Mullins softening is no candidate).
3. A **pair** ``{A, B}`` passes when it passes as a single would, the best single leaves more
   than ``PAIR_TRY_IF_LEFT`` of the null's gap (or none passes), the pair closes at least
   ``PAIR_GAIN_MIN`` of the best single's gap, and **each member passes given the other**:
   the pair's cut against the other member alone is significant in the same sense and
   closes ``PARTNER_MIN`` of that member's excess gap. The other member is taken where it
   fits (``where_it_fits``: the null on a judged record where it alone fails to fit): a
   partner is not credited for taming an extrapolation gone wild. The pair's gain and both
   shares are read pooled over the judged records or on the median run, whichever is larger
   (``Context.share``, ``Context.ratio``; with ``MEDIAN_RUNS`` runs or more, the halves of a
   split record one run): one run whose fit extrapolates far does not outweigh the others.
4. The answer (``effect``): the best passing pair; else the best passing single -- unless the
   next passing single is a different effect the judged errors cannot tell from it (z
   within ``Z_TIE`` and gaps within ``TIE_GAP``), or a row with a delay fits as well or
   better (gap within ``TIE_GAP``) and fails only because its lag is not seen: then
   ``"ambiguous"`` (the same for a pair answer and a pair with a delay); if nothing passes,
   ``"outside_candidates"`` when the null's gap stands clear of the noise (excess above
   ``OUTSIDE_NOISE`` x the noise gap), else ``"none"``; the two effects ranked first are then
   the best pair's when it fits clearly better than the best single (``closest_two``).

Ranking: by judged gap; of two rows the judged errors cannot tell apart (z within ``Z_TIE``,
gaps within ``TIE_GAP``), the one with fewer parameters first.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bushenv.diagnose.evidence import cut_z
from bushenv.diagnose.lag import LagEvidence
from bushenv.metrics import rms_ratio

FAIL_RATIO = 1.25
Z_NAME = 3.0
SHRINK_MIN = 0.10
CLEAR_CUT = 0.25  # a held-out cut of this share of the excess gap is no accident of noise
PAIR_GAIN_MIN = 0.25
PAIR_TRY_IF_LEFT = 0.10
OUTSIDE_NOISE = 2.0
MOSTLY_UNEXPLAINED = 0.5  # the named model leaves more than this share of the excess gap
# Shares (a pair's, the lasting test's) are also read on the median run when this many runs
# are judged (``Context.share``): with two, one badly extrapolated run is half the evidence.
MEDIAN_RUNS = 3
Z_TIE = 2.0
TIE_GAP = 0.05
ADDS_MIN = 0.01  # a pair partner that cuts the first effect's gap by less adds nothing
# A named pair's member closes at least this share of what the other member leaves above the
# noise: a second candidate fits part of the structured residual a first effect of another
# form leaves, significantly but weakly (validator seeds 1-2: such partners closed 25-30 %).
PARTNER_MIN = 1.0 / 3.0
# A dissipative effect is refused when it leaves more than DISSIPATION_LEFT_MAX of the per-block
# dissipation the null misses AND the records hold less than DISSIPATION_SHOWN_MIN of the
# dissipation it claims. Validator seeds 1-2: right answers with friction left 0.00-0.28 and
# showed 0.72-1.17 of their claim; friction named where absent left 0.00-3.9 and showed
# 0.30-2.7 (7 of 17 beyond both thresholds). The second condition keeps a real friction whose
# loop is there while some other dissipation is left unexplained.
DISSIPATION_LEFT_MAX = 0.35
DISSIPATION_SHOWN_MIN = 0.7
# A law of the deflection (``Effect.holds_its_law``: hardening, friction) is refused when a
# smooth law of the deflection refitted on each third of every record explains more than
# LAW_DRIFT_MAX of the cut it claims beyond one law per record (``law_drift``). Validator
# seeds 1-2 (reference, widened, outside): right single hardening answers drifted
# 0.000-0.018, hardening rows of true pairs 0.000-0.005 (their single rows up to 0.5: the
# partner's effect is left in them); hardening named where absent 0.13 and 0.85. The
# threshold leans to keeping a real hardening. Friction is asked the same (eighth revision):
# own friction singles and pairs with friction in the top two all kept; two own answers that
# named friction beside a thermal drift (one with no friction there) now abstain.
LAW_SEGMENTS = 3
LAW_DRIFT_MAX = 0.1

AMBIGUOUS = "ambiguous"
OUTSIDE = "outside_candidates"

RULE_TEXT = (
    f"A candidate whose judged gap exceeds {FAIL_RATIO:g} x the null's (the baseline with its "
    f"spring and damper refitted) failed to fit and is not ranked. A single effect passes when "
    f"its cut in judged squared error against the null is significant (z >= {Z_NAME:g}, the "
    f"spread summed over 1 s blocks, or a cut of {100 * CLEAR_CUT:.0f} % of the gap above the "
    f"noise) and it closes at least "
    f"{100 * SHRINK_MIN:.0f} % of the null's gap above the noise; a delay must also be seen as "
    f"a phase lag linear in frequency at unchanged gain, and friction must show its loop (it "
    f"is refused when it leaves more than {100 * DISSIPATION_LEFT_MAX:.0f} % of the per-block "
    f"dissipation the null misses and the records hold less than "
    f"{100 * DISSIPATION_SHOWN_MIN:.0f} % of the dissipation it claims), and hardening and "
    f"friction must hold their law (refused when a law of the deflection refitted on each "
    f"third of every record explains more than {100 * LAW_DRIFT_MAX:.0f} % of its cut beyond "
    f"one law per record); any candidate is refused where a stiffness lost for good at the "
    f"largest deflection, fitted beside it, cuts significantly and closes at least half of "
    f"what it leaves above the noise (pooled and on the median run) and "
    f"{100 * SHRINK_MIN:.0f} % of the null's. A pair "
    f"passes when it "
    f"passes so, "
    f"closes at least {100 * PAIR_GAIN_MIN:.0f} % of what the best single leaves, and each of "
    f"its effects passes the same test given the other (taken where it fits: the null on a "
    f"record where it alone fails to fit), closing at least "
    f"{100 * PARTNER_MIN:.0f} % of what the other leaves above the noise (the pair's gain "
    f"and these shares pooled over the judged records or on the median run, whichever is "
    f"larger, with {MEDIAN_RUNS} runs or more). Named: the best "
    f"passing pair, else the best passing single ('ambiguous' when the next passing single "
    f"cannot be told from it, or a delay fits as well but its lag is not seen); "
    f"if nothing passes, 'outside_candidates' when the gap stands clear of the noise "
    f"({OUTSIDE_NOISE:g} x), else 'none'."
)


@dataclass
class Context:
    """What every row is judged against."""

    force: np.ndarray  # judged samples, stacked
    null_pred: np.ndarray
    edges: list[tuple[int, int]]
    gap_null: float
    gap_noise: float
    lag: LagEvidence
    dx: np.ndarray | None = None  # displacement increment per judged sample (m)
    x: np.ndarray | None = None  # displacement per judged sample (m)
    records: list[tuple[int, int]] | None = None  # each judged record's samples
    runs: list[int] | None = None  # each judged record's run (the halves of one: one run)

    def excess(self, gap: float) -> float:
        return float(np.sqrt(max(gap * gap - self.gap_noise**2, 0.0)))

    def closes(self, gap_after: float, gap_ref: float) -> float:
        """Share of ``gap_ref``'s excess over the noise that ``gap_after`` closes."""
        ref = self.excess(gap_ref)
        return 1.0 - self.excess(gap_after) / ref if ref > 0 else 0.0

    def run_gaps(self, pred: np.ndarray) -> list[float]:
        """The gap of ``pred`` on each judged run; none with fewer than ``MEDIAN_RUNS``."""
        if not self.records:
            return []
        ids = self.runs if self.runs is not None else list(range(len(self.records)))
        gaps = []
        for run in dict.fromkeys(ids):
            idx = np.concatenate(
                [np.arange(a, b) for (a, b), i in zip(self.records, ids, strict=True) if i == run]
            )
            gaps.append(rms_ratio(self.force[idx], pred[idx]))
        return gaps if len(gaps) >= MEDIAN_RUNS else []

    def share(self, after: dict[str, Any], ref: dict[str, Any], pick=max) -> float:
        """Share of row ``ref``'s excess over the noise that row ``after`` closes: over all
        judged samples or on the median run, whichever ``pick`` takes. One run judged by
        fits that extrapolate far (a programme beyond the fitted ones: a heat grown past
        anything they held) dominates the pooled gap. A partner that closes most of what
        the other leaves on most runs is there all the same (``max``), while one that closes
        a small share on every run stays small on the median run too; a column that mends
        that one run alone refuses nothing (``min``, ``lasting.py``)."""
        pooled = self.closes(after["gap_after"], ref["gap_after"])
        median = self._median_run(after, ref, self.closes)
        return pooled if median is None else float(pick(pooled, median))

    def ratio(self, after: dict[str, Any], ref: dict[str, Any]) -> float:
        """Row ``after``'s gap over row ``ref``'s: pooled, or on the median run, whichever is
        smaller (as ``share``)."""

        def ratio(x: float, y: float) -> float:
            return x / y if y > 0 else 1.0

        pooled = ratio(after["gap_after"], ref["gap_after"])
        median = self._median_run(after, ref, ratio)
        return pooled if median is None else min(pooled, median)

    def _median_run(self, after: dict[str, Any], ref: dict[str, Any], per) -> float | None:
        """``per(gap of after, gap of ref)`` on the median run; None below ``MEDIAN_RUNS``."""
        a, b = self.run_gaps(after["_pred"]), self.run_gaps(ref["_pred"])
        if not a:
            return None
        return float(np.median([per(x, y) for x, y in zip(a, b, strict=True)]))


def _block_work(ctx: Context, pred: np.ndarray) -> np.ndarray:
    """Per block, the work of ``pred - null`` along the motion: the energy a model dissipates
    beyond the null's (J)."""
    w = (pred - ctx.null_pred) * ctx.dx
    return np.array([np.sum(w[a:b]) for a, b in ctx.edges])


def dissipation_evidence(r: dict[str, Any], ctx: Context) -> tuple[float, float]:
    """``(left, shown)`` of row ``r``'s dissipation against the per-block dissipation the null
    misses (measured force minus null, along the motion). ``left``: the share of that pattern
    the row leaves, both above the force noise's share (0 when nothing stands above the noise
    and the row claims nothing either; inf when it claims a dissipation the records do not
    show at all). ``shown``: how much of the dissipation the row claims the measured pattern
    holds (its regression on the claim: 1 all of it, 0 none; the noise averages out)."""
    measured = _block_work(ctx, ctx.force)
    claimed = _block_work(ctx, r["_pred"])
    sigma2 = (ctx.gap_noise * np.sqrt(np.mean(ctx.force**2))) ** 2
    noise = sigma2 * float(np.sum(ctx.dx**2))  # expected sum over blocks of the noise's work^2
    claim = float(np.sum(claimed**2))
    shown = float(np.dot(measured, claimed)) / claim if claim > 0 else 1.0
    missed = float(np.sum(measured**2)) - noise
    left = max(float(np.sum((measured - claimed) ** 2)) - noise, 0.0)
    if missed <= 0.0:
        return (0.0 if claim <= noise else float("inf")), shown
    return left / missed, shown


def record_edges(lengths: list[int]) -> list[tuple[int, int]]:
    """``(start, stop)`` of each record in the stacked judged samples."""
    stops = np.cumsum(lengths)
    return [(int(b - n), int(b)) for n, b in zip(lengths, stops, strict=True)]


def _law_columns(x: np.ndarray) -> np.ndarray:
    """A smooth force law of the deflection: offset, linear, and both odd and even growth."""
    s = x / max(float(np.max(np.abs(x))), 1e-15)
    return np.stack([np.ones_like(s), s, s * np.abs(s), s**3], axis=1)


def _sse(a: np.ndarray, y: np.ndarray) -> float:
    w, *_ = np.linalg.lstsq(a, y, rcond=None)
    return float(np.sum((y - a @ w) ** 2))


def law_drift(r: dict[str, Any], ctx: Context) -> float:
    """How much the force law of the deflection changes through each record, after row
    ``r``: what a smooth law refitted on each ``LAW_SEGMENTS``-th of every record explains of
    the row's residual beyond one law per record, above the noise's expected share, as a
    share of the cut the row claims against the null (0: the law holds; inf: no cut). An
    elastic effect is a law of the deflection alone; a zero drifting in time or a stiffness
    lost for good after the largest deflection is not, whatever it fits."""
    res = ctx.force - r["_pred"]
    gain = 0.0
    for a, b in ctx.records:
        cols, y = _law_columns(ctx.x[a:b]), res[a:b]
        parts = np.array_split(np.arange(b - a), LAW_SEGMENTS)
        gain += _sse(cols, y) - sum(_sse(cols[i], y[i]) for i in parts)
    sigma2 = (ctx.gap_noise * np.sqrt(np.mean(ctx.force**2))) ** 2
    extra = (LAW_SEGMENTS - 1) * 4 * len(ctx.records)  # parameters the segments add
    gain = max(gain - extra * sigma2, 0.0)
    cut = float(np.sum((ctx.force - ctx.null_pred) ** 2) - np.sum(res**2))
    return gain / cut if cut > 0 else float("inf")


def mark_failed(rows: list[dict[str, Any]], ctx: Context) -> None:
    for r in rows:
        r["failed_to_fit"] = bool(r["gap_after"] > FAIL_RATIO * ctx.gap_null)


def _lag_ok(r: dict[str, Any], ctx: Context) -> bool:
    return "delay" not in r["members"] or ctx.lag.seen


def mark_passes(rows: list[dict[str, Any]], ctx: Context) -> None:
    """Rule 2 (``t_vs_null``, ``closes_excess``, ``passes``) on every row."""
    for r in rows:
        r["z_vs_null"] = float(cut_z(ctx.force, ctx.null_pred, r["_pred"], ctx.edges))
        r["closes_excess"] = ctx.closes(r["gap_after"], ctx.gap_null)
        r["significant"] = bool(r["z_vs_null"] >= Z_NAME or r["closes_excess"] >= CLEAR_CUT)
        dissipation_ok = True
        if r.get("_dissipative") and ctx.dx is not None:
            left, shown = dissipation_evidence(r, ctx)
            r["dissipation_left"] = left if np.isfinite(left) else None  # None: none shown
            r["dissipation_shown"] = shown
            dissipation_ok = bool(left <= DISSIPATION_LEFT_MAX or shown >= DISSIPATION_SHOWN_MIN)
        law_ok = True
        if r.get("_holds_law") and ctx.x is not None and ctx.records:
            r["law_drift"] = drift = law_drift(r, ctx)
            law_ok = bool(drift <= LAW_DRIFT_MAX)
        r["_passes_unless_lag"] = bool(
            not r["failed_to_fit"]
            and r["significant"]
            and r["closes_excess"] >= SHRINK_MIN
            and dissipation_ok
            and law_ok
        )
        r["passes"] = bool(r["_passes_unless_lag"] and _lag_ok(r, ctx))


def where_it_fits(r: dict[str, Any], ctx: Context) -> dict[str, Any]:
    """``r`` with the null's prediction on each judged record where ``r`` fails to fit (its
    gap there above ``FAIL_RATIO`` x the null's): what a partner is credited against. A
    partner that only tames an effect's extrapolation to a record it does not fit adds
    nothing to that effect."""
    pred, out = r["_pred"], None
    for a, b in ctx.records or []:
        f = ctx.force[a:b]
        if rms_ratio(f, pred[a:b]) > FAIL_RATIO * rms_ratio(f, ctx.null_pred[a:b]):
            out = pred.copy() if out is None else out
            out[a:b] = ctx.null_pred[a:b]
    if out is None:
        return r
    return {**r, "_pred": out, "gap_after": rms_ratio(ctx.force, out)}


def mark_pairs(singles: list[dict], pairs: list[dict], ctx: Context) -> None:
    """Rule 3 on every pair row: ``members_add`` and ``passes``."""
    by_name = {r["effect"]: r for r in singles}
    ok = [r for r in singles if not r["failed_to_fit"]]
    best = ok[0] if ok else {"gap_after": ctx.gap_null, "_pred": ctx.null_pred}
    open_for_pairs = (
        not (ok and ok[0]["passes"]) or best["gap_after"] > PAIR_TRY_IF_LEFT * ctx.gap_null
    )
    for r in pairs:
        adds = []
        for m in r["members"]:
            other = where_it_fits(by_name[next(o for o in r["members"] if o != m)], ctx)
            t = cut_z(ctx.force, other["_pred"], r["_pred"], ctx.edges)
            share = ctx.share(r, other)
            adds.append((t >= Z_NAME or share >= CLEAR_CUT) and share >= PARTNER_MIN)
        r["members_add"] = bool(all(adds))
        closes = ctx.ratio(r, best) <= 1.0 - PAIR_GAIN_MIN
        pair_ok = open_for_pairs and r["members_add"] and closes
        r["_passes_unless_lag"] = bool(pair_ok and r["_passes_unless_lag"])
        r["passes"] = bool(pair_ok and r["passes"])


def indistinguishable(a: dict[str, Any], b: dict[str, Any], ctx: Context) -> bool:
    """Whether two rows' judged errors differ by less than their spread explains."""
    lo, hi = sorted((a["gap_after"], b["gap_after"]))
    if hi > (1.0 + TIE_GAP) * lo:
        return False
    worse, better = (a, b) if a["gap_after"] >= b["gap_after"] else (b, a)
    return cut_z(ctx.force, worse["_pred"], better["_pred"], ctx.edges) < Z_TIE


def rank(rows: list[dict[str, Any]], order: list[str], ctx: Context) -> list[dict[str, Any]]:
    """Best first: by judged gap (then fitting error, then the members' single ranks); a row
    with fewer extra parameters that the blocks cannot tell from a better one goes first.
    Rows that failed to fit go last."""

    def key(r: dict[str, Any]):
        return (r["failed_to_fit"], r["gap_after"], r["gap_train"],
                [order.index(m) for m in r["members"]])  # fmt: skip

    ranked = sorted(rows, key=key)
    for i in range(1, len(ranked)):
        j = i
        while (
            j > 0
            and not ranked[j]["failed_to_fit"]
            and ranked[j]["n_extra_parameters"] < ranked[j - 1]["n_extra_parameters"]
            and indistinguishable(ranked[j], ranked[j - 1], ctx)
        ):
            ranked[j - 1], ranked[j] = ranked[j], ranked[j - 1]
            j -= 1
    return ranked


def runner_up(first: str, with_first: list[dict], singles: list[dict], ctx: Context) -> str:
    """The effect that adds most to ``first``: the partner in its best pair (``with_first``:
    pairs that improve on ``first``, best first); among pairs the data cannot tell apart from
    that one, the partner that is the better single effect (``singles`` ranked, those that
    failed to fit alone last)."""
    order = [r["effect"] for r in singles]
    close = [
        r for r in with_first if r is with_first[0] or indistinguishable(r, with_first[0], ctx)
    ]
    partners = [next(m for m in r["members"] if m != first) for r in close]
    return min(partners, key=order.index)


def _unseen_delay_rival(rows: list[dict], chosen: dict, ctx: Context) -> dict | None:
    """A row with a delay that would pass but for its lag not being seen, and that fits as
    well as ``chosen`` or better: the records cannot say whether ``chosen`` or the delay
    explains the gap (a short delay shows almost no phase at these frequencies, yet a
    relaxation or an inertia fitted in its place names an effect that may not be there)."""
    if ctx.lag.seen or "delay" in chosen["members"]:
        return None
    for r in rows:
        if "delay" in r["members"] and r.get("_passes_unless_lag"):
            if r["gap_after"] <= (1.0 + TIE_GAP) * chosen["gap_after"]:
                return r
    return None


@dataclass
class Answer:
    """``effect``: a candidate's name, ``"none"``, ``AMBIGUOUS`` or ``OUTSIDE``; ``row`` the
    model whose predictions are reported (None: the baseline's); ``between`` the two
    candidates an ambiguous answer cannot tell apart."""

    effect: str
    row: dict[str, Any] | None
    top_two: list[str]
    between: list[str]


def answer(singles: list[dict], pairs: list[dict], ctx: Context) -> Answer:
    """The answer from ranked ``singles`` and ``pairs`` (rules 4)."""
    ok = [r for r in singles if not r["failed_to_fit"]]
    winners = [r for r in pairs if r["passes"]]
    if winners:
        best = winners[0]
        rival = _unseen_delay_rival(pairs, best, ctx)
        if rival is not None:  # the effects the two pairs do not share
            between = [m for m in best["members"] if m not in rival["members"]]
            between += [m for m in rival["members"] if m not in best["members"]]
            return Answer(AMBIGUOUS, best, list(best["members"]), between)
        return Answer(best["effect"], best, list(best["members"]), [])
    passing = [r for r in ok if r["passes"]]
    if passing:
        first = passing[0]
        name = first["effect"]
        # pairs with the first that add to it (a partner that adds nothing is no runner-up;
        # one that fails to fit alone may still add beside the first)
        with_first = [
            r
            for r in pairs
            if name in r["members"]
            and not r["failed_to_fit"]
            and r["gap_after"] < (1.0 - ADDS_MIN) * first["gap_after"]
        ]
        others = [r["effect"] for r in ok if r["effect"] != name]
        top_two = (
            [name, runner_up(name, with_first, singles, ctx)] if with_first else [name] + others[:1]
        )
        if len(passing) > 1 and indistinguishable(first, passing[1], ctx):
            between = [name, passing[1]["effect"]]
            return Answer(AMBIGUOUS, first, between, between)
        rival = _unseen_delay_rival(ok, first, ctx)
        if rival is not None:
            between = [name, rival["effect"]]
            return Answer(AMBIGUOUS, first, between, between)
        return Answer(name, first, top_two, [])
    closest = closest_two(ok, pairs, ctx)
    if ctx.excess(ctx.gap_null) > OUTSIDE_NOISE * ctx.gap_noise:
        return Answer(OUTSIDE, None, closest, [])
    return Answer("none", None, closest, [])


def closest_two(singles: list[dict], pairs: list[dict], ctx: Context) -> list[str]:
    """When nothing passes, the two candidates that come closest: the best pair's members when
    that pair fits better than the best single by more than the judged errors' spread (two
    effects at once, none of which explains the gap alone), else the two best singles (ranked,
    those that failed to fit left out)."""
    names = [r["effect"] for r in singles]
    fitted = [r for r in pairs if not r["failed_to_fit"]]
    if not singles or not fitted:
        return names[:2]
    best, single = fitted[0], singles[0]
    if best["gap_after"] < single["gap_after"] and not indistinguishable(best, single, ctx):
        order = names + [m for m in best["members"] if m not in names]
        return sorted(best["members"], key=order.index)
    return names[:2]


def unexplained(ans: Answer, rows: list[dict], gap_before: float, ctx: Context) -> dict:
    """The share of the gap the answer leaves, what the best candidate leaves, both above the
    measurement noise; "mostly outside the candidates" only when that is so."""
    ok = [r for r in rows if not r["failed_to_fit"]]
    best = min(ok, key=lambda r: r["gap_after"]) if ok else None
    named = ans.row
    share = named["gap_after"] / gap_before if named and gap_before > 0 else 1.0
    best_share = best["gap_after"] / gap_before if best and gap_before > 0 else 1.0
    best_share = min(best_share, 1.0)
    left = 1.0 - ctx.closes(named["gap_after"], ctx.gap_null) if named else 1.0
    best_left = 1.0 - ctx.closes(best["gap_after"], ctx.gap_null) if best else 1.0
    noise = f"the force's measurement noise alone is a {100 * ctx.gap_noise:.2g} % gap"
    text = []
    if ans.effect == "none":
        text.append(f"No candidate passes the rule and the gap is close to the noise ({noise}).")
    elif ans.effect == OUTSIDE:
        text.append(
            "The cause lies outside the candidates: no candidate passes the rule, and the gap "
            f"stands clear of the noise ({noise})"
            + (
                f"; the best, {best['effect']}, would leave {100 * best_share:.0f} %."
                if best
                else "."
            )
        )
    else:
        text.append(
            f"{named['effect']} leaves {100 * share:.0f} % of the gap unexplained "
            f"({100 * left:.0f} % of what stands above the noise; {noise})."
        )
    mostly = ans.effect == OUTSIDE or (named is not None and left > MOSTLY_UNEXPLAINED)
    if mostly and ans.effect != OUTSIDE:
        text.append(
            f"The gap lies mostly outside the candidate set: the named model leaves "
            f"{100 * left:.0f} % of what stands above the noise."
        )
    return {
        "unexplained_share": float(share),
        "unexplained_share_above_noise": float(left),
        "best_candidate": best["effect"] if best else "none",
        "best_unexplained_share": float(best_share),
        "best_unexplained_share_above_noise": float(best_left),
        "gap_noise": ctx.gap_noise,
        "mostly_outside_candidates": bool(mostly),
        "text": text,
    }
