"""bushenv fit / bushenv card: files written, card contents, flags from the registry, bad input."""

import dataclasses
import json

import numpy as np
import pytest
from standin import DT, standin_drive, standin_force

from bushenv.cli import main
from bushenv.identify.card import CardError, data_sha256, load_card, sha256_file
from bushenv.identify.options import option
from bushenv.metrics import all_metrics
from bushenv.models import MODELS, ModelEntry, load_model
from bushenv.models.linear import LinearBushing
from bushenv.records import Record, load_csv, resample, save_csv

QUICK = [
    "--teacher-steps",
    "100",
    "--window-lengths",
    "10,30",
    "--iters-per-length",
    "10,10",
    "--batch-windows",
    "4",
    "--eval-every",
    "5",
]


def write_record(path, duration_s, seed, peak_m=0.002):
    x = standin_drive(duration_s, seed=seed, peak_m=peak_m)
    return save_csv(Record.from_arrays(x, standin_force(x), DT, name=path.stem), path)


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    d = tmp_path_factory.mktemp("records")
    return {
        "a": write_record(d / "train_a.csv", 4.0, 0),
        "b": write_record(d / "train_b.csv", 3.0, 1),
        "held": write_record(d / "held.csv", 3.0, 2, peak_m=0.0025),
    }


@pytest.fixture(scope="module")
def fitted(records, tmp_path_factory):
    out = tmp_path_factory.mktemp("fit") / "my_nn.npz"
    args = ["fit", str(records["a"]), str(records["b"]), "--model", "nn", "--out", str(out)]
    code = main(args + ["--validate", str(records["held"]), "--seed", "4", "--quiet", *QUICK])
    assert code == 0
    return out


def test_fit_writes_model_card_and_figures_beside_each_other(fitted):
    names = sorted(p.name for p in fitted.parent.iterdir())
    assert names == [
        "my_nn.1-held.loops.png",
        "my_nn.1-held.time.png",
        "my_nn.card.json",
        "my_nn.card.md",
        "my_nn.npz",
    ]
    assert load_model(fitted).name == "nn"


def test_card_names_records_with_hashes_options_and_held_out_metrics(fitted, records):
    card = json.loads(fitted.with_name("my_nn.card.json").read_text())
    assert card["model"] == "nn" and card["model_sha256"] == sha256_file(fitted)
    src = card["source"]
    assert src["seed"] == 4 and src["wall_time_s"] > 0
    assert src["options"]["window_lengths"] == [10, 30] and src["options"]["n_past_x"] == 5
    roles = [(r["role"], r["name"]) for r in card["records"]]
    assert roles == [("train", "train_a"), ("train", "train_b"), ("held-out", "held")]
    held = card["records"][2]
    rec = load_csv(records["held"])
    assert held["sha256"] == sha256_file(records["held"])
    assert held["data_sha256"] == data_sha256(rec)
    assert held["sample_rate_hz"] == pytest.approx(204.8) and held["duration_s"] == pytest.approx(
        len(rec) * DT
    )
    expected = all_metrics(rec.force, load_model(fitted).simulate(rec.displacement))
    for key in ("rms_ratio", "esr", "max_error", "nrmse"):
        assert held["metrics"][key] == pytest.approx(expected[key], rel=1e-12)
    md = fitted.with_name("my_nn.card.md").read_text()
    assert "| held-out |" in md and "| teacher_steps | 100 |" in md
    assert "![my_nn.1-held.time.png](my_nn.1-held.time.png)" in md


def test_load_card_checks_record_hashes_and_the_model_file(fitted, records, tmp_path):
    card = load_card(fitted, records=[records["a"], load_csv(records["held"])])
    assert card.checked_records == ["train_a.csv", "held.csv"]
    changed = tmp_path / "held.csv"
    rec = load_csv(records["held"])
    rec.force[10] += 1.0
    save_csv(rec, changed, overwrite=True)
    with pytest.raises(CardError, match="record held.csv does not match the card"):
        load_card(fitted, records=[changed])
    with pytest.raises(CardError, match="record other.csv is not one of the card's records"):
        load_card(fitted, records=[write_record(tmp_path / "other.csv", 1.0, 5)])


