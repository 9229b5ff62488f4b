"""A wrong-sign static force needs no reference: a passive bushing pushes back."""

import json

import numpy as np
import pytest

from bushenv.certify import CertifyOptions, certify
from bushenv.certify.certificate import SIGN_FLOOR_N
from bushenv.cli import main

from .conftest import pulling_nn

SMALL = dict(
    passivity_holds_m=(0.0,),
    reference_freq_hz=(10.0,),
    energy_amplitudes_m=(1e-3,),
    energy_freq_hz=(10.0,),
)


def test_a_network_that_pulls_at_4mm_is_wrong_sign_without_a_reference():
    model = pulling_nn()
    cert = certify(model, None, CertifyOptions(holds=9, stroke_m=4e-3, **SMALL))
    doc = cert.document
    holds = {round(h["x_m"] * 1e3, 6): h for h in doc["holds"]}
    at4 = holds[4.0]
    assert at4["static_force_n"] < -400  # holds +4 mm with a negative force
    assert at4["reference_static_force_n"] is None and at4["wrong_sign"]
    x = np.array([h["x_m"] for h in doc["holds"]])
    f = np.array([h["static_force_n"] for h in doc["holds"]])
    want = (f * x < 0) & (np.abs(f) > SIGN_FLOOR_N)
    assert [h["wrong_sign"] for h in doc["holds"]] == list(want)
    assert doc["summary"]["wrong_sign_holds"] == 8  # every hold but x = 0
    assert doc["summary"]["wrong_sign_ranges_m"] == [[-4e-3, -1e-3], [1e-3, 4e-3]]
    assert not doc["summary"]["passes_holds"]
    assert "deflection" in doc["settings"]["wrong_sign_against"]


def test_a_network_that_pushes_back_is_not_wrong_sign_without_a_reference():
    model = pulling_nn(beta=-0.5)  # the same network, pushing back
    doc = certify(model, None, CertifyOptions(holds=9, stroke_m=4e-3, **SMALL)).document
    assert doc["summary"]["wrong_sign_holds"] == 0


def test_certify_without_reference_reports_the_wrong_sign_and_exits_1(tmp_path, capsys):
    path = pulling_nn().save(tmp_path / "pulls.npz")
    out = tmp_path / "cert"
    args = ["certify", str(path), "--stroke-mm", "4", "--holds", "9", "--passivity-mm", "0",
            "--energy-mm", "1", "--out", str(out), "--quiet"]  # fmt: skip
    code = main(args)
    printed = capsys.readouterr().out
    assert code == 1
    assert "wrong sign 8 [-4..-1 mm, +1..+4 mm]" in printed
    assert "judged against the deflection" in printed
    doc = json.loads((out / "certificate.json").read_text())
    assert doc["reference"]["source"] is None and doc["summary"]["wrong_sign_holds"] == 8


@pytest.mark.parametrize("x_m, static_n, want", [(4e-3, -460.0, True), (4e-3, 460.0, False),
                                                 (-1e-3, 20.0, True), (1e-3, -5.0, False),
                                                 (0.0, -50.0, False)])  # fmt: skip
def test_the_sign_rule_without_a_reference(x_m, static_n, want):
    from bushenv.certify.certificate import wrong_sign

    assert bool(wrong_sign([[x_m]], [[static_n]])[0]) is want


def test_the_vector_rule_weighs_a_moment_by_the_lever_and_is_the_scalar_rule_for_c_1():
    from bushenv.certify.certificate import wrong_sign

    units = ("m",)
    assert wrong_sign(np.array([[1e-3]]), np.array([[-11.0]]), units)[0]
    assert not wrong_sign(np.array([[1e-3]]), np.array([[-9.0]]), units)[0]
    assert not wrong_sign(np.array([[-1e-3]]), np.array([[-50.0]]), units)[0]
    three = ("m", "m", "rad")
    q = np.array([[0.0, 0.0, 0.05]])  # 0.05 rad: the floor is 10 N x 0.04 m/rad x 0.05 rad
    assert wrong_sign(q, np.array([[0.0, 0.0, -0.5]]), three)[0]  # -0.025 J < -0.02 J
    assert not wrong_sign(q, np.array([[0.0, 0.0, -0.3]]), three)[0]
    # against a reference: a coordinate where the two oppose, both beyond the floor
    ref = np.array([[0.0, 0.0, 1.0]])
    assert wrong_sign(q, np.array([[0.0, 0.0, -0.5]]), three, ref)[0]
    assert not wrong_sign(q, np.array([[0.0, 0.0, -0.3]]), three, ref)[0]
