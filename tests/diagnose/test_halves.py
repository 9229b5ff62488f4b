"""A record that alone shows the gap is judged half against half, its halves one session."""

import json

import numpy as np

from bushenv.cli import main
from bushenv.diagnose import fit, halves, rule
from bushenv.diagnose.fit import diagnose
from bushenv.diagnose.markdown import markdown
from bushenv.diagnose.validation.thermal_session import (
    diagnose_session,
    programmes,
    thermal_forces,
)
from bushenv.record_files import save_columns
from bushenv.records import Record

from .synthetic import Rec, force, motion, record

DT = 1 / 204.8


def _slow(seed: int, effect: str) -> Rec:
    """A slow sine (0.3 Hz, 20 s): too slow to show a mass, a delay or a drift."""
    t = np.arange(int(20 / DT)) * DT
    x = 2e-3 * np.sin(2 * np.pi * 0.3 * t + seed)
    f = force(x, DT, effect)
    f = f + 0.005 * np.std(f) * np.random.default_rng(seed).normal(size=f.size)
    return Rec(t, x, f, DT, f"slow{seed}")


def test_halves_are_the_record_in_time_and_run_as_one_session():
    rec = record(1, duration_s=10.0)
    a, b = halves.halves_of(rec, "train")
    assert (a.name, b.name) == ("train.half1", "train.half2")
    assert np.array_equal(np.concatenate([a.force, b.force]), rec.force)
    assert b.time[0] == rec.time[a.time.size]
    assert halves.order_with_halves(None, "train") == [("train.half1", None), ("train.half2", 0.0)]
    given = [("test1", "cold"), ("train", 30.0), ("test2", 5.0)]
    assert halves.order_with_halves(given, "train") == [
        ("test1", "cold"), ("train.half1", 30.0), ("train.half2", 0.0), ("test2", 5.0),
    ]  # fmt: skip
    recs, names = halves.split_records([rec, rec], ["train", "other"], "train")
    assert names == ["train.half1", "train.half2", "other"] and recs[2] is rec


def test_a_record_too_short_for_two_judged_halves_is_not_split():
    assert not halves.can_split(record(1, duration_s=6.0))  # 3 s halves: 3 blocks
    assert halves.can_split(record(1, duration_s=10.0))


def test_an_effect_only_train_shows_is_named_on_its_halves():
    """TRAIN's fast motion shows the mass; the slow TESTs do not. Judged on whole records the
    mass is fitted only where it does not show: outside_candidates; half against half it is
    named."""
    train = record(1, "inertia", duration_s=30.0, name="train")
    tests = [_slow(2, "inertia"), _slow(3, "inertia")]
    whole = fit._diagnose_axis(
        [train], tests, "linear", None, 0, None, None, None, None, None, halve=False
    )
    assert whole["effect"] == rule.OUTSIDE
    r = diagnose(train, tests)
    assert r["effect"] == "inertia"
    assert r["named_on_records"] == ["train.half1", "train.half2"]
    assert r["records"]["sessions"] == [["train.half1", "train.half2"]]
    assert any("two halves run as one session" in n for n in r["notes"])
    assert "Named on: `train.half1`, `train.half2`." in markdown({**r, "plots": []})


def test_a_gap_no_candidate_closes_stays_outside_on_the_halves():
    """A hum at 7 Hz in TRAIN's force, unrelated to the motion: no candidate closes it on
    whole records or on halves."""
    train = record(1, duration_s=30.0, name="train")
    hum = 0.3 * np.std(train.force) * np.sin(2 * np.pi * 7.0 * train.time)
    train = Rec(train.time, train.displacement, train.force + hum, DT, "train")
    r = diagnose(train, [_slow(2, "none"), _slow(3, "none")])
    assert r["effect"] == rule.OUTSIDE
    assert r["named_on_records"] == []


def test_a_partner_that_only_tames_a_wild_extrapolation_is_not_named_on_halves():
    """A session of two records of the heated specimen, the broad one first and warm: only
    the hot record shows the heat. Thermal fitted on the hot halves extrapolates to the broad
    record 23 times worse than the null; a hardening beside it tames that and was named as a
    partner (``hardening+thermal``). Weighed where thermal fits (``rule.where_it_fits``),
    the answer is thermal, on the hot record's halves."""
    progs = programmes()
    order = ("broad", "hot")
    r = diagnose_session(thermal_forces(progs, order, warm=True), progs, order)
    assert r["effect"] == "thermal", (r["effect"], r["top_two"])
    assert r["named_on_records"] == ["hot.half1", "hot.half2"]
    assert r["records"]["judged"] == ["broad", "hot.half1", "hot.half2"]


def _three_axis(x0: np.ndarray, f0: np.ndarray, seed: int, name: str) -> Record:
    """A three-axis record: ``x0``, ``f0`` on the axial coordinate, a plain spring and damper
    under gentle random motion on the other two."""
    n, rng = x0.size, np.random.default_rng(seed)
    xs = [x0] + [0.5 * motion(seed + k, n * DT, DT, steps=False)[:n] for k in (1, 2)]
    fs = [f0] + [force(x, DT) for x in xs[1:]]
    fs = [f + 0.005 * np.std(f) * rng.normal(size=n) for f in fs]
    return Record(np.arange(n) * DT, np.stack(xs, 1), np.stack(fs, 1), name=name)


def test_a_coordinate_named_on_halves_reports_them_in_a_three_axis_diagnosis(tmp_path):
    """The axial mass shows only in TRAIN: that coordinate is named on TRAIN's halves, whose
    three-axis forces (measured, baseline, augmented) are reported beside the records'."""
    x0 = motion(1, 30.0, DT)
    recs = [_three_axis(x0, force(x0, DT, "inertia"), 10, "train")]
    for s in (2, 3):
        slow = _slow(s, "inertia")
        recs.append(_three_axis(slow.displacement, slow.force, 20 + s, f"slow{s}"))
    paths = []
    for r in recs:
        paths.append(str(tmp_path / f"{r.name}.csv"))
        save_columns(paths[-1], r.time, r.q, r.f)
    assert main(["diagnose", *paths, "--out", str(tmp_path / "out"), "--quiet"]) == 0
    axial = json.loads((tmp_path / "out" / "axial" / "report.json").read_text())
    assert axial["effect"] == "inertia"
    assert axial["named_on_records"] == ["train.half1", "train.half2"]
    for n in ("train", "train.half1", "train.half2", "slow2"):
        assert (tmp_path / "out" / "predictions" / f"{n}.csv").is_file()
