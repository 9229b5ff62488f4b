import csv
import json

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.diagnose.candidates import effect_names

from .synthetic import record


def write_csv(path, rec):
    data = np.column_stack([rec.time, rec.displacement, rec.force])
    np.savetxt(path, data, delimiter=",", header="time,displacement,force", comments="")
    return path


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    root = tmp_path_factory.mktemp("diag")
    train = write_csv(root / "train.csv", record(11, "friction", duration_s=20.0))
    t1 = write_csv(root / "random_a.csv", record(12, "friction", duration_s=12.0))
    t2 = write_csv(root / "steps_b.csv", record(13, "friction", duration_s=12.0))
    out = root / "out"
    code = main(["diagnose", str(train), str(t1), str(t2), "--out", str(out), "--quiet"])
    return root, out, code


def test_diagnose_command_writes_the_contract_files(case):
    _, out, code = case
    assert code == 0
    report = json.loads((out / "report.json").read_text())
    assert report["effect"] == "friction"
    assert {"effect", "ranking", "where", "top_two", "pairs", "gap_before", "gap_after"} <= set(
        report
    )
    assert [r["effect"] for r in report["ranking"]][0] == "friction"
    assert sorted(r["effect"] for r in report["ranking"]) == sorted(effect_names())
    assert report["mode"] == "cross"  # every record is used by default
    assert 0 <= report["unexplained"]["unexplained_share"] <= 1
    for r in report["ranking"]:
        assert {"effect", "gap_before", "gap_after", "shrink"} <= set(r)
        assert r["shrink"] == pytest.approx(1 - r["gap_after"] / r["gap_before"])
    assert {"regimes", "frequency", "time", "summary"} <= set(report["where"])
    for stem in ("random_a", "steps_b"):
        with open(out / "predictions" / f"{stem}.csv") as fh:
            rows = list(csv.reader(fh))
        assert rows[0] == ["time", "force_measured", "force_baseline", "force_augmented"]
        assert len(rows) == 1 + int(round(12.0 * 204.8))
    md = (out / "report.md").read_text()
    assert "friction" in md
    for png in report["plots"]:
        assert (out / png).stat().st_size > 1000
        assert f"({png})" in md
    for stem in ("random_a", "steps_b"):
        assert f"forces_{stem}.png" in report["plots"] and f"loops_{stem}.png" in report["plots"]


def test_none_writes_augmented_equal_to_baseline(tmp_path):
    train = write_csv(tmp_path / "train.csv", record(21, "none", duration_s=15.0))
    test = write_csv(tmp_path / "test.csv", record(22, "none", duration_s=10.0))
    out = tmp_path / "out"
    assert main(["diagnose", str(train), str(test), "--out", str(out), "--quiet"]) == 0
    assert json.loads((out / "report.json").read_text())["effect"] == "none"
    data = np.loadtxt(out / "predictions" / "test.csv", delimiter=",", skiprows=1)
    assert np.array_equal(data[:, 2], data[:, 3])


def test_existing_out_dir_is_refused_and_left_untouched(case, capsys):
    root, out, _ = case
    keep = root / "existing"
    keep.mkdir()
    (keep / "notes.txt").write_text("mine")
    args = ["diagnose", str(root / "train.csv"), str(root / "random_a.csv"), "--quiet"]
    assert main(args + ["--out", str(keep)]) == 2
    err = capsys.readouterr().err
    assert "already exists" in err and "--force" in err
    assert sorted(p.name for p in keep.iterdir()) == ["notes.txt"]
    assert main(args + ["--out", str(keep), "--force"]) == 0
    assert (keep / "notes.txt").read_text() == "mine"
    assert (keep / "report.json").is_file()


def test_bad_records_are_refused_with_the_loaders_message(tmp_path, capsys):
    good = write_csv(tmp_path / "good.csv", record(31, "none", duration_s=5.0))
    bad = tmp_path / "bad.csv"
    bad.write_text("time,disp,force\n0,0,0\n0.1,0,0\n")
    code = main(["diagnose", str(good), str(bad), "--out", str(tmp_path / "o1"), "--quiet"])
    assert code == 2
    err = capsys.readouterr().err
    assert "bad.csv" in err and "disp" in err
    missing = tmp_path / "missing.csv"
    code = main(["diagnose", str(missing), str(good), "--out", str(tmp_path / "o2"), "--quiet"])
    assert code == 2
    assert "missing.csv" in capsys.readouterr().err
    assert not (tmp_path / "o1").exists() and not (tmp_path / "o2").exists()


def test_too_short_and_constant_records_are_refused(tmp_path, capsys):
    good = write_csv(tmp_path / "good.csv", record(32, "none", duration_s=5.0))
    short = tmp_path / "short.csv"
    short.write_text(
        "time,displacement,force\n" + "".join(f"{i * 0.01},0.001,{i}\n" for i in range(10))
    )
    code = main(["diagnose", str(good), str(short), "--out", str(tmp_path / "o"), "--quiet"])
    assert code == 2
    assert "short" in capsys.readouterr().err
    flat = tmp_path / "flat.csv"
    flat.write_text(
        "time,displacement,force\n" + "".join(f"{i * 0.01},0.001,{i}\n" for i in range(200))
    )
    args = ["diagnose", str(flat), str(good), "--out", str(tmp_path / "o3"), "--quiet"]
    code = main(args + ["--resample", "keep"])  # flat.csv is at 100 Hz, good.csv is not
    assert code == 2
    assert "displacement is constant" in capsys.readouterr().err


def test_duplicate_test_file_stems_are_refused(tmp_path, capsys):
    a = tmp_path / "a"
    b = tmp_path / "b"
    a.mkdir()
    b.mkdir()
    train = write_csv(tmp_path / "train.csv", record(41, "none", duration_s=5.0))
    t1 = write_csv(a / "test.csv", record(42, "none", duration_s=5.0))
    t2 = write_csv(b / "test.csv", record(43, "none", duration_s=5.0))
    code = main(["diagnose", str(train), str(t1), str(t2), "--out", str(tmp_path / "o"), "--quiet"])
    assert code == 2
    assert "distinct" in capsys.readouterr().err


def test_unavailable_baseline_is_a_clear_error(tmp_path, capsys, monkeypatch):
    import bushenv.identify as identify

    monkeypatch.delattr(identify, "fit_model", raising=False)
    train = write_csv(tmp_path / "train.csv", record(51, "none", duration_s=5.0))
    test = write_csv(tmp_path / "test.csv", record(52, "none", duration_s=5.0))
    code = main(
        [
            "diagnose",
            str(train),
            str(test),
            "--out",
            str(tmp_path / "o"),
            "--quiet",
            "--baseline",
            "nn",
        ]
    )
    assert code == 2
    assert "fit_model" in capsys.readouterr().err


def test_quiet_writes_nothing_on_stderr(tmp_path, capsys):
    train = write_csv(tmp_path / "train.csv", record(61, "relaxation", duration_s=8.0))
    test = write_csv(tmp_path / "test.csv", record(62, "relaxation", duration_s=8.0))
    out = tmp_path / "out"
    assert main(["diagnose", str(train), str(test), "--out", str(out), "--quiet"]) == 0
    assert capsys.readouterr().err == ""
