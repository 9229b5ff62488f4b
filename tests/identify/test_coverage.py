"""What a card says a three-axis model was shown: held combinations found where they are, not
where they are not, and named on the card for held-out records that use the others."""

import json

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.identify.coverage import (
    coverage,
    every_combination,
    held_combinations,
    not_shown,
)
from bushenv.models.planar_base import COORDS
from bushenv.motions import held_sweeps, random_independent

DT = 1 / 204.8
SPAN = np.array([2e-3, 2e-3, 0.05])


def test_a_held_rotation_under_a_radial_sweep_is_found_with_its_sign_and_level():
    q = np.zeros((int(4 / DT), 3))
    q[:, 2] = -0.04  # held at 80 % of the span, below zero
    q[:, 1] = 1.5e-3 * np.sin(2 * np.pi * 2.0 * np.arange(len(q)) * DT)
    found = held_combinations(q, DT, SPAN, COORDS)
    assert list(found) == ["rotation held -, radial moving"]
    assert found["rotation held -, radial moving"] == pytest.approx(0.8)


def test_random_motion_holds_nothing_still_and_a_record_at_rest_moves_nothing():
    q = random_independent(1.0, 40.0, DT, seed=0)
    assert held_combinations(q, DT, np.abs(q).max(axis=0), COORDS) == {}
    assert held_combinations(np.zeros((1000, 3)), DT, SPAN, COORDS) == {}
    assert held_combinations(q[:, :1], DT, SPAN[:1], COORDS[:1]) == {}  # one coordinate


def test_the_combined_programme_shows_every_combination_once_each():
    motions = held_sweeps(1.0, DT, duration_s=6.0)
    assert len(motions) == len(every_combination(COORDS)) == 12
    cov = coverage([q for _, q in motions], DT, COORDS)
    assert cov["held_not_shown"] == [] and sorted(cov["held_shown"]) == sorted(
        every_combination(COORDS)
    )
    for name, q in motions:  # each record holds exactly the combination its name says
        held, sign, moving = name.split("_")[0], name.split("_")[2], name.split("_")[3]
        assert list(held_combinations(q, DT, cov_span(cov), COORDS)) == [
            f"{held} held {sign}, {moving} moving"
        ]


def cov_span(cov):
    return np.array([cov["span"][c] for c in COORDS])


def test_not_shown_names_what_a_use_holds_beyond_the_training_records():
    train = coverage([random_independent(1.0, 40.0, DT, seed=1)], DT, COORDS)
    assert train["held_shown"] == {} and len(train["held_not_shown"]) == 12
    use = dict(held_sweeps(1.0, DT, duration_s=6.0))["radial_held_-_axial_sweep"]
    assert list(not_shown(train, use, DT)) == ["radial held -, axial moving"]
    again = coverage([use], DT, COORDS)
    assert not_shown(again, use, DT) == {}


def test_a_fit_card_lists_the_combinations_and_names_held_out_records_beyond_them(tmp_path, capsys):
    rec = tmp_path / "rec"
    assert main(["measure", "--axes", "3", "--programme", "random", "--duration", "8",
                 "--out", str(rec), "--quiet"]) == 0  # fmt: skip
    comb = tmp_path / "comb"
    assert main(["measure", "--axes", "3", "--programme", "combined", "--duration", "4",
                 "--out", str(comb), "--quiet"]) == 0  # fmt: skip
    assert len(list(comb.glob("*.csv"))) == 12
    held = comb / "rotation_held_+_radial_sweep.csv"
    capsys.readouterr()
    assert main(["fit", *map(str, sorted(rec.glob("*.csv"))), "--validate", str(held),
                 "--model", "linear", "--out", str(tmp_path / "m.npz"), "--quiet",
                 "--no-plots"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "combinations shown: 0 of 12" in out
    assert "not shown: " in out and "rotation held +, radial moving" in out
    card = json.loads((tmp_path / "m.card.json").read_text())
    assert card["coverage"]["held_shown"] == {}
    assert list(card["records"][-1]["not_shown"]) == ["rotation held +, radial moving"]
    assert main(["card", str(tmp_path / "m.npz")]) == 0
    assert "rotation held +, radial moving, which the training records never held" in (
        capsys.readouterr().out
    )


def test_combined_is_refused_for_one_axis_naming_the_fix(tmp_path, capsys):
    assert main(["measure", "--programme", "combined", "--out", str(tmp_path)]) == 2
    assert "add --axes 3" in capsys.readouterr().err


def test_a_record_made_in_memory_is_named_on_the_card_not_taken_for_a_file(tmp_path):
    from bushenv.identify.card import record_entry
    from bushenv.models.planar_linear import PlanarLinear
    from bushenv.records import Record

    motion = dict(held_sweeps(1.0, DT, duration_s=2.0))["axial_held_+_radial_sweep"]
    model = PlanarLinear.preset()
    rec = Record(np.arange(len(motion)) * DT, motion, model.simulate(motion), name="held, sweep")
    entry = record_entry(rec, "held-out", model, tmp_path)
    assert entry["file"] is None and entry["name"] == "held, sweep" and entry["sha256"] is None
