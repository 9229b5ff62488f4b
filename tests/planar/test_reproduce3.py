"""bushenv reproduce --planar: the 3-axis table beside seed 000 Table 3, apart from report.json."""

import json

import numpy as np
import pytest

import bushenv.planar.reproduce3 as r3
from bushenv.cli import main
from bushenv.metrics import rms_ratio
from bushenv.models.base import PAPER_DT
from bushenv.planar.fitting import fit_planar
from bushenv.planar.reference import PlanarRubber


def test_planar_only_writes_its_own_report_and_the_table_beside_table3(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.setattr(r3, "MODELS", ("linear",))
    args = ["reproduce", "--planar", "only", "--identification-s", "8", "--verification-s", "7"]
    assert main([*args, "--out", str(tmp_path), "--quiet"]) == 0
    assert not (tmp_path / "report.json").exists()  # the papers' report (and its golden) untouched
    report = json.loads((tmp_path / "planar.json").read_text())
    assert list(report["records"]) == list(r3.unseen_records(PAPER_DT, 0, 7.0))
    row = report["records"]["random correlated n=1"]["linear"]
    assert set(row) == {"axial", "radial", "rotation"}
    assert report["records"]["radial preload + rotation sweep"]["linear"]["axial"]["at_rest"]
    out = capsys.readouterr().out
    assert "seed 000 Table 3                 axial               10.9 / 24.9" in out
    # the JSON is what the models do: recompute linear's radial RMS ratio on one record
    lin = fit_planar(r3.identification_records(PAPER_DT, 0, 8.0), "linear", None, PAPER_DT)
    qt = r3.unseen_records(PAPER_DT, 0, 7.0)["random correlated n=1"]
    ft = PlanarRubber.preset(seed=101).simulate(qt)
    want = rms_ratio(ft[:, 1], lin.model.simulate(qt)[:, 1])
    assert np.isclose(row["radial"]["rms_ratio"], want, rtol=1e-12)
    assert main([*args, "--out", str(tmp_path), "--quiet"]) == 2  # planar.json exists, no --force


@pytest.mark.slow
def test_hybrid_bw_meets_the_target_on_unseen_random_coupled_records():
    # docs/planar.md, "The 3-axis table in bushenv reproduce": seed 0, default options (30-150 s);
    # seed 1 misses one cell (moment MAX 6.5 %), as the docs say
    report = r3.planar_table(0, 40.0, 20.0, PAPER_DT, models=("hybrid-bw",))
    for rec, row in report["records"].items():
        if rec.startswith("random"):
            for axis, m in row["hybrid-bw"].items():
                assert m["rms_ratio"] <= 0.03 and m["max_error_ratio"] <= 0.06, (rec, axis, m)
