"""``bushenv certify`` of a three-axis network: the one certificate over held deflection vectors
(fixed points, folds, free runs), wrong sign against the deflection (q . f >= 0 for a passive
bushing) or against a reference, passivity as a matrix test."""

import json

import numpy as np
import pytest

from bushenv.certify import CertifyOptions, certify, per_coordinate
from bushenv.certify.network import CertifyError
from bushenv.cli import main
from bushenv.models.planar_linear import PlanarLinear
from bushenv.models.planar_narx import N_IN, PlanarNarx

SPAN = (3e-3, 3e-3, 0.075)
SMALL = dict(hold_s=4.0, reference_freq_hz=(10.0, 50.0))


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


def test_holds_per_coordinate_are_odd_and_the_one_axis_grid_is_the_holds_themselves():
    assert per_coordinate(201, 1) == 201 and per_coordinate(201, 3) == 7
    assert per_coordinate(27, 3) == 3 and per_coordinate(3, 2) == 3


def test_a_quiet_network_settles_everywhere_and_a_constant_pull_is_wrong_sign():
    cert = certify(network(), None, CertifyOptions(holds=125, span=SPAN, **SMALL))
    s = cert.document["summary"]
    assert s["holds"] == 125 and s["holds_settling_stably"] == 125 and s["folds"] == 0
    assert cert.document["coords"] == ["axial", "radial", "rotation"]
    h = cert.document["holds"][0]
    assert len(h["q"]) == 3 and len(h["static_force"]) == 3 and "x_m" not in h
    pulling = network(w1_scale=0.0, b_out=(-1.0, 0.0, 0.0))  # -500 N axial at every hold
    doc = certify(pulling, None, CertifyOptions(holds=125, span=SPAN, **SMALL)).document
    bad = np.array(doc["summary"]["wrong_sign_at"])
    assert doc["summary"]["wrong_sign_holds"] > 0 and not doc["summary"]["passes_holds"]
    assert np.all(bad[:, 0] > 0)  # a constant -500 N axial pulls outward only where axial > 0


def test_a_reference_judges_the_static_force_coordinate_by_coordinate():
    ref = PlanarLinear(np.diag([2.5e5, 1.0e6, 3.0e3]), np.zeros((3, 3)))
    pulling = network(w1_scale=0.0, b_out=(-1.0, 0.0, 0.0))
    doc = certify(pulling, ref, CertifyOptions(holds=27, span=SPAN, **SMALL)).document
    at = [h for h in doc["holds"] if h["q"][0] > 0 and h["q"][1] == 0 and h["q"][2] == 0][0]
    assert at["reference_static_force"] == pytest.approx([2.5e5 * 3e-3, 0.0, 0.0], abs=1e-6)
    assert at["wrong_sign"] and at["static_off"]  # -500 N against +750 N
    assert "reference" in doc["settings"]["wrong_sign_against"]
    p = doc["passivity"]["holds"][0]
    assert np.array(p["reference_loss_eigenvalues_j"]).shape == (2, 3)
    # a spring has no loss: its eigenvalues vanish to rounding
    assert np.abs(p["reference_loss_eigenvalues_j"]).max() < 1e-6


def test_a_network_that_cannot_settle_fails_its_holds():
    doc = certify(network(feedback=4.0), None, CertifyOptions(holds=27, span=SPAN, **SMALL))
    s = doc.document["summary"]
    assert not s["passes_holds"]
    assert s["holds_with_more_than_one"] + s["holds_without_a_stable_one"] > 0


def test_a_linear_model_has_nothing_to_certify_and_says_so():
    with pytest.raises(CertifyError, match="holds by construction"):
        certify(PlanarLinear.preset(), None, CertifyOptions(span=SPAN))


def test_a_reference_of_another_number_of_coordinates_is_refused():
    from bushenv.models.linear import LinearBushing

    with pytest.raises(CertifyError, match="reference has 1 coordinate"):
        certify(network(), LinearBushing(1e6, 0.0), CertifyOptions(holds=27, span=SPAN))


def test_the_command_takes_a_three_axis_file_with_a_span_and_exits_as_a_test_runner(
    tmp_path, capsys
):
    path = str(network().save(tmp_path / "nn3.npz"))
    assert main(["certify", path, "--out", str(tmp_path / "c"), "--quiet"]) == 2
    assert "give --stroke-mm and --rotation-mrad" in capsys.readouterr().err
    code = main(["certify", path, "--stroke-mm", "3", "--rotation-mrad", "75", "--holds", "27",
                 "--hold-s", "4", "--out", str(tmp_path / "c"), "--quiet"])  # fmt: skip
    doc = json.loads((tmp_path / "c" / "certificate.json").read_text())
    assert code == (
        0 if doc["summary"]["passes_holds"] and doc["summary"]["passes_passivity"] else 1
    )
    assert doc["coords"] == ["axial", "radial", "rotation"] and doc["summary"]["holds"] == 27
    for png in ("spectral_radius", "spectral_radius_map", "static_force", "passivity"):
        assert (tmp_path / "c" / f"{png}.png").stat().st_size > 0
    out = capsys.readouterr().out
    assert "rotation +-75 mrad" in out and "q . f >= 0" in out


