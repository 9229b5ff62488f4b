"""A law of the deflection (a backbone, a friction) is named only when it holds through each
record (``rule.law_drift``): a load-cell zero drifting in time, a stiffness lost for good at
the largest deflection or a stiffness lost to heat is not a hardening nor a friction however
much error their fit cuts."""

import numpy as np

from bushenv.diagnose import rule
from bushenv.diagnose.candidates import effect_names, get_effect
from bushenv.diagnose.lag import lag_evidence
from bushenv.metrics import rms_ratio

DT = 0.005
T = np.arange(0, 60, DT)


def _motion(rng):
    """Band-limited random motion of 1 mm RMS around a mean that wanders slowly."""
    x = np.convolve(rng.normal(size=T.size), np.ones(20) / 20, mode="same")
    x *= 1e-3 / np.std(x)
    return x + 0.8e-3 * np.sin(2 * np.pi * T / 40.0)


def _law_fit(x, y):
    """The least-squares odd-and-even law of ``x`` (a hardening row's own kind of fit)."""
    s = x / np.max(np.abs(x))
    a = np.stack([s, s * np.abs(s), s**3], axis=1)
    w, *_ = np.linalg.lstsq(a, y, rcond=None)
    return a @ w


def _row(ctx, pred, effect="hardening"):
    r = {"effect": effect, "members": [effect], "_pred": pred, "_holds_law": True}
    r.update(n_extra_parameters=6, gap_after=rms_ratio(ctx.force, pred), gap_train=0.0)
    rule.mark_failed([r], ctx)
    rule.mark_passes([r], ctx)
    return r


def _ctx(x, y, noise_n=0.0, rng=None):
    if noise_n:
        y = y + noise_n * rng.normal(size=y.size)
    half = x.size // 2
    records = [(0, half), (half, x.size)]
    edges = [(i, min(i + 200, x.size)) for i in range(0, x.size, 200)]
    gap_noise = noise_n / float(np.sqrt(np.mean(y**2))) if noise_n else 0.0
    null = x * float(np.dot(x, y) / np.dot(x, x))  # the spring refitted
    ctx = rule.Context(y, null, edges, rms_ratio(y, null), gap_noise, lag_evidence([]), None,
                       x, records)  # fmt: skip
    return ctx


def test_a_hardening_law_that_holds_through_the_records_passes_under_noise():
    rng = np.random.default_rng(0)
    x = _motion(rng)
    y = 4e9 * x**3  # N: the cubic term of a stiffening backbone
    ctx = _ctx(x, y, noise_n=0.05 * float(np.std(y)), rng=rng)
    r = _row(ctx, _law_fit(x, ctx.force))
    assert r["law_drift"] < 0.01
    assert r["passes"]


def test_a_zero_drifting_in_time_is_refused_as_hardening_though_the_fit_cuts_the_error():
    rng = np.random.default_rng(1)
    levels = np.repeat(np.linspace(0.2e-3, 3e-3, 12), T.size // 12 + 1)[: T.size]
    x = 0.2 * _motion(rng) + levels  # held steps rising through the test, as the zero drifts
    y = 300.0 * ((T / T[-1]) ** 2 + 0.2 * np.sin(2 * np.pi * T / 17.0))  # N: the cell's zero
    ctx = _ctx(x, y)
    r = _row(ctx, _law_fit(x, y))
    assert r["closes_excess"] > rule.SHRINK_MIN and r["significant"]  # it does cut the error
    assert r["law_drift"] > 3 * rule.LAW_DRIFT_MAX
    assert not r["passes"]


def test_a_stiffness_lost_for_good_at_the_largest_deflection_is_refused_as_hardening():
    rng = np.random.default_rng(2)
    x = _motion(rng) * (0.2 + 0.8 * T / T[-1])  # the amplitude grows through the record
    reached = np.maximum.accumulate(np.abs(x)) / np.max(np.abs(x))
    y = -6e5 * reached * x  # N: Mullins softening, memory of the largest deflection
    ctx = _ctx(x, y)
    r = _row(ctx, _law_fit(x, y))
    assert r["closes_excess"] > rule.SHRINK_MIN
    assert r["law_drift"] > rule.LAW_DRIFT_MAX
    assert not r["passes"]
    r.pop("_holds_law")  # an effect that is no law of the deflection is not asked
    rule.mark_passes([r], ctx)
    assert r["passes"]


def _friction_fit(x, y):
    """The least-squares friction (a smooth sign of the velocity) and spring: one law of the
    deflection's history for the whole record."""
    v = np.gradient(x, DT)
    a = np.stack([np.tanh(v / (0.05 * np.std(v))), x], axis=1)
    w, *_ = np.linalg.lstsq(a, y, rcond=None)
    return a @ w


def test_a_friction_whose_loop_holds_passes_and_one_that_softens_with_heat_is_refused():
    assert {n for n in effect_names() if get_effect(n).holds_its_law} == {"hardening", "friction"}
    rng = np.random.default_rng(3)
    x = _motion(rng)
    v = np.gradient(x, DT)
    loop = 40.0 * np.tanh(v / (0.05 * np.std(v)))  # N: a friction force
    ctx = _ctx(x, loop, noise_n=0.05 * float(np.std(loop)), rng=rng)
    r = _row(ctx, _friction_fit(x, ctx.force), "friction")
    assert r["law_drift"] < rule.LAW_DRIFT_MAX and r["passes"]
    heat = np.cumsum(v * v) * DT / (np.sum(v * v) * DT)  # dissipated energy, 0 to 1
    y = loop - 1.5e5 * heat * x  # N: the same loop on a spring that softens as it heats
    ctx = _ctx(x, y)
    r = _row(ctx, _friction_fit(x, y), "friction")
    assert r["closes_excess"] > rule.SHRINK_MIN and r["significant"]  # it does cut the error
    assert r["law_drift"] > rule.LAW_DRIFT_MAX
    assert not r["passes"]


def test_record_edges_cover_the_stacked_samples_in_order():
    assert rule.record_edges([3, 5, 2]) == [(0, 3), (3, 8), (8, 10)]
