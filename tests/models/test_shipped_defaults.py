"""The identified default models shipped in bushenv/data/models (train_default_models.py)."""

import numpy as np
import pytest

from bushenv.metrics import rms_ratio
from bushenv.models import PAPER_DT, default_model_path, get_model

# Free-run RMS ratio on the n = 1.5 verification record, as measured when the files were made,
# with headroom; a failure means the reference bushing changed and the models need retraining.
LIMITS = {"nn": 0.12, "hybrid": 0.07, "boucwen": 0.07}


@pytest.mark.parametrize("axis", ["axial", "radial"])
@pytest.mark.parametrize("name", sorted(LIMITS))
def test_shipped_default_loads_by_name_and_runs_at_paper_rate(name, axis):
    assert default_model_path(name, axis).is_file()
    m = get_model(name, axis=axis)
    assert m.name == name and m.dt == pytest.approx(PAPER_DT)
    t = np.arange(400) * PAPER_DT
    f = m.simulate(0.002 * np.sin(2 * np.pi * 5 * t))
    assert np.all(np.isfinite(f)) and np.max(np.abs(f)) > 100.0


@pytest.mark.parametrize("axis", ["axial", "radial"])
@pytest.mark.parametrize("name", sorted(LIMITS))
def test_shipped_default_free_runs_the_n15_verification_record(name, axis):
    from bushenv.machine import random_test
    from bushenv.reference.rubber import RubberBushing

    verify = random_test(RubberBushing.preset(axis), 1.5, seed=1)  # as the training script
    pred = get_model(name, axis=axis).simulate(verify.displacement)
    assert rms_ratio(verify.force, pred) < LIMITS[name]
