"""No abstention where a candidate explains the records that show the effect.

When nothing passes the rule on all judged records together and the answer would be
``outside_candidates``, the rule is applied once more on the records that *show* a gap of their
own: a record whose own linear fit (spring and damper fitted on that record alone) leaves more
than ``rule.OUTSIDE_NOISE`` x the noise shows behaviour a linear bushing does not have; a
record that does not (a TRAIN too small or too slow to excite the effect) only says how far
the effect's fit on the others extrapolates, which is not the question. A candidate that passes
there is named (``Answer.on_records`` lists those records) -- a single, or a pair when a pair
is what closes those records' gap, by the same rule and partner test as on all records; if
none does, the answer stays ``outside_candidates``.
"""

from __future__ import annotations

import copy

import numpy as np

from bushenv.diagnose import naming, partner, rule
from bushenv.metrics import rms_ratio


def own_linear_gap(force: np.ndarray, x: np.ndarray, dx: np.ndarray) -> float:
    """What a spring and damper fitted on this record alone leave of its force (RMS ratio).
    ``dx`` is the displacement per sample (v dt): the damper's column up to a scale."""
    a = np.stack([x, dx], axis=1)
    w, *_ = np.linalg.lstsq(a, force, rcond=None)
    return rms_ratio(force, a @ w)


def showing_records(ctx: rule.Context) -> list[int]:
    """Indices of the judged records whose own linear fit leaves a gap clear of the noise."""
    out = []
    for i, (a, b) in enumerate(ctx.records or []):
        gap = own_linear_gap(ctx.force[a:b], ctx.x[a:b], ctx.dx[a:b])
        if np.sqrt(max(gap**2 - ctx.gap_noise**2, 0.0)) > rule.OUTSIDE_NOISE * ctx.gap_noise:
            out.append(i)
    return out


def restricted(ctx: rule.Context, keep: list[int]) -> tuple[rule.Context, np.ndarray]:
    """The context on the records ``keep`` only, and the sample index it keeps."""
    idx = np.concatenate([np.arange(*ctx.records[i]) for i in keep])
    starts = np.cumsum([0] + [ctx.records[i][1] - ctx.records[i][0] for i in keep])
    records, edges = [], []
    for i, s in zip(keep, starts[:-1], strict=True):
        a, b = ctx.records[i]
        records.append((int(s), int(s + b - a)))
        edges += [(int(s + e0 - a), int(s + e1 - a)) for e0, e1 in ctx.edges if a <= e0 < b]
    force, null = ctx.force[idx], ctx.null_pred[idx]
    runs = None if ctx.runs is None else [ctx.runs[i] for i in keep]
    sub = rule.Context(
        force, null, edges, rms_ratio(force, null), ctx.gap_noise, ctx.lag,
        ctx.dx[idx], ctx.x[idx], records, runs,
    )  # fmt: skip
    return sub, idx


def _restrict(r: dict, idx: np.ndarray, sub: rule.Context) -> dict:
    c = copy.copy(r)
    c["_pred"] = r["_pred"][idx]
    c["gap_after"] = rms_ratio(sub.force, c["_pred"])
    return c


def answer_on_showing(
    singles: list[dict], pairs: list[dict], ctx: rule.Context, row_of: partner.RowOf
) -> tuple[rule.Answer, list[int]] | None:
    """The answer of the whole rule -- singles, pairs and each partner beside the other's
    richest form (``row_of`` judges those) -- on the records that show a gap, when some
    records do not, and those records' indices (else None: the pooled answer stands). A pair
    is named there when a pair is what closes those records' gap."""
    keep = showing_records(ctx)
    if not keep or len(keep) == len(ctx.records or []):
        return None
    sub, idx = restricted(ctx, keep)
    s_rows = [_restrict(r, idx, sub) for r in singles]
    p_rows = [_restrict(r, idx, sub) for r in pairs]
    rule.mark_failed(s_rows + p_rows, sub)
    s_rows, p_rows = naming.apply_rule(
        s_rows, p_rows, sub, lambda c: _restrict(row_of(c), idx, sub)
    )
    ans = rule.answer(s_rows, p_rows, sub)
    if ans.effect in (rule.OUTSIDE, "none"):
        return None
    full = {frozenset(r["members"]): r for r in singles + pairs}
    row = full[frozenset(ans.row["members"])]
    return rule.Answer(ans.effect, row, ans.top_two, ans.between), keep
