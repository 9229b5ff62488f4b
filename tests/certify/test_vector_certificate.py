"""``bushenv certify`` of a three-axis network: holds on a grid of deflection vectors, wrong sign
judged against the deflection (q . f >= 0 for a passive bushing), passivity as a matrix test."""

import json

import numpy as np
import pytest

from bushenv.certify.network import CertifyError
from bushenv.cli import main
from bushenv.models.planar_linear import PlanarLinear
from bushenv.models.planar_narx import N_IN, PlanarNarx
from bushenv.planar.certificate import VectorOptions, certify_vector, per_coordinate, wrong_sign

SPAN = (3e-3, 3e-3, 0.075)


def network(w1_scale=0.05, feedback=0.0, b_out=(0.0, 0.0, 0.0), seed=0):
    """A small MIMO network; ``feedback`` adds a unit that feeds each output's last value back."""
    rng = np.random.default_rng(seed)
    w1 = rng.normal(0, w1_scale, (9, N_IN))
    w_out = rng.normal(0, 0.3, (3, 9))
    if feedback:
        w1[:3, 18:21] = feedback * np.eye(3)  # lag-1 own outputs into units 0-2
        w_out[:, :3] = np.eye(3)
    return PlanarNarx(
        q_offset=np.zeros(3), q_scale=np.array([2e-3, 2e-3, 0.05]), f_offset=np.zeros(3),
        f_scale=np.array([500.0, 2000.0, 150.0]), w1=w1, b1=np.zeros(9), w_out=w_out,
        b_out=np.array(b_out),
    )  # fmt: skip


def test_the_one_axis_rule_is_the_case_c_equals_1():
    units = ("m",)
    assert wrong_sign(np.array([[1e-3]]), np.array([[-11.0]]), units)[0]
    assert not wrong_sign(np.array([[1e-3]]), np.array([[-9.0]]), units)[0]
    assert not wrong_sign(np.array([[-1e-3]]), np.array([[-50.0]]), units)[0]
    assert per_coordinate(201, 1) == 201 and per_coordinate(201, 3) == 7


def test_a_quiet_network_settles_everywhere_and_a_constant_pull_is_wrong_sign():
    doc, grid = certify_vector(network(), VectorOptions(SPAN, 5))
    s = doc["summary"]
    assert s["holds"] == 125 and s["holds_settling_stably"] == 125 and s["fold_crossings"] == 0
    assert np.array(grid["radius"]).shape == (5, 5, 5)
    pulling = network(w1_scale=0.0, b_out=(-1.0, 0.0, 0.0))  # -500 N axial at every hold
    doc, _ = certify_vector(pulling, VectorOptions(SPAN, 5))
    bad = np.array(doc["wrong_sign_at"])
    assert doc["summary"]["wrong_sign_holds"] > 0 and not doc["summary"]["passes_holds"]
    assert np.all(bad[:, 0] > 0)  # a constant -500 N axial pulls outward only where axial > 0


def test_a_network_that_cannot_settle_fails_its_holds():
    doc, _ = certify_vector(network(feedback=4.0), VectorOptions(SPAN, 3))
    s = doc["summary"]
    assert not s["passes_holds"]
    assert s["holds_with_more_than_one"] + s["holds_without_a_stable_one"] > 0


def test_a_linear_model_has_nothing_to_certify_and_says_so():
    with pytest.raises(CertifyError, match="no recurrence to certify"):
        certify_vector(PlanarLinear.preset(), VectorOptions(SPAN, 3))


def test_the_command_takes_a_three_axis_file_with_a_span_and_exits_as_a_test_runner(
    tmp_path, capsys
):
    path = str(network().save(tmp_path / "nn3.npz"))
    assert main(["certify", path, "--out", str(tmp_path / "c"), "--quiet"]) == 2
    assert "give --stroke-mm and --rotation-mrad" in capsys.readouterr().err
    code = main(["certify", path, "--stroke-mm", "3", "--rotation-mrad", "75", "--holds", "27",
                 "--out", str(tmp_path / "c"), "--quiet"])  # fmt: skip
    doc = json.loads((tmp_path / "c" / "certificate.json").read_text())
    assert code == (
        0 if doc["summary"]["passes_holds"] and doc["summary"]["passes_passivity"] else 1
    )
    assert doc["coords"] == ["axial", "radial", "rotation"] and doc["summary"]["holds"] == 27
    assert (tmp_path / "c" / "spectral_radius.png").stat().st_size > 0
    out = capsys.readouterr().out
    assert "rotation +-75 mrad" in out and "wrong sign is q . f < 0" in out
    assert main(["certify", path, "--reference", "rubber", "--stroke-mm", "3",
                 "--rotation-mrad", "75", "--out", str(tmp_path / "d")]) == 2  # fmt: skip
    assert "compares with no reference yet" in capsys.readouterr().err
