"""The divergences search found (tests/regressions/corpus) are explained by the certificate.

Energy failures of a NARX model on the rig: the profile's dominant frequency lies in the
model's linearised non-passive band. Deviation or self-sustained failures that end in a hold:
the certificate at that hold says the static force has the wrong sign, the run departs, or
the held fixed point is unstable and the run oscillates.
"""

from pathlib import Path

import numpy as np
import pytest

from bushenv.certify import CertifyOptions, certify, non_passive_bands
from bushenv.models import get_model
from bushenv.models.narx import NarxBushing
from bushenv.search.corpus import case_files, load_case, model_sha, model_spec, truth_reference

CORPUS = Path(__file__).resolve().parents[1] / "regressions" / "corpus"


def _failures():
    # the shipped nn / hybrid, and the older NARX model files cases keep (../models/*.npz)
    for path in case_files(CORPUS):
        case = load_case(path)
        for name, verdict in case.expect.items():
            spec = model_spec(case, name)
            narx = isinstance(get_model(spec, axis=case.axis, dt=case.dt), NarxBushing)
            if narx and verdict["diverged"] and case.env == "rig":
                yield pytest.param(case, name, verdict["criterion"], id=f"{case.name}:{name}")


def _shipped(case, name):
    spec = model_spec(case, name)
    if model_sha(spec, case.axis) != case.expect[name]["sha256"]:
        pytest.skip(f"the {name} model ({case.axis}) is not the model this case was found on")
    return get_model(spec, axis=case.axis, dt=case.dt)


@pytest.mark.parametrize("case,name,criterion", list(_failures()))
def test_every_search_found_rig_failure_of_a_narx_model_is_explained(case, name, criterion):
    model = _shipped(case, name)
    x = case.profile
    if criterion == "energy":
        spectrum = np.abs(np.fft.rfft(x - x.mean()))
        peak_hz = np.fft.rfftfreq(x.size, case.dt)[np.argmax(spectrum)]
        bands = non_passive_bands(model, 0.0)
        assert any(lo <= peak_hz <= hi for lo, hi in bands), (peak_hz, bands)
        return
    moves = np.abs(np.diff(x[::-1])) > 1e-12
    held = int(np.argmax(moves)) if moves.any() else x.size  # a constant profile: all hold
    assert held * case.dt >= 0.5, "a non-energy failure that does not end in a hold"
    hold = float(x[-1])
    opts = CertifyOptions(
        holds=3,
        stroke_m=abs(hold) or 1e-3,  # holds at -s, 0, +s: the failing hold is one of them
        passivity_holds_m=(0.0,),
        reference_freq_hz=(10.0,),
        energy_amplitudes_m=(1e-3,),
        energy_freq_hz=(10.0,),
    )
    cert = certify(model, truth_reference(case.axis, case.dt), opts)
    h = cert.document["holds"][1 if hold == 0 else 2 if hold > 0 else 0]
    assert h["x_m"] == pytest.approx(hold)
    assert h["wrong_sign"] or h["departs"] or h["oscillates"], h
