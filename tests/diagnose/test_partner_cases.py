"""The own partner cases are physical specimens: heat never takes more than a third of the
stiffness, whatever heats it (the partner's own dissipation, a warm start, heat carried over)."""

import numpy as np
import pytest

import bushenv.diagnose.validation.partner_cases as pc


def _losses(monkeypatch, seed, index, label):
    """The largest share of stiffness lost to heat in each record of the case's final forces."""
    seen = []
    heat = pc._heat

    def watched(power, v, dt, p, start):
        theta = heat(power, v, dt, p, start)
        seen.append(float(np.max(p["scale"] * theta)))
        return theta

    monkeypatch.setattr(pc, "_heat", watched)
    case = pc.make_partner_case(seed, index, label=label)
    return case, seen[-(len(case.train) + len(case.tests)) :]


# seed 5, cases 0 and 2: a strong Eyring relaxation arm heats the specimen far more than its
# damper alone; before the cap held for the whole session these lost 140 % and 111 %.
@pytest.mark.parametrize("index", [0, 2])
def test_heat_takes_at_most_a_third_of_the_stiffness_beside_a_partner(monkeypatch, index):
    case, losses = _losses(monkeypatch, 5, index, ("relaxation", "thermal"))
    assert case.label == ("relaxation", "thermal")
    assert max(losses) <= pc.MAX_LOSS * (1 + 1e-9)
    assert max(losses) >= 0.5 * pc.MAX_LOSS  # the cap trims, it does not erase the drift


def test_the_cap_leaves_a_case_that_keeps_within_it_alone(monkeypatch):
    case, losses = _losses(monkeypatch, 5, 5, ("relaxation", "thermal"))
    assert max(losses) < 0.9 * pc.MAX_LOSS
    again = pc.make_partner_case(5, 5, label=("relaxation", "thermal"))
    for a, b in zip(case.tests, again.tests, strict=True):  # deterministic given the seed
        assert np.array_equal(a.force, b.force)
