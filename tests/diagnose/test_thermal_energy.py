"""Thermal drift is recognised by what only it does: a slow loss of stiffness and damping that
follows the energy the specimen dissipates, whatever order the programmes run in and however
warm the specimen starts; relaxation follows the deflection history instead.

The specimen (``validation/thermal_session.py``) runs four programmes as one session, its heat
fed by its own dissipated power; the same programmes on a relaxing specimen must be named
relaxation, not thermal.
"""

import numpy as np
import pytest

from bushenv.diagnose.validation.thermal_session import (
    DT,
    ORDERS,
    TAU_S,
    C,
    K,
    diagnose_session,
    programmes,
    relaxing_forces,
    thermal_forces,
)


@pytest.mark.parametrize(
    "order,warm", [("hot first", False), ("slow first", False), ("hot first", True)]
)
def test_a_drift_that_follows_the_dissipated_energy_is_named_thermal(order, warm):
    progs = programmes()
    r = diagnose_session(thermal_forces(progs, ORDERS[order], warm), progs, ORDERS[order])
    assert r["effect"] == "thermal", (r["effect"], r["top_two"])
    assert r["shrink"] > 0.4


@pytest.mark.parametrize("order", list(ORDERS))
def test_a_memory_of_the_deflection_is_named_relaxation_not_thermal(order):
    progs = programmes()
    r = diagnose_session(relaxing_forces(progs), progs, ORDERS[order])
    assert r["effect"] == "relaxation", (r["effect"], r["top_two"])
    assert "thermal" not in r["effect"].split("+")


@pytest.mark.parametrize(
    "order,warm",
    [(("slow", "hot"), False), (("mixed", "hot"), True), (("hot", "broad"), True)],
)
def test_a_session_of_two_records_is_named_thermal(order, warm):
    """Each record is judged by a fit on the other alone. A lone record keeps a warm start only
    where it needs one: under a steady power its heat is affine in the start's cooling, and a
    start fitted whole traded with the spring and the heating law (the first two were
    ``outside_candidates`` and ``hardening+thermal``); the third starts warm and needs it."""
    progs = programmes()
    r = diagnose_session(thermal_forces(progs, order, warm), progs, order)
    assert r["effect"] == "thermal", (r["effect"], r["top_two"])


@pytest.mark.parametrize("order", list(ORDERS))
def test_a_heat_fed_by_friction_is_read_as_hysteretic(order):
    """A heat fed by ``|v|`` (a friction's dissipation) over a session of four programmes is
    named thermal with the hysteretic heating law."""
    progs = programmes()
    r = diagnose_session(
        thermal_forces(progs, ORDERS[order], False, "hysteretic"), progs, ORDERS[order]
    )
    assert r["effect"] == "thermal", (r["effect"], r["top_two"])
    assert r["parameters"]["thermal"]["heating"] == "hysteretic"


@pytest.mark.parametrize(
    "order,warm", [(("broad", "slow"), False), (("hot", "slow"), False), (("mixed", "broad"), True)]
)
def test_a_run_order_carries_the_heat_from_record_to_record(order, warm):
    """Told the order and the rest, a record's start is what the one before left, cooled over
    the rest: no start of its own to trade with the spring. These sessions answered
    ``outside_candidates`` without the order."""
    progs = programmes()
    r = diagnose_session(thermal_forces(progs, order, warm), progs, order, run_order=True)
    assert r["effect"] == "thermal", (r["effect"], r["top_two"])
    assert r["records"]["sessions"] == [list(order)]


def test_a_warm_session_gives_back_its_cold_spring_and_its_leak():
    """Every record after the first starts warm; the leak (60 s) lies between the grid's
    values. Read between them, the leak and the cold spring come back: a leak held at a grid
    value makes the warm starts take part of the spring (10 % high before)."""
    progs = programmes()
    order = ORDERS["hot first"]
    r = diagnose_session(thermal_forces(progs, order, True), progs, order)
    p = r["parameters"]
    assert r["effect"] == "thermal", r["effect"]
    assert abs(p["k_n_per_m"] / K - 1.0) < 0.02, p["k_n_per_m"]
    assert abs(p["thermal"]["time_constant_s"] / TAU_S - 1.0) < 0.1, p["thermal"]
    assert p["thermal"]["heating"] == "viscous"


def test_a_judged_start_is_read_from_its_cooling_not_from_the_records_level():
    """A record that is only stiffer or softer than the fit (a level, as a friction's secant at
    another amplitude gives) gets no start; one whose stiffness recovers as it cools gets the
    start it cooled from."""
    from bushenv.diagnose.fitting import cooling_scale

    t = np.arange(int(20.0 / DT)) * DT
    x = 2e-3 * np.sin(2 * np.pi * 1.3 * t) * (1.0 + 0.5 * np.sin(2 * np.pi * 0.11 * t))
    v = np.gradient(x, DT)
    spring = np.stack([x, v], axis=1)
    start = -np.exp(-t / 8.0)[:, None] * spring @ np.array([2e4, 200.0])  # a warm start, N
    softer = -0.1 * (K * x + C * v)  # 10 % softer through the whole record
    assert cooling_scale(softer, start, spring) == pytest.approx(0.0, abs=0.02)
    assert cooling_scale(0.7 * start, start, spring) == pytest.approx(0.7, rel=1e-6)
    assert cooling_scale(softer + 0.7 * start, start, spring) == pytest.approx(0.7, rel=1e-3)


def test_a_judged_start_claims_no_more_than_its_cooling_nor_its_level_shows():
    """The start is the smaller reading: a level without a cooling gets none, and a cooling
    whose record is stiffer than the start would make it gets only what the level shows."""
    from bushenv.diagnose.fitting import judged_start

    t = np.arange(int(20.0 / DT)) * DT
    x = 2e-3 * np.sin(2 * np.pi * 1.3 * t) * (1.0 + 0.5 * np.sin(2 * np.pi * 0.11 * t))
    v = np.gradient(x, DT)
    spring = np.stack([x, v], axis=1)
    start = -np.exp(-t / 8.0)[:, None] * spring @ np.array([2e4, 200.0])
    softer, stiffer = -0.1 * (K * x + C * v), 0.1 * (K * x + C * v)
    assert judged_start(softer, start, spring) == pytest.approx(0.0, abs=0.02)
    assert judged_start(0.7 * start, start, spring) == pytest.approx(0.7, rel=1e-6)
    assert judged_start(softer + 0.7 * start, start, spring) == pytest.approx(0.7, rel=1e-3)
    level = float((stiffer + 0.7 * start) @ start) / float(start @ start)
    assert level < 0.5  # the stiffer record's level shows less than its cooling
    assert judged_start(stiffer + 0.7 * start, start, spring) == pytest.approx(level, rel=1e-9)
