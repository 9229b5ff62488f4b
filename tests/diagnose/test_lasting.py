"""No candidate is a stiffness lost for good (``lasting.py``): a row is refused where such a
stiffness, fitted beside it, explains most of what it leaves; a softening that recovers keeps
its name."""

import numpy as np

from bushenv.diagnose import lasting, rule
from bushenv.diagnose.candidates import effect_names, get_effect
from bushenv.diagnose.effects.base import LOST_SATURATION, Scales, Signals
from bushenv.diagnose.fit import diagnose
from bushenv.diagnose.rule import OUTSIDE
from bushenv.diagnose.validation.outside_cases import make_outside_case
from bushenv.diagnose.validation.partner_cases import make_partner_case
from bushenv.diagnose.validation.widened_cases import make_widened_case

from .synthetic import K, Rec, force, motion


def _row(result, effect):
    return next(r for r in result["ranking"] if r["effect"] == effect)


def test_every_effect_is_compared_with_a_stiffness_lost_at_the_largest_deflection():
    x = 1e-3 * np.sin(np.linspace(0, 20, 400)) * np.linspace(1.0, 0.2, 400)  # falls after 1 mm
    s = Signals(x, 0.01)
    scales = Scales.of([s])
    peak = np.maximum.accumulate(np.abs(x))
    assert peak[-1] == np.max(np.abs(x)) > 3 * np.max(np.abs(x[-40:]))  # it never recovers
    for name in effect_names():
        eff = get_effect(name)
        shape = eff.shapes(scales)[0]
        usual, with_lost = eff.columns(s, shape, scales), eff.lasting_columns(s, shape, scales)
        lost = with_lost[:, usual.shape[1] :]
        assert lost.shape == (x.size, len(LOST_SATURATION)), name
        assert np.array_equal(with_lost[:, : usual.shape[1]], usual), name
        moving = np.abs(x) > 1e-6
        loss = lost[moving] / -x[moving, None]  # the stiffness lost (per weight)
        assert np.all(np.diff(loss, axis=0) >= -1e-12), name  # it never recovers
        assert np.all(loss[-1] > 0), name


def test_a_stiffness_lost_for_good_that_the_payne_memory_fits_is_not_named_friction(monkeypatch):
    case = make_outside_case(0, 9)  # a Mullins softening: memory of the largest deflection
    assert case.drawn["form"] == "mullins"
    result = diagnose(case.train, case.tests)
    row = _row(result, "friction")
    assert row["lasting_softening"]["refuses"] and not row["passes"]
    assert row["lasting_softening"]["share"] > 0.75  # the lost stiffness explains what is left
    assert result["effect"] == OUTSIDE
    monkeypatch.setattr(lasting, "LASTS_MIN", np.inf)  # the check off
    without = diagnose(case.train, case.tests)
    assert without["effect"] == "friction"  # what the Payne memory alone would have named


def test_a_payne_softening_that_recovers_is_still_named_friction():
    case = make_widened_case(11, 40)
    assert case.drawn["forms"] == {"friction": "payne"}  # recovers within 0.5-8 s
    result = diagnose(case.train, case.tests)
    row = _row(result, "friction")
    assert result["effect"] == "friction" and row["passes"]
    assert not row["lasting_softening"]["refuses"]
    assert row["lasting_softening"]["share"] < lasting.LASTS_MIN


def _blocks_record(seed, levels, loss_share):
    """Random motion in blocks of ``levels`` x 4 mm on a spring and damper that loses, for
    good, ``loss_share`` of its stiffness as tanh of the largest deflection so far / 2 mm."""
    dt = 1 / 204.8
    x = motion(seed, 30.0, dt, steps=False)
    t = np.arange(x.size) * dt
    x = x / (0.65 + 0.35 * np.sin(2 * np.pi * t / 15.0))  # motion()'s own modulation undone
    x = 4e-3 * np.repeat(levels, x.size // len(levels) + 1)[: x.size] * x / np.max(np.abs(x))
    lost = loss_share * K * np.tanh(np.maximum.accumulate(np.abs(x)) / 2e-3) * x
    f = force(x, dt) - lost
    f = f + 0.005 * np.std(f) * np.random.default_rng(seed + 7).normal(size=x.size)
    return Rec(t, x, f, dt, f"blocks{seed}")


def test_a_stiffness_lost_for_good_in_another_form_is_no_thermal_drift(monkeypatch):
    levels = ([1.0, 0.4, 0.4], [1.0, 0.2], [0.8, 0.3, 0.3])  # each record falls after its peak
    recs = [_blocks_record(41 + i, lv, 0.4) for i, lv in enumerate(levels)]
    result = diagnose(recs[0], recs[1:])
    row = _row(result, "thermal")
    assert row["lasting_softening"]["refuses"] and not row["passes"]
    assert result["effect"] == OUTSIDE
    monkeypatch.setattr(lasting, "LASTS_MIN", np.inf)  # the check off
    assert diagnose(recs[0], recs[1:])["effect"] == "thermal"  # a heat that never cools


def _session_order(case):
    """The partner case's records in the order its session ran them, the rests between."""
    names = [r.name for r in case.train + case.tests]
    order, rests = case.drawn["order"], case.drawn["rests_s"]
    return [(names[i], None if j == 0 else rests[j - 1]) for j, i in enumerate(order)]


def test_a_column_that_mends_the_one_run_a_pair_extrapolates_to_refuses_nothing(monkeypatch):
    """Own thermal + relaxation case (seed 5, case 11) with its run order: the heating law
    fitted on the other runs extrapolates to the fast sweep, and a stiffness lost for good
    fitted beside the pair mends that run -- pooled it closes most of what the pair leaves,
    on the median run it does not. The pair is named; pooled alone it was refused."""
    case = make_partner_case(5, 11, label=("relaxation", "thermal"))
    order = _session_order(case)
    got = diagnose(case.train, case.tests, run_order=order)
    assert got["effect"] == "relaxation+thermal", got["effect"]
    pair = next(r for r in got["pairs"] if r["effect"] == "relaxation+thermal")
    assert not pair["lasting_softening"]["refuses"]
    monkeypatch.setattr(rule, "MEDIAN_RUNS", 99)  # pooled only
    pooled = diagnose(case.train, case.tests, run_order=order)
    pair = next(r for r in pooled["pairs"] if r["effect"] == "relaxation+thermal")
    assert pair["lasting_softening"]["refuses"] and pair["lasting_softening"]["share"] > 0.5
    assert pooled["effect"] == "relaxation"
