"""No abstention where a candidate explains the records that show the effect.

When nothing passes the rule on all judged records together and the answer would be
``outside_candidates``, the rule is applied once more on the records that *show* a gap of their
own: a record whose own linear fit (spring and damper fitted on that record alone) leaves more
than ``rule.OUTSIDE_NOISE`` x the noise shows behaviour a linear bushing does not have; a
record that does not (a TRAIN too small or too slow to excite the effect) only says how far
the effect's fit on the others extrapolates, which is not the question. A candidate that passes
there is named (``Answer.on_records`` lists those records); if none does, the answer stays
``outside_candidates``.
"""

from __future__ import annotations

import copy

import numpy as np

from bushenv.diagnose import rule
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
    sub = rule.Context(
        force, null, edges, rms_ratio(force, null), ctx.gap_noise, ctx.lag,
        ctx.dx[idx], ctx.x[idx], records,
    )  # fmt: skip
    return sub, idx


def answer_on_showing(
    singles: list[dict], ctx: rule.Context
) -> tuple[rule.Answer, list[int]] | None:
    """The best single that passes the rule on the records that show a gap, when some records
    do not, and those records' indices (else None: the pooled answer stands)."""
    keep = showing_records(ctx)
    if not keep or len(keep) == len(ctx.records or []):
        return None
    sub, idx = restricted(ctx, keep)
    rows = []
    for r in singles:
        c = copy.copy(r)
        c["_pred"] = r["_pred"][idx]
        c["gap_after"] = rms_ratio(sub.force, c["_pred"])
        rows.append(c)
    rule.mark_failed(rows, sub)
    rule.mark_passes(rows, sub)
    passing = sorted((c for c in rows if c["passes"]), key=lambda c: c["gap_after"])
    if not passing:
        return None
    best = next(r for r in singles if r["effect"] == passing[0]["effect"])
    if len(passing) > 1 and rule.indistinguishable(passing[0], passing[1], sub):
        between = [passing[0]["effect"], passing[1]["effect"]]
        return rule.Answer(rule.AMBIGUOUS, best, between, between), keep
    name = best["effect"]
    others = [c["effect"] for c in passing[1:]] or [
        c["effect"] for c in rows if c["effect"] != name
    ]
    return rule.Answer(name, best, [name] + others[:1], []), keep
