"""bushenv measure --axes 3: its records and programmes (bushenv fit on them:
tests/identify/test_fit_command_measured.py)."""

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.record_columns import THREE_AXES
from bushenv.record_files import load_record


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
    assert train[0].read_text().splitlines()[0] == THREE_AXES.header_text
    rec = {p.name: load_record(p, coords=3) for p in train}
    ind = rec["random_independent_n1_6s_seed0.csv"]
    cor = rec["random_correlated_n1_6s_seed0.csv"]
    assert ind.time.size == round(6 / ind.dt)
    peak = np.abs(ind.q).max(axis=0)
    assert np.allclose(peak, [2e-3, 2e-3, 0.05], rtol=1e-6)  # amplitude index n = 1 per axis
    assert abs(np.corrcoef(cor.q[:, 0], cor.q[:, 1])[0, 1]) > 0.5
    assert abs(np.corrcoef(ind.q[:, 0], ind.q[:, 1])[0, 1]) < 0.3
    assert np.abs(load_record(held[0], coords=3).q).max() > 1.4 * np.abs(ind.q).max()


def test_measure_papers_programme_has_the_coupled_sine_sets(tmp_path):
    from bushenv.programmes import programme_items

    motions = {i.name: i.x for i in programme_items("papers", 3, 1 / 204.8)}
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


def _fails(args, capsys) -> str:
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_measure_refuses_programmes_without_a_3_axis_form(tmp_path, capsys):
    line = _fails(["measure", "--axes", "3", "--programme", "step", "--out", str(tmp_path)], capsys)
    assert "--programme step has no 3-axis form" in line
    line = _fails(["measure", "--axes", "3", "--model", "nn", "--out", str(tmp_path)], capsys)
    assert "over 3 coordinates has no preset" in line and "its .npz file" in line


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
