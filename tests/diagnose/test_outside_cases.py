"""The outside set: cases whose gap no candidate models."""

import numpy as np
import pytest

from bushenv.diagnose.candidates import effect_names
from bushenv.diagnose.rule import OUTSIDE
from bushenv.diagnose.validation.outside_cases import FORMS, _play, make_outside_case, outside_force
from bushenv.diagnose.validation.validate import SETS, judge_case


def test_the_play_operator_moves_only_beyond_its_clearance():
    x = np.array([0.0, 0.5, 1.0, 2.0, 1.5, 1.0, 0.0, -1.0])
    y = _play(x, 0.5)
    assert list(y) == [0.0, 0.0, 0.5, 1.5, 1.5, 1.5, 0.5, -0.5]


@pytest.mark.parametrize("index", range(len(FORMS)))
def test_each_form_is_drawn_deterministically_and_shows(index):
    a, b = make_outside_case(5, index), make_outside_case(5, index)
    assert a.label == (OUTSIDE,) and a.drawn["form"] == FORMS[index]
    assert not set(a.label) & set(effect_names())
    for ra, rb in zip(a.train + a.tests, b.train + b.tests, strict=True):
        assert np.array_equal(ra.force, rb.force)
    assert a.drawn["visible"] > 0.01  # the effect leaves a gap a linear fit cannot close


def test_the_forms_add_nothing_at_zero_strength():
    dt = 1e-3
    x = 1e-3 * np.sin(2 * np.pi * 3 * np.arange(2000) * dt)
    p = {"scale": 0.0, "x_peak": 1e-3, "sign": 1.0, "period_s": 10.0, "phase": 0.3,
         "mains_hz": 50.0}  # fmt: skip
    base = 1e5 * x + 1e3 * np.gradient(x, dt)
    for form in FORMS:
        assert np.allclose(outside_force(form, p, 1e5, 1e3, x, dt), base)


def test_an_outside_case_is_right_only_when_answered_outside_and_any_effect_named_is_absent():
    case = make_outside_case(0, 1)
    assert SETS["outside"] is make_outside_case
    res = {"effect": OUTSIDE, "top_two": ["friction", "thermal"], "gap_before": 0.1,
           "gap_after": 0.1, "mode": "cross", "predictions": []}  # fmt: skip
    res["predictions"] = [{"force_measured": np.ones(3), "force_baseline": np.zeros(3),
                           "force_augmented": np.zeros(3)}]  # fmt: skip
    row = judge_case(case, res)
    assert row["right"] and not row["absent_named"]
    row = judge_case(case, dict(res, effect="friction"))
    assert not row["right"] and row["absent_named"] == ["friction"]
