"""bushenv reproduce: the report holds every figure of the tables, and refuses to overwrite."""

import json

import pytest

from bushenv.cli import main


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("repro")
    code = main(
        [
            "reproduce",
            "--out",
            str(out),
            "--axes",
            "radial",
            "--shipped",
            "--identification-s",
            "6.44",
            "--verification-s",
            "6.44",
        ]
    )
    assert code == 0
    return out


def test_report_json_holds_every_table_figure(quick_report):
    report = json.loads((quick_report / "report.json").read_text())
    for name in ("linear", "nn", "hybrid", "boucwen"):
        row = report["radial"][name]
        for key in ("rms_ratio", "esr", "max_error", "peak_error", "identification_s"):
            assert isinstance(row[key], float), (name, key)
        assert 0.0 < row["rms_ratio"] < 1.0
        # judged on an unseen record of the training amplitude too (the papers' protocol)
        assert 0.0 < row["same_amplitude"]["rms_ratio"] < 1.0
        assert row["same_amplitude"]["rms_ratio"] != row["rms_ratio"]
        assert row["verification_s"] > 0.0
        step = report["step"]["radial"][name]
        assert isinstance(step["bounded"], bool)
        assert step["departure_s"] is None or step["departure_s"] > 0
    assert report["paper"]["table2"]["axial"]["nn"] == [5.1, 7.7]
    k = report["radial"]["linear"]["linear_fit"]["k_n_per_mm"]
    assert 1000 < k < 2500  # near seed 000 Table 1 (1518.73 N/mm)


def test_report_writes_plots_and_markdown(quick_report):
    for name in ("radial_force_vs_time.png", "radial_loops.png", "radial_step.png", "report.md"):
        assert (quick_report / name).stat().st_size > 1000


def test_existing_report_is_not_overwritten(quick_report, capsys):
    code = main(["reproduce", "--out", str(quick_report), "--axes", "radial", "--shipped"])
    assert code == 2
    assert "exists; pass --force" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--seed", "-1"], "--seed must be >= 0"),
        (["--identification-s", "1"], "--identification-s must be at least 6.44 s"),
        (["--axes", "vertical"], "unknown axis 'vertical'"),
    ],
)
def test_bad_arguments_are_refused_before_measuring(tmp_path, capsys, argv, message):
    code = main(["reproduce", "--out", str(tmp_path / "r"), *argv])
    assert code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "r").exists()
