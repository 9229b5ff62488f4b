"""One model card over C coordinates: the same writer, format and checks for one axis and three."""

import json

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.identify import fit
from bushenv.identify.card import CARD_FORMAT, card_paths, load_card, save_fit
from bushenv.identify.card_text import coordinates, per_coordinate
from bushenv.models import get_model
from bushenv.models.base import PAPER_DT
from bushenv.records import Record

DT = PAPER_DT


def _record(n_coords: int, seconds: float, seed: int, name: str) -> Record:
    """A linear bushing's response to incommensurate sines, from rest."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds / DT)) * DT
    hz = rng.uniform(0.5, 4.0, size=(n_coords, 3))
    q = sum(np.sin(2 * np.pi * hz[:, k] * t[:, None]) for k in range(3)) * 0.6e-3
    q *= np.minimum(1.0, t / 0.5)[:, None]
    model = get_model("linear", dt=DT, coords=n_coords)
    x = q[:, 0] if n_coords == 1 else q
    return Record(t, x, model.simulate(x), name=name)


@pytest.mark.parametrize("n_coords", [1, 3])
def test_a_fit_of_any_number_of_coordinates_gets_the_one_card(tmp_path, n_coords, capsys):
    train = _record(n_coords, 6.0, 0, "train")
    held = _record(n_coords, 4.0, 1, "held")
    result = fit([train], "linear", progress=False)
    card = save_fit(result, tmp_path / "m.npz", held_out=[held], plots=False, notes=["a note"])
    assert card["format"] == CARD_FORMAT and card["coords"] == list(train.coords)
    assert list(card["training_range"]) == list(train.coords)
    assert "coverage" in card and card["notes"] == ["a note"] and "plots" not in card
    for entry in card["records"]:
        by = per_coordinate(entry["metrics"], coordinates(card))
        assert list(by) == list(train.coords)
        assert all(m["rms_ratio"] < 1e-6 for m in by.values())  # linear fits a linear bushing
    md = card_paths(tmp_path / "m.npz")[1].read_text()
    for c in train.coords:
        assert f"| train | {c} |" in md and f"| held-out | {c} |" in md
    loaded = load_card(tmp_path / "m.npz", records=[held])
    assert loaded.checked_records == ["held"]
    capsys.readouterr()
    assert main(["card", str(tmp_path / "m.npz")]) == 0
    assert "RMS ratio" in capsys.readouterr().out


def test_a_three_axis_card_written_before_the_one_card_still_reads(tmp_path):
    result = fit([_record(3, 6.0, 0, "train")], "linear", progress=False)
    save_fit(result, tmp_path / "m.npz", plots=False)
    path = card_paths(tmp_path / "m.npz")[0]
    old = json.loads(path.read_text())
    old["format"] = "bushenv-planar-model-card"
    del old["coords"]
    path.write_text(json.dumps(old))
    card = load_card(path)
    assert coordinates(card.data) == ["axial", "radial", "rotation"]


def test_the_card_warns_where_the_network_is_worse_than_its_backbone_on_unseen_records():
    from bushenv.identify.card_text import backbone_lines
    from bushenv.models.planar_base import COORDS

    def metrics(rms):
        return {
            c: {"rms_ratio": r, "max_error_ratio": 2 * r} for c, r in zip(COORDS, rms, strict=True)
        }

    card = {
        "model": "hybrid-bw",
        "records": [{"role": "train", "metrics": metrics([9, 9, 9])},
                    {"role": "held-out", "metrics": metrics([0.01, 0.03, 0.02])}],
        "backbone": {"model": "boucwen", "records": [{"metrics": metrics([0.02, 0.02, 0.02])}]},
    }  # fmt: skip
    line, warning = backbone_lines(card)
    assert "hybrid-bw 1.00 (2.00) / 3.00 (6.00) / 2.00 (4.00)" in line  # held-out only
    assert "makes the radial worse" in warning and "axial" not in warning
    card["backbone"]["records"][0]["metrics"] = metrics([0.02, 0.0289, 0.02])
    assert len(backbone_lines(card)) == 1  # within 5 % of the backbone (3.8 %): no warning
