"""``bushenv fit`` on three-axis records measured by ``bushenv measure --axes 3``: the model, its
per-coordinate card, the range it names, and the refusals (one line each, exit 2)."""

import json
from pathlib import Path

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.identify import options_class
from bushenv.identify.options import flag_of, option_fields
from bushenv.models import load_model, names_for
from bushenv.record_columns import THREE_AXES
from bushenv.record_files import load_record

DOC = (Path(__file__).resolve().parents[2] / "docs" / "fit.md").read_text()


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    out = tmp_path_factory.mktemp("planar_records")
    args = ["measure", "--axes", "3", "--programme", "random", "--duration", "6"]
    assert main([*args, "--out", str(out / "train"), "--quiet"]) == 0
    assert main([*args, "--n", "1.5", "--seed", "5", "--out", str(out / "held"), "--quiet"]) == 0
    return sorted((out / "train").glob("*.csv")), sorted((out / "held").glob("*.csv"))


@pytest.mark.parametrize("model", ["linear", "boucwen"])
def test_fit_on_3_axis_records_writes_model_and_per_axis_card(records, tmp_path, capsys, model):
    train, held = records
    out = tmp_path / f"{model}.npz"
    extra = ["--evaluations", "10"] if model == "boucwen" else []
    args = ["fit", *map(str, train), "--model", model, "--validate", *map(str, held)]
    assert main([*args, "--out", str(out), "--quiet", *extra]) == 0
    fitted = load_model(out)
    assert fitted.name == model
    card = json.loads(out.with_name(f"{model}.card.json").read_text())
    assert card["format"] == "bushenv-model-card" and card["model"] == model
    roles = [r["role"] for r in card["records"]]
    assert roles == ["train", "train", "held-out", "held-out"]
    rec = load_record(held[0], coords=3)
    pred = fitted.simulate(rec.q)
    for i, axis in enumerate(("axial", "radial", "rotation")):
        m = card["records"][2]["metrics"][axis]
        want = np.sqrt(np.mean((pred[:, i] - rec.f[:, i]) ** 2) / np.mean(rec.f[:, i] ** 2))
        assert m["rms_ratio"] == pytest.approx(want, rel=1e-9)
        assert set(m) >= {"rms_ratio", "esr", "max_error_ratio", "max_error"}
    assert "| held-out | rotation |" in out.with_name(f"{model}.card.md").read_text()
    printed = capsys.readouterr().out
    assert "rotation" in printed
    # the held-out records are at n = 1.5: the card names them as extrapolation
    span = card["training_range"]
    assert span["radial"] == pytest.approx(2e-3, rel=1e-6)
    for r in card["records"][2:]:
        assert r["peak_deflection"]["radial"] / span["radial"] == pytest.approx(1.5, rel=1e-6)
        assert f"extrapolation: {r['file']} goes beyond" in printed
        assert "axial 1.50x, radial 1.50x, rotation 1.50x" in printed
    assert (
        "## Held-out records beyond the training range"
        in out.with_name(f"{model}.card.md").read_text()
    )


def test_a_held_out_record_within_the_training_range_is_not_named(records, tmp_path, capsys):
    train, _ = records
    out = tmp_path / "lin.npz"
    args = ["fit", str(train[0]), "--model", "linear", "--validate", str(train[1])]
    assert main([*args, "--out", str(out), "--quiet", "--no-plots"]) == 0
    assert "extrapolation:" not in capsys.readouterr().out


