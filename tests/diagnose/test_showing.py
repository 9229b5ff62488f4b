"""A candidate that explains the records showing the effect is named, not abstained on."""

import numpy as np

from bushenv.diagnose import rule, showing
from bushenv.diagnose.evidence import block_edges
from bushenv.metrics import rms_ratio

DT, N, K = 0.01, 3000, 1e5


def _case(train_shows: bool):
    """TRAIN and TEST of one bushing; the TEST stiffens (a cubic, 20 % of its force), TRAIN
    does too only if ``train_shows``. The candidate, fitted on the TEST, is right there and
    extrapolates badly to TRAIN (60 % too stiff): judged on both it fails to fit."""
    rng = np.random.default_rng(3)
    t = np.arange(N) * DT
    x_tr = 2e-3 * np.sin(2 * np.pi * 0.7 * t)
    x_te = 3e-3 * np.sin(2 * np.pi * 0.45 * t) * np.sin(2 * np.pi * 0.05 * t + 0.3)
    cubic_te = 0.2 * K * x_te**3 / np.max(np.abs(x_te)) ** 2
    cubic_tr = 0.2 * K * x_tr**3 / np.max(np.abs(x_tr)) ** 2 if train_shows else 0 * x_tr
    noise = 0.002 * K * 2e-3
    f_tr = K * x_tr + cubic_tr + noise * rng.normal(size=N)
    f_te = K * x_te + cubic_te + noise * rng.normal(size=N)
    force, x = np.concatenate([f_tr, f_te]), np.concatenate([x_tr, x_te])
    null = K * x
    ctx = rule.Context(
        force, null, block_edges([N, N], [DT, DT]), rms_ratio(force, null),
        0.002 * 2e-3 / np.sqrt(np.mean(x**2)), None, np.gradient(x), x, rule.record_edges([N, N]),
    )  # fmt: skip
    cand = {
        "effect": "hardening", "members": ["hardening"], "n_extra_parameters": 6,
        "gap_train": 0.0, "_pred": np.concatenate([1.6 * K * x_tr, K * x_te + cubic_te]),
    }  # fmt: skip
    cand["gap_after"] = rms_ratio(force, cand["_pred"])
    return ctx, cand


def test_a_candidate_right_on_the_records_showing_the_gap_is_named_there():
    ctx, cand = _case(train_shows=False)
    rule.mark_failed([cand], ctx)
    rule.mark_passes([cand], ctx)
    assert not cand["passes"]  # pooled, TRAIN's bad extrapolation sinks it
    assert rule.answer([cand], [], ctx).effect == rule.OUTSIDE
    assert showing.showing_records(ctx) == [1]  # TRAIN's own linear fit leaves only noise
    ans, keep = showing.answer_on_showing([cand], ctx)
    assert ans.effect == "hardening" and keep == [1]


def test_when_every_record_shows_the_gap_the_pooled_answer_stands():
    ctx, cand = _case(train_shows=True)
    rule.mark_failed([cand], ctx)
    rule.mark_passes([cand], ctx)
    assert showing.showing_records(ctx) == [0, 1]
    assert showing.answer_on_showing([cand], ctx) is None
