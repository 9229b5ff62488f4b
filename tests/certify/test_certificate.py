import json

import numpy as np
import pytest

from bushenv.certify import (
    CertifyError,
    CertifyOptions,
    certify,
    least_stable_holds,
    non_passive_bands,
)
from bushenv.certify.certificate import SIGN_FLOOR_N
from bushenv.models.linear import LinearBushing
from bushenv.persist import write_json

from .conftest import X_SCALE_M, fold_nn, fold_u, wrong_sign_hybrid

SMALL = dict(
    passivity_holds_m=(0.0,),
    reference_freq_hz=(10.0, 50.0),
    energy_amplitudes_m=(1e-3,),
    energy_freq_hz=(10.0, 50.0),
)


def _wrong_sign_truth(model, x):
    """Static force of the wrong-sign hybrid by a dense search, independent of bushenv."""
    xs = x / X_SCALE_M
    y = np.linspace(-1, 1, 400_001)
    out = []
    for u in xs:
        f = np.tanh(-u + 0.3 * y) - y  # beta = 1, feedback 0.3 (conftest defaults)
        k = np.flatnonzero((f[:-1] < 0) != (f[1:] < 0))
        assert k.size == 1
        out.append(model.k_n_per_m * u * X_SCALE_M + model.f_scale_n * y[k[0]])
    return np.array(out)


def test_wrong_sign_holds_are_exactly_where_the_static_force_opposes_the_reference():
    model = wrong_sign_hybrid()
    reference = LinearBushing(model.k_n_per_m, 0.0)
    cert = certify(model, reference, CertifyOptions(holds=81, stroke_m=4e-3, **SMALL))
    holds = cert.document["holds"]
    x = np.array([h["x_m"] for h in holds])
    static = np.array([h["static_force_n"] for h in holds])
    np.testing.assert_allclose(static, _wrong_sign_truth(model, x), atol=0.05)
    ref = np.array([h["reference_static_force_n"] for h in holds])
    np.testing.assert_allclose(ref, model.k_n_per_m * x, atol=1e-9)
    want = (static * ref < 0) & (np.minimum(np.abs(static), np.abs(ref)) > SIGN_FLOOR_N)
    got = np.array([h["wrong_sign"] for h in holds])
    assert list(got) == list(want)
    assert got.sum() > 20  # about +-1.6 mm of the +-4 mm stroke
    (lo_neg, hi_neg), (lo_pos, hi_pos) = cert.document["summary"]["wrong_sign_ranges_m"]
    assert lo_neg == pytest.approx(-hi_pos, abs=1e-4) and hi_neg == pytest.approx(-lo_pos, abs=1e-4)
    assert 1.3e-3 < hi_pos < 2.0e-3
    assert not cert.document["summary"]["passes_holds"]


def test_the_fold_model_certificate_lists_its_folds_and_least_stable_holds():
    model = fold_nn()
    reference = LinearBushing(1.0e6, 0.0)
    cert = certify(model, reference, CertifyOptions(holds=41, stroke_m=1e-3, **SMALL))
    doc = cert.document
    uf = fold_u(2.0) * X_SCALE_M
    assert [f["x_m"] for f in doc["folds"]] == pytest.approx([-uf, uf], abs=1e-8)
    assert [f["pair_exists"] for f in doc["folds"]] == ["above", "below"]
    counts = [len(h["fixed_points"]) for h in doc["holds"]]
    x = np.array([h["x_m"] for h in doc["holds"]])
    assert counts == [3 if abs(v) < uf else 1 for v in x]
    worst = least_stable_holds(model, np.linspace(-1e-3, 1e-3, 201), n=2)
    assert sorted(np.abs(worst)) == pytest.approx([0.53e-3, 0.53e-3])  # the grid next to u_f
    assert not doc["summary"]["passes_holds"]


def test_the_document_is_plain_json_with_the_issues_fields(tmp_path):
    cert = certify(fold_nn(), LinearBushing(1.0e6, 0.0), CertifyOptions(holds=5, **SMALL))
    path = tmp_path / "c.json"
    write_json(path, cert.document)
    doc = json.loads(path.read_text())
    h = doc["holds"][0]
    for key in (
        "x_m",
        "fixed_points",
        "reached",
        "departs",
        "static_force_n",
        "reference_static_force_n",
        "wrong_sign",
    ):
        assert key in h
    # one layout for every C (vectors), and the scalar forms of one coordinate
    assert set(h["fixed_points"][0]) == {"force", "force_n", "spectral_radius", "stable"}
    assert h["q"] == [h["x_m"]] and h["static_force"] == [h["static_force_n"]]
    assert doc["format"] == "bushenv-certificate" and doc["coords"] == ["deflection"]
    assert {"x_m", "force_n", "pair_exists", "spectral_radii"} <= set(doc["folds"][0])
    p = doc["passivity"]["holds"][0]
    assert len(p["frequency_hz"]) == len(p["im_k_n_per_m"][0])
    assert doc["passivity"]["energy_scan"]["fires"] == [[False, False]]


def test_non_passive_bands_of_a_model_with_a_silent_network_are_empty():
    model = wrong_sign_hybrid(f_scale_n=1e-9)  # practically Kelvin-Voigt
    assert non_passive_bands(model, 0.0) == []


def test_bad_options_and_mismatched_rates_are_refused():
    with pytest.raises(CertifyError, match="holds must be >= 3"):
        certify(fold_nn(), LinearBushing(1e6, 0.0), CertifyOptions(holds=2))
    with pytest.raises(CertifyError, match="stroke"):
        certify(fold_nn(), LinearBushing(1e6, 0.0), CertifyOptions(stroke_m=-1.0))
    with pytest.raises(CertifyError, match="reference at 100 Hz"):
        certify(fold_nn(), LinearBushing(1e6, 0.0, dt=0.01), CertifyOptions(holds=5))
    with pytest.raises(CertifyError, match="NARX models"):
        certify(LinearBushing(1e6, 0.0), LinearBushing(1e6, 0.0))


def test_extra_holds_join_the_grid_and_a_departing_one_says_where_it_lingered():
    model = fold_nn()
    hold = fold_u(2.0) * (1 + 1e-4) * X_SCALE_M
    opts = CertifyOptions(holds=5, stroke_m=1e-3, extra_holds_m=(hold,), **SMALL)
    doc = certify(model, LinearBushing(1.0e6, 0.0), opts).document
    x = [h["x_m"] for h in doc["holds"]]
    assert x == sorted(x) and len(x) == 6 and hold in x
    h = doc["holds"][x.index(hold)]
    assert h["departs"] and h["departure_observed"] and h["departs_from"] == "ghost"
    # it sat near the ghost of the vanished lower pair (y = -sqrt(1/2)), then jumped up
    ghost_force = model.f_offset_n - np.sqrt(0.5) * model.f_scale_n
    assert h["linger_force_n"] == pytest.approx(ghost_force, abs=0.05 * model.f_scale_n)
    assert h["static_force_n"] > 1800
