"""The certificate searcher: proposals from the model's certificates, a sweep otherwise."""

import numpy as np
import pytest

from bushenv.models.linear import LinearBushing
from bushenv.scales import MACHINE
from bushenv.search.base import SearchError
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.families import FAMILIES
from bushenv.search.guided import CertificateSearch, sine_coordinates, step_coordinates

from .test_references import wrong_sign_hybrid


def test_step_and_sine_coordinates_give_the_asked_profile():
    x = FAMILIES["step"].profile(step_coordinates(-3e-3, MACHINE.stroke_m))
    assert x[-1] == pytest.approx(-3e-3, rel=1e-12)
    d = FAMILIES["sine"].describe(sine_coordinates(45.0, 0.5e-3, 0.0, MACHINE))
    assert d["freq_hz"] == pytest.approx(45.0, rel=1e-9)
    assert d["amplitude_m"] == pytest.approx(0.5e-3, rel=1e-9)
    assert d["offset_m"] == pytest.approx(0.0, abs=1e-12)


def test_the_certificate_points_at_the_wrong_sign_hold_first(reference_axial):
    with BatchEvaluator(wrong_sign_hybrid(), reference_axial, "rig") as ev:
        res = CertificateSearch(batch_size=8).run(ev, 16, seed=0)
    assert res.diverged and res.first_failure.evaluation == 1
    assert res.first_failure.family == "step"
    assert "static" in res.first_failure.verdict["criteria"]


def test_a_model_the_certificates_cannot_read_is_swept_and_the_control_stays_clean(
    reference_axial,
):
    with BatchEvaluator(LinearBushing.preset("axial"), reference_axial, "rig") as ev:
        proposals = CertificateSearch().proposals(ev)
        res = CertificateSearch().run(ev, 64, seed=0)
    assert {name for name, _ in proposals} == {"step", "sine"}
    assert res.evaluations == 64 and not res.diverged


def test_the_search_is_deterministic_and_refuses_the_quarter_car(reference_axial):
    model = wrong_sign_hybrid()
    runs = []
    for _ in range(2):
        with BatchEvaluator(model, reference_axial, "rig") as ev:
            res = CertificateSearch(batch_size=16).run(ev, 40, seed=3)
        runs.append([h[1] for h in res.history])
    assert np.array_equal(runs[0], runs[1])
    with BatchEvaluator(model, reference_axial, "quartercar") as ev:
        with pytest.raises(SearchError, match="quartercar"):
            CertificateSearch().run(ev, 8)