def test_card_command_exits_2_naming_a_record_that_does_not_match(
    fitted, records, tmp_path, capsys
):
    assert main(["card", str(fitted), str(records["a"]), str(records["held"])]) == 0
    assert "2 record file(s) match the card" in capsys.readouterr().out
    rec = load_csv(records["a"])
    rec.displacement[5] += 1e-6
    bad = save_csv(rec, tmp_path / "train_a.csv")
    assert main(["card", str(fitted), str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "record train_a.csv does not match the card" in err


def test_the_library_takes_record_files_and_saves_the_same_card(records, tmp_path):
    from bushenv.identify import fit
    from bushenv.identify.card import save_fit

    result = fit([records["a"]], "linear", progress=False)
    card = save_fit(result, tmp_path / "lin.npz", held_out=[load_csv(records["held"])], plots=False)
    assert [r["sha256"] for r in card["records"]] == [
        sha256_file(records["a"]),
        sha256_file(records["held"]),
    ]
    assert load_card(tmp_path / "lin.npz", records=[records["a"]]).data == card


def test_a_replaced_model_file_no_longer_matches_its_card(fitted, tmp_path):
    copy = tmp_path / "my_nn.npz"
    copy.write_bytes(fitted.read_bytes())
    (tmp_path / "my_nn.card.json").write_text(fitted.with_name("my_nn.card.json").read_text())
    load_card(copy)
    LinearBushing(1e5, 1e3).save(copy)
    with pytest.raises(CardError, match="does not match the card"):
        load_card(copy)


def test_results_on_stdout_progress_with_time_left_on_stderr(records, tmp_path, capsys):
    out = tmp_path / "h.npz"
    args = ["fit", str(records["a"]), "--model", "hybrid", "--out", str(out), "--no-plots"]
    assert main(args + ["--progress-every-s", "0", *QUICK]) == 0
    captured = capsys.readouterr()
    assert "model hybrid -> " in captured.out and "RMS ratio %" in captured.out
    assert "s left]" in captured.err
    assert main(args + ["--force", "--quiet", *QUICK]) == 0
    assert capsys.readouterr().err == ""


def bad_inputs(records, tmp_path):
    a, held = str(records["a"]), str(records["held"])
    slow = save_csv(resample(load_csv(records["b"]), 0.01), tmp_path / "slow.csv")
    short = write_record(tmp_path / "short.csv", 0.25, 3)
    return [
        ([a, str(slow)], "slow.csv line 3: sampled at 100 Hz (time step 0.01 s), "),
        ([a, str(slow)], "train_a.csv at 204.8 Hz"),
        ([a, "--validate", str(slow)], "slow.csv line 3: sampled at 100 Hz (time step 0.01"),
        ([a, "--validate"], "--validate needs at least one held-out record file"),
        ([a, "--generations", "3"], "--generations is not an option of model nn"),
        ([str(short)], "short.csv: record too short for the lags"),
        ([a, "--n-past-x", "100"], "record too short for the lags"),
        ([a, "--hidden", "4,4,4"], "hidden must be one or two positive sizes"),
        ([a, "--recipe", "magic"], "recipe must be one of free-run, teacher-forcing"),
        ([], "no training records given"),
        ([a, str(tmp_path / "missing.csv")], "missing.csv: no such record file"),
        ([a, "--validate", held, "--teacher-lr", "x"], "teacher_lr: 'x' is not a number"),
    ]


def test_bad_input_is_one_line_exit_2_and_writes_nothing(records, tmp_path, capsys):
    out = tmp_path / "out" / "m.npz"
    for extra, message in bad_inputs(records, tmp_path):
        code = main(["fit", *extra, "--model", "nn", "--out", str(out), "--quiet", *QUICK])
        err = capsys.readouterr().err.strip()
        assert code == 2, extra
        assert err.count("\n") == 0 and message in err, (extra, err)
        assert not out.parent.exists(), extra


def test_an_existing_model_file_is_not_replaced_without_force(fitted, records, capsys):
    before = fitted.read_bytes()
    code = main(["fit", str(records["a"]), "--model", "linear", "--out", str(fitted)])
    assert code == 2 and "pass --force" in capsys.readouterr().err
    assert fitted.read_bytes() == before


@dataclasses.dataclass(frozen=True)
class ScaledOptions:
    gain: float = option(2.0, "multiply the least-squares stiffness by this")


def fit_scaled(data, options, seed=0, progress=False):
    x, f, v = data.concatenated()
    (k, c), *_ = np.linalg.lstsq(np.column_stack([x, v]), f, rcond=None)
    return LinearBushing(options.gain * k, c, dt=data.dt)


def test_a_model_registered_at_run_time_gets_its_flags_and_is_fitted(records, tmp_path, capsys):
    entry = ModelEntry(LinearBushing, "test model", fit=fit_scaled, options=ScaledOptions)
    with MODELS.temporarily("scaled", entry):
        with pytest.raises(SystemExit):
            main(["fit", "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "options of scaled" in text and "--gain X" in text and "(default: 2.0)" in text
        out = tmp_path / "s.npz"
        args = ["fit", str(records["a"]), "--model", "scaled", "--out", str(out), "--quiet"]
        assert main(args + ["--gain", "3", "--no-plots"]) == 0
        card = load_card(out)
        assert card.data["source"]["options"] == {"gain": 3.0}
        plain = main(
            [
                "fit",
                str(records["a"]),
                "--model",
                "linear",
                "--out",
                str(tmp_path / "l.npz"),
                "--quiet",
                "--no-plots",
            ]
        )
        assert plain == 0
        assert load_model(out).k_n_per_m == pytest.approx(
            3 * load_model(tmp_path / "l.npz").k_n_per_m
        )
    with pytest.raises(SystemExit) as stop:  # gone with its model: argparse refuses the flag
        main(
            [
                "fit",
                str(records["a"]),
                "--model",
                "linear",
                "--out",
                str(tmp_path / "x.npz"),
                "--gain",
                "3",
            ]
        )
    assert stop.value.code == 2
