"""A run order: the heat a record leaves is carried over the rest into the next, a session has
one start, and a bad order file or a bad row is refused by name."""

import json

import numpy as np
import pytest

from bushenv.diagnose.design import Prepared
from bushenv.diagnose.effects.base import Scales, Signals
from bushenv.diagnose.effects.thermal import Thermal, heating_state, session_heat, warm_heat
from bushenv.diagnose.errors import DiagnoseError
from bushenv.diagnose.session import link, read_order

DT = 1 / 200.0


def _signals(seed: int, seconds: float) -> Signals:
    rng = np.random.default_rng(seed)
    return Signals(np.cumsum(rng.normal(size=int(seconds / DT))) * 1e-5, DT)


def _prep(name: str, s: Signals) -> Prepared:
    return Prepared(name, "test", np.arange(s.x.size) * DT, s, np.ones(s.x.size), 0 * s.x)


@pytest.mark.parametrize("tau", [30.0, np.inf])
@pytest.mark.parametrize("heating", ["viscous", "hysteretic"])
def test_the_heat_carried_over_a_rest_is_the_heat_of_the_records_run_as_one(tau, heating):
    """Two records with a rest of one sample between are one record run through: the second
    record's heat is the tail of the whole one's, for a leak and without one."""
    a, b = _signals(1, 5.0), _signals(2, 3.0)
    b.before = (a, DT)
    whole = heating_state(np.concatenate([a.v, b.v]), DT, tau, heating, 0.01)
    np.testing.assert_allclose(session_heat(b, tau, heating, 0.01), whole[a.x.size :], rtol=1e-9)
    alone = heating_state(b.v, DT, tau, heating, 0.01)
    assert np.max(np.abs(session_heat(b, tau, heating, 0.01) - alone)) > 0.1 * np.max(alone)


def test_a_session_has_one_start_that_cools_through_the_records_after_it():
    a, b, c = _signals(1, 5.0), _signals(2, 3.0), _signals(3, 2.0)
    preps = [_prep("a", a), _prep("b", b), _prep("c", c)]
    assert link(preps, [("a", None), ("b", 40.0), ("c", 10.0)]) == [["a", "b", "c"]]
    assert preps[1].start_key == preps[2].start_key == preps[0].uid
    assert c.session_time_s == pytest.approx(5.0 + 40.0 + 3.0 + 10.0)
    tau = 30.0
    scales = Scales.of([a, b, c])
    cols = Thermal().nuisance_columns(c, ("viscous", tau), scales)
    t = np.arange(c.x.size) * DT
    expected = -warm_heat(tau, scales) * np.exp(-(58.0 + t) / tau) * c.x
    np.testing.assert_allclose(cols[:, 0], expected, rtol=1e-12)


def test_a_session_that_began_cold_has_no_start_and_records_not_listed_keep_their_own():
    a, b, d = _signals(1, 5.0), _signals(2, 3.0), _signals(4, 3.0)
    preps = [_prep("a", a), _prep("b", b), _prep("d", d)]
    link(preps, [("a", "cold"), ("b", 40.0)])
    for s in (a, b):
        assert not np.any(Thermal().nuisance_columns(s, ("viscous", 30.0), Scales.of([s])))
    assert preps[2].start_key == preps[2].uid and d.before is None
    assert np.any(Thermal().nuisance_columns(d, ("viscous", 30.0), Scales.of([d])))


@pytest.mark.parametrize(
    "order,message",
    [
        ([("a", None), ("x", 3.0)], "row 2: no record named 'x'; the records are a, b"),
        ([("a", None), ("a", 3.0)], "row 2: record 'a' is listed twice"),
        ([("a", 3.0)], "row 1: 'a' has a rest but no record before it"),
        ([("a", None), ("b", -1.0)], "row 2: rest -1.0 of 'b' is not a time in s >= 0"),
    ],
)
def test_a_bad_order_is_refused_by_row(order, message):
    preps = [_prep("a", _signals(1, 2.0)), _prep("b", _signals(2, 2.0))]
    with pytest.raises(DiagnoseError, match=message.replace("(", r"\(").replace(")", r"\)")):
        link(preps, order)


def test_records_of_one_name_cannot_be_ordered():
    preps = [_prep("a", _signals(1, 2.0)), _prep("a", _signals(2, 2.0))]
    with pytest.raises(DiagnoseError, match="distinct; a name more than one record"):
        link(preps, [("a", None)])


def test_an_order_file_is_read_and_a_bad_line_named(tmp_path):
    path = tmp_path / "order.csv"
    path.write_text("record,rest_before_s\ntrain,\n\ntest_a,120\ntest_b,cold\ntest_c,30.5\n")
    assert read_order(path) == [
        ("train", None),
        ("test_a", 120.0),
        ("test_b", "cold"),
        ("test_c", 30.5),
    ]
    path.write_text("record,rest_before_s\ntrain,\ntest_a,2 min\n")
    with pytest.raises(DiagnoseError, match=r"order.csv line 3: rest '2 min' is not a number"):
        read_order(path)
    path.write_text("name,rest\ntrain,\n")
    with pytest.raises(DiagnoseError, match=r"order.csv line 1: expected the header"):
        read_order(path)
    with pytest.raises(DiagnoseError, match="cannot read the run order"):
        read_order(tmp_path / "missing.csv")


def test_the_command_takes_a_run_order_and_refuses_a_bad_one_by_line(tmp_path, capsys):
    from bushenv.cli import main

    from .synthetic import record
    from .test_report import write_csv

    train = write_csv(tmp_path / "train.csv", record(21, "none", duration_s=8.0))
    test = write_csv(tmp_path / "sweep.csv", record(22, "none", duration_s=6.0))
    order = tmp_path / "order.csv"
    order.write_text("record,rest_before_s\nsweep,\ntrian,60\n")
    args = ["diagnose", str(train), str(test), "--run-order", str(order), "--quiet"]
    assert main([*args, "--out", str(tmp_path / "bad")]) == 2
    err = capsys.readouterr().err
    assert "order.csv line 3: no record named 'trian'; the records are sweep, train" in err
    assert not (tmp_path / "bad").exists()
    order.write_text("record,rest_before_s\nsweep,\ntrain,60\n")
    assert main([*args, "--out", str(tmp_path / "out")]) == 0
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert report["records"]["sessions"] == [["sweep", "train"]]
    times = report["records"]["session_time_s"]
    assert times == {"sweep": 0.0, "train": pytest.approx(66.0, abs=0.01)}
    md = (tmp_path / "out" / "report.md").read_text()
    assert "- run in one session, heat carried over: sweep -> train" in md
    assert "where_session.png" in report["plots"] and "![where_session.png]" in md
    assert (tmp_path / "out" / "where_session.png").stat().st_size > 10_000