def _fails(args, capsys) -> str:
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_mixed_one_and_3_axis_records_are_refused(records, tmp_path, capsys):
    one = tmp_path / "one"
    assert main(["measure", "--programme", "random", "--duration", "3", "--out", str(one),
                 "--quiet"]) == 0  # fmt: skip
    single = next(one.glob("*.csv"))
    out = tmp_path / "m.npz"
    line = _fails(["fit", str(records[0][0]), str(single), "--model", "linear", "--out",
                   str(out)], capsys)  # fmt: skip
    assert str(records[0][0]) in line and str(single) in line and "one kind" in line
    line = _fails(["fit", str(single), "--model", "linear", "--validate", str(records[1][0]),
                   "--out", str(out)], capsys)  # fmt: skip
    assert "3-axis record" in line
    line = _fails(["fit", str(single), "--model", "nn-axis", "--out", str(out)], capsys)
    assert "nn-axis is a three-axis model" in line and THREE_AXES.header_text in line
    assert not out.exists()


def test_a_one_axis_option_on_a_3_axis_fit_is_refused(records, tmp_path, capsys):
    args = ["fit", str(records[0][0]), "--model", "nn", "--patience", "3"]
    line = _fails([*args, "--out", str(tmp_path / "x.npz")], capsys)
    assert "--patience is not an option of the 3-axis model nn" in line and "--window" in line


@pytest.mark.parametrize("name", names_for(3, fittable=True))
def test_every_planar_fit_flag_is_explained_in_docs_fit(name):
    missing = [
        flag_of(f.name)
        for f in option_fields(options_class(name, 3))
        if f"`{flag_of(f.name)}`" not in DOC
    ]
    assert not missing, f"docs/fit.md does not explain {missing} of the 3-axis {name}"


def test_3_axis_records_at_two_rates_are_refused_naming_both(records, tmp_path, capsys):
    from bushenv.record_files import save_columns

    rec = load_record(records[0][0], coords=3)
    fast = save_columns(tmp_path / "fast.csv", rec.time / 2, rec.q, rec.f)
    args = ["fit", str(records[0][0]), str(fast), "--model", "linear"]
    line = _fails([*args, "--out", str(tmp_path / "x.npz")], capsys)
    assert "fast.csv line 3: sampled at 409.6 Hz" in line and "204.8 Hz" in line
    # --resample brings them to one rate, as for one-axis records
    out = tmp_path / "y.npz"
    assert main([*args, "--resample", "204.8", "--no-plots", "--quiet", "--out", str(out)]) == 0
    card = json.loads(out.with_name("y.card.json").read_text())
    assert card["sample_rate_hz"] == pytest.approx(204.8) and len(card["records"]) == 2


def test_a_hybrid_card_sets_its_network_against_its_backbone_alone(records, tmp_path, capsys):
    from bushenv.metrics import rms_ratio

    train, held = records
    out = tmp_path / "hbw.npz"
    args = ["fit", *map(str, train), "--model", "hybrid-bw", "--validate", *map(str, held),
            "--evaluations", "1", "--teacher-steps", "20", "--free-run-steps", "0",
            "--out", str(out), "--quiet", "--no-plots"]  # fmt: skip
    assert main(args) == 0
    card = json.loads(out.with_name("hbw.card.json").read_text())
    assert card["backbone"]["model"] == "boucwen"
    assert [r["name"] for r in card["backbone"]["records"]] == [p.stem for p in held]
    rec = load_record(held[0], coords=3)  # the figures are the backbone's own free run
    alone = load_model(out).backbone_alone().simulate(rec.q)
    got = card["backbone"]["records"][0]["metrics"]["radial"]["rms_ratio"]
    assert got == pytest.approx(rms_ratio(rec.f[:, 1], alone[:, 1]), rel=1e-12)
    assert "its backbone alone (boucwen)" in capsys.readouterr().out
    md = out.with_name("hbw.card.md").read_text()
    assert "## The network against its backbone alone" in md

    linear = tmp_path / "lin.npz"  # no backbone, no entry
    assert main(["fit", *map(str, train), "--model", "linear", "--validate", *map(str, held),
                 "--out", str(linear), "--quiet", "--no-plots"]) == 0  # fmt: skip
    assert "backbone" not in json.loads(linear.with_name("lin.card.json").read_text())
