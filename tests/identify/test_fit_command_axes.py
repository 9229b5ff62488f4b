"""``bushenv fit`` over any number of coordinates: the records say C, and the same command,
options, card and outputs follow for one axis and for three."""

import json

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.models import load_model
from bushenv.record_files import load_record

# the flags that cut each kind's training short: --teacher-steps is the same flag for both
BUDGET = {
    1: ["--teacher-steps", "20", "--iters-per-length", "5,5,5,5,5"],
    3: ["--teacher-steps", "20", "--free-run-steps", "5", "--window", "32"],
}


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    """Per C, (training record, held-out record) measured on the reference."""
    out = {}
    for axes in (1, 3):
        folder = tmp_path_factory.mktemp(f"rec{axes}")
        argv = ["measure", "--axes", str(axes), "--programme", "random", "--duration", "8",
                "--quiet"]  # fmt: skip
        assert main([*argv, "--out", str(folder)]) == 0
        paths = sorted(folder.glob("*.csv"))
        if axes == 1:  # one record: a second measured with another seed is held out
            assert main([*argv, "--seed", "1", "--out", str(folder / "held")]) == 0
            paths += sorted((folder / "held").glob("*.csv"))
        out[axes] = (str(paths[0]), str(paths[1]))
    return out


@pytest.mark.parametrize("axes", [1, 3])
@pytest.mark.parametrize("model", ["linear", "hybrid"])
def test_one_command_fits_records_of_any_coordinates_with_one_card(
    records, tmp_path, capsys, axes, model
):
    train, held = records[axes]
    out = tmp_path / "m.npz"
    extra = BUDGET[axes] if model == "hybrid" else []
    argv = ["fit", train, "--validate", held, "--model", model, "--seed", "3", "--no-plots",
            "--quiet", "--out", str(out), *extra]  # fmt: skip
    assert main(argv) == 0
    stdout = capsys.readouterr().out
    assert stdout.startswith(f"model {model} -> {out}")
    assert "RMS ratio %" in stdout and "coordinate" in stdout
    card = json.loads(out.with_name("m.card.json").read_text())
    assert out.with_name("m.card.md").exists()
    assert card["model"] == model and len(card["coords"]) == axes
    assert card["source"]["seed"] == 3 and [r["role"] for r in card["records"]] == [
        "train",
        "held-out",
    ]
    assert set(card["training_range"]) == set(card["coords"])
    loaded = load_model(out, coords=axes)
    assert loaded.n_coords == axes and loaded.name == model


def test_a_kind_without_a_form_for_the_records_names_both_and_the_records_it_takes(
    records, tmp_path, capsys
):
    capsys.readouterr()
    argv = ["fit", records[1][0], "--model", "nn-axis", "--out", str(tmp_path / "m.npz")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "nn-axis is a three-axis model" in err and "not from one axis" in err
    assert "time,displacement_axial" in err and "choose one of linear" in err


def test_a_flag_of_the_other_coordinate_count_is_refused_naming_what_the_kind_takes(
    records, tmp_path, capsys
):
    capsys.readouterr()
    argv = ["fit", records[1][0], "--model", "hybrid", "--free-run-steps", "3", "--out",
            str(tmp_path / "m.npz")]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--free-run-steps is not an option of model hybrid" in err
    assert "hybrid (3-axis)" in err and "--iters-per-length" in err


@pytest.mark.parametrize("axes", [1, 3])
def test_the_same_seed_gives_the_same_model_to_the_bit_whatever_c(records, tmp_path, axes):
    # budgets are iterations: no clock decides where a training stops unless asked
    train, held = records[axes]
    runs = []
    for name in ("a", "b"):
        out = tmp_path / f"{name}.npz"
        argv = ["fit", train, "--model", "hybrid", "--seed", "2", "--no-plots", "--quiet",
                "--out", str(out), *BUDGET[axes]]  # fmt: skip
        assert main(argv) == 0
        runs.append(load_model(out, coords=axes))
    x = load_record(held).displacement  # the held-out record drives both
    assert np.array_equal(runs[0].simulate(x), runs[1].simulate(x))