def test_the_command_certifies_against_a_three_axis_reference(tmp_path, capsys):
    path = str(network().save(tmp_path / "nn3.npz"))
    ref = str(PlanarLinear.preset().save(tmp_path / "lin3.npz"))
    code = main(["certify", path, "--reference", ref, "--stroke-mm", "3", "--rotation-mrad",
                 "75", "--holds", "27", "--hold-s", "4", "--out", str(tmp_path / "d"),
                 "--quiet"])  # fmt: skip
    assert code in (0, 1)
    doc = json.loads((tmp_path / "d" / "certificate.json").read_text())
    assert doc["reference"]["source"] == ref and doc["reference"]["class"] == "PlanarLinear"
    assert all(h["reference_static_force"] is not None for h in doc["holds"])
    assert doc["judge"]["vetting"] and "vetting_verdict" in doc["judge"]  # vetted first
    assert "reference: " + ref + ", vetting" in capsys.readouterr().out
    one_axis = str(tmp_path / "lin1.npz")
    from bushenv.models.linear import LinearBushing

    LinearBushing(1e6, 0.0).save(one_axis)
    argv = ["certify", path, "--reference", one_axis, "--stroke-mm", "3", "--rotation-mrad",
            "75", "--out", str(tmp_path / "e"), "--quiet"]  # fmt: skip
    assert main(argv) == 2
    assert "is a one-axis model" in capsys.readouterr().err


def test_a_three_axis_reference_that_fails_its_vetting_is_refused_unless_trusted(tmp_path, capsys):
    path = str(network().save(tmp_path / "nn3.npz"))
    pulling = str(network(w1_scale=0.0, b_out=(-1.0, 0.0, 0.0)).save(tmp_path / "pull3.npz"))
    argv = ["certify", path, "--reference", pulling, "--stroke-mm", "3", "--rotation-mrad", "75",
            "--holds", "27", "--hold-s", "4", "--out", str(tmp_path / "f"), "--quiet"]  # fmt: skip
    assert main(argv) == 2
    assert "failed its vetting" in capsys.readouterr().err
    assert main([*argv, "--trust-reference"]) in (0, 1)
    doc = json.loads((tmp_path / "f" / "certificate.json").read_text())
    assert doc["judge"]["trusted_despite_failed_vetting"]


@pytest.mark.parametrize("coords", [1, 3])
def test_one_layout_for_any_number_of_coordinates(coords):
    from .conftest import fold_nn

    model = fold_nn() if coords == 1 else network()
    span = (1e-3,) if coords == 1 else SPAN
    doc = certify(model, None, CertifyOptions(holds=27, span=span, **SMALL)).document
    assert doc["format"] == "bushenv-certificate" and len(doc["coords"]) == coords
    assert doc["settings"]["span"] == list(span)
    for h in doc["holds"]:
        assert len(h["q"]) == coords and all(len(p["force"]) == coords for p in h["fixed_points"])
        assert {"reached", "departs", "oscillates", "wrong_sign", "static_off"} <= set(h)
    for f in doc["folds"]:
        assert len(f["q_from"]) == len(f["q_to"]) == coords
    for p in doc["passivity"]["holds"]:
        assert np.array(p["loss_eigenvalues_j"]).shape[1:] == (512, coords)
    common = {"holds", "holds_settling_stably", "holds_with_more_than_one", "folds",
              "wrong_sign_holds", "least_loss_eigenvalue_j", "passes_holds",
              "passes_passivity"}  # fmt: skip
    assert common <= set(doc["summary"])
    assert (doc["passivity"]["energy_scan"] is None) == (coords > 1)


def test_a_three_axis_certificate_of_the_layout_before_is_refused_by_name(tmp_path):
    from bushenv.export.certificate import read_document
    from bushenv.models import ModelError

    old = {"summary": {}, "model": {"name": "nn"}, "holds": [{"q": [0, 0, 0], "fixed_points": 2}]}
    path = tmp_path / "certificate.json"
    path.write_text(json.dumps(old))
    with pytest.raises(ModelError, match="layout before the one certificate"):
        read_document(path)
