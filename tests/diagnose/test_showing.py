"""A candidate that explains the records showing the effect is named, not abstained on."""

import numpy as np

from bushenv.diagnose import rule, showing
from bushenv.diagnose.effects.rich import LastingForm
from bushenv.diagnose.evidence import block_edges
from bushenv.diagnose.lag import LagEvidence
from bushenv.metrics import rms_ratio

DT, N, K = 0.01, 3000, 1e5
NO_LAG = LagEvidence(False, False, 0.0, 0.0, 1.0, [], "no lag")


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
        0.002 * 2e-3 / np.sqrt(np.mean(x**2)), NO_LAG, np.gradient(x), x, rule.record_edges([N, N]),
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
    ans, keep = showing.answer_on_showing([cand], [], ctx, _no_rich_form(cand))
    assert ans.effect == "hardening" and keep == [1]


def test_when_every_record_shows_the_gap_the_pooled_answer_stands():
    ctx, cand = _case(train_shows=True)
    rule.mark_failed([cand], ctx)
    rule.mark_passes([cand], ctx)
    assert showing.showing_records(ctx) == [0, 1]
    assert showing.answer_on_showing([cand], [], ctx, _no_rich_form(cand)) is None


def _no_rich_form(cand):
    """A row_of that gives ``cand`` back beside a stiffness lost for good (nothing is lost
    here) and refuses any richest form (no pair here)."""

    def row_of(combo):
        if any(isinstance(m, LastingForm) for m in combo.members):
            return cand
        raise AssertionError(f"no pair here, so no richest form of {combo.name} is asked for")

    return row_of


def _row(name, pred, force):
    return {
        "effect": name, "members": name.split("+"), "n_extra_parameters": 1,
        "gap_train": 0.0, "_pred": pred, "gap_after": rms_ratio(force, pred),
    }  # fmt: skip


def test_a_pair_that_closes_the_showing_records_gap_is_named_there():
    """The TEST stiffens and carries a mass; TRAIN shows neither. Each candidate, fitted on
    the TEST, extrapolates badly to TRAIN, so nothing passes pooled; on the TEST the pair is
    what closes the gap, and each member adds beside the other's (here: usual) form."""
    rng = np.random.default_rng(5)
    t = np.arange(N) * DT
    x_tr = 2e-3 * np.sin(2 * np.pi * 0.7 * t)
    x_te = 2e-3 * np.sin(2 * np.pi * 0.45 * t) + 1e-3 * np.sin(2 * np.pi * 3.0 * t)
    cubic = 0.2 * K * x_te**3 / np.max(np.abs(x_te)) ** 2
    mass = 100.0 * np.gradient(np.gradient(x_te, DT), DT)
    noise = 0.002 * K * 2e-3
    f_tr = K * x_tr + noise * rng.normal(size=N)
    f_te = K * x_te + cubic + mass + noise * rng.normal(size=N)
    force, x = np.concatenate([f_tr, f_te]), np.concatenate([x_tr, x_te])
    null = K * x
    ctx = rule.Context(
        force, null, block_edges([N, N], [DT, DT]), rms_ratio(force, null),
        noise / np.sqrt(np.mean(force**2)), NO_LAG, np.gradient(x), x, rule.record_edges([N, N]),
    )  # fmt: skip
    bad_tr = 1.6 * K * x_tr
    singles = [
        _row("hardening", np.concatenate([bad_tr, K * x_te + cubic]), force),
        _row("inertia", np.concatenate([bad_tr, K * x_te + mass]), force),
    ]
    pairs = [_row("hardening+inertia", np.concatenate([bad_tr, K * x_te + cubic + mass]), force)]
    by_names = {frozenset(r["members"]): r for r in singles + pairs}
    rule.mark_failed(singles + pairs, ctx)
    rule.mark_passes(singles + pairs, ctx)
    assert not any(r["passes"] for r in singles + pairs)
    ans, keep = showing.answer_on_showing(
        singles, pairs, ctx, lambda combo: by_names[frozenset(combo.names)]
    )
    assert keep == [1]
    assert set(ans.effect.split("+")) == {"hardening", "inertia"}
    assert ans.row is pairs[0]
