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
# damper alone; when the cap held for the damper's heat alone these lost 140 % and 111 %.
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


@pytest.mark.parametrize(
    "name,p",
    [
        ("relaxation", {"scale": 1.0, "k_a": 1e5, "tau_s": 0.2, "s0": 2e-3}),
        ("friction", {"scale": 1.0, "f_y": 60.0, "x_y": 1.5e-4}),
        ("hardening", {"scale": 1.0, "k": 2e5, "x_l_pos": 6e-3, "x_l_neg": 5e-3}),
    ],
)
def test_a_partner_heats_by_the_work_its_loop_dissipates(name, p):
    """Over whole cycles the heat a partner feeds equals its loop's work (a spring's: none)."""
    dt = 1e-4
    t = np.arange(0.0, 10.0, dt)
    x = 3e-3 * np.sin(2 * np.pi * t)
    f = pc.effect_force(name, p, x, dt)
    power = pc.dissipated_power(name, p, f, x, dt)
    cycles = (t >= 5.0) & (t < 9.0)
    work = float(np.sum(f[cycles] * np.gradient(x, dt)[cycles]) * dt)
    heat = float(np.sum(power[cycles]) * dt)
    assert np.all(power >= 0.0)
    if name == "hardening":
        assert heat == 0.0 and abs(work) < 1e-9
    else:
        assert work > 0.1 and heat == pytest.approx(work, rel=2e-3)


def test_each_effects_records_are_told_a_heat_seen_in_one_record_only():
    """Seed 5 case 8 (two records, the steps run first and cold): the relaxation shows in both
    records, the heat in the sine blocks alone -- no fit on the other record can learn it."""
    case = pc.make_partner_case(5, 8, label=("relaxation", "thermal"))
    seen = case.drawn["visible_by_record"]
    noise = case.drawn["noise_fraction"]
    assert set(seen) == {"relaxation", "thermal"}
    assert all(len(v) == len(case.train) + len(case.tests) for v in seen.values())
    assert min(seen["relaxation"]) > 3 * noise
    assert seen["thermal"][0] > 10 * noise and seen["thermal"][1] < noise


def test_a_single_effect_shows_where_it_is_drawn_and_a_case_without_one_shows_none():
    one = pc.make_partner_case(1, 1)
    assert list(one.drawn["visible_by_record"]) == list(one.label)
    assert max(one.drawn["visible_by_record"][one.label[0]]) > 0
    cases = (pc.make_partner_case(1, i) for i in range(8))
    none = next(c for c in cases if c.label == ())
    assert none.drawn["visible_by_record"] == {}
