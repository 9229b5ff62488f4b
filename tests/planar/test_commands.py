"""bushenv measure --axes 3 and bushenv fit on 3-axis records: files, cards, refusals."""

import json
from pathlib import Path

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.identify.options import flag_of, option_fields
from bushenv.models import load_model, names_for
from bushenv.planar.fitting import options_class
from bushenv.planar.records import HEADER_TEXT, load_planar_csv

DOC = (Path(__file__).resolve().parents[2] / "docs" / "fit.md").read_text()


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    out = tmp_path_factory.mktemp("planar_records")
    args = ["measure", "--axes", "3", "--programme", "random", "--duration", "6"]
    assert main([*args, "--out", str(out / "train"), "--quiet"]) == 0
    assert main([*args, "--n", "1.5", "--seed", "5", "--out", str(out / "held"), "--quiet"]) == 0
    return sorted((out / "train").glob("*.csv")), sorted((out / "held").glob("*.csv"))


def test_measure_writes_independent_and_correlated_3_axis_records(records):
    train, held = records
    assert [p.name for p in train] == [
        "random_correlated_n1_6s_seed0.csv",
        "random_independent_n1_6s_seed0.csv",
    ]
    assert train[0].read_text().splitlines()[0] == HEADER_TEXT
    rec = {p.name: load_planar_csv(p) for p in train}
    ind = rec["random_independent_n1_6s_seed0.csv"]
    cor = rec["random_correlated_n1_6s_seed0.csv"]
    assert ind.time.size == round(6 / ind.dt)
    peak = np.abs(ind.q).max(axis=0)
    assert np.allclose(peak, [2e-3, 2e-3, 0.05], rtol=1e-6)  # amplitude index n = 1 per axis
    assert abs(np.corrcoef(cor.q[:, 0], cor.q[:, 1])[0, 1]) > 0.5
    assert abs(np.corrcoef(ind.q[:, 0], ind.q[:, 1])[0, 1]) < 0.3
    assert np.abs(load_planar_csv(held[0]).q).max() > 1.4 * np.abs(ind.q).max()


def test_measure_papers_programme_has_the_coupled_sine_sets(tmp_path):
    from bushenv.planar.machine import items

    motions = dict(items("papers", 1 / 204.8))
    names = list(motions)
    assert "radial_preload_3mm_rotation_sweep" in names
    assert "rotation_preload_0.075rad_radial_sweep" in names
    assert sum(n.startswith("random_") for n in names) == 4
    # the n = 1 sets identify: 2 mm and 0.05 rad held, each under the other's sweep, then a
    # 2 mm axial hold under a radial sweep; each addition comes last, so the records before
    # keep the noise seeds they had
    assert names[6:] == [
        "radial_preload_2mm_rotation_sweep",
        "rotation_preload_0.05rad_radial_sweep",
        "axial_preload_3mm_radial_sweep",
        "axial_preload_2mm_radial_sweep",
    ]
    at_rest = {1: 0, 2: 0, 0: 2}  # held coordinate -> the one at rest
    sets = ((names[6], 1, 2e-3, 2, 0.05), (names[7], 2, 0.05, 1, 2e-3),
            (names[9], 0, 2e-3, 1, 2e-3))  # fmt: skip
    for name, held, level, swept, swept_peak in sets:
        q = motions[name]
        assert np.allclose(q[int(2 * 204.8) :, held], level) and np.all(q[:, at_rest[held]] == 0)
        assert np.abs(q[:, swept]).max() == pytest.approx(swept_peak, rel=0.02)
    assert np.allclose(motions[names[8]][int(2 * 204.8) :, 0], 3e-3)  # n = 1.5 verifies


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
    assert card["format"] == "bushenv-planar-model-card" and card["model"] == model
    roles = [r["role"] for r in card["records"]]
    assert roles == ["train", "train", "held-out", "held-out"]
    rec = load_planar_csv(held[0])
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
    assert "nn-axis is a 3-axis model" in line and HEADER_TEXT in line
    assert not out.exists()


def test_a_one_axis_option_on_a_3_axis_fit_is_refused(records, tmp_path, capsys):
    args = ["fit", str(records[0][0]), "--model", "nn", "--patience", "3"]
    line = _fails([*args, "--out", str(tmp_path / "x.npz")], capsys)
    assert "--patience is not an option of the 3-axis model nn" in line and "--window" in line


def test_measure_refuses_programmes_without_a_3_axis_form(tmp_path, capsys):
    line = _fails(["measure", "--axes", "3", "--programme", "step", "--out", str(tmp_path)], capsys)
    assert "--programme step has no 3-axis form" in line
    line = _fails(["measure", "--axes", "3", "--model", "nn", "--out", str(tmp_path)], capsys)
    assert "three-axis model with a preset" in line


@pytest.mark.parametrize("name", names_for(3, fittable=True))
def test_every_planar_fit_flag_is_explained_in_docs_fit(name):
    missing = [
        flag_of(f.name)
        for f in option_fields(options_class(name))
        if f"`{flag_of(f.name)}`" not in DOC
    ]
    assert not missing, f"docs/fit.md does not explain {missing} of the 3-axis {name}"


def test_3_axis_records_at_two_rates_are_refused_naming_both(records, tmp_path, capsys):
    from bushenv.planar.records import save_planar_csv

    rec = load_planar_csv(records[0][0])
    fast = save_planar_csv(tmp_path / "fast.csv", rec.time / 2, rec.q, rec.f)
    args = ["fit", str(records[0][0]), str(fast), "--model", "linear"]
    line = _fails([*args, "--out", str(tmp_path / "x.npz")], capsys)
    assert "fast.csv is sampled at 409.6 Hz" in line and "204.8 Hz" in line
    line = _fails([*args[:2], "--model", "linear", "--resample", "204.8", "--out",
                   str(tmp_path / "x.npz")], capsys)  # fmt: skip
    assert "--resample is for one-axis records" in line


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
    rec = load_planar_csv(held[0])  # the figures are the backbone's own free run
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


def test_the_card_warns_where_the_network_is_worse_than_its_backbone_on_unseen_records():
    from bushenv.models.planar_base import COORDS
    from bushenv.planar.card import backbone_lines

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
