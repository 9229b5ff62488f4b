"""Torch training of the NARX models: loss goes down, seeds reproduce, numba == torch."""

import numpy as np
import pytest
from standin import DT, standin_drive, standin_force

from bushenv.identify import fit_model
from bushenv.identify.neural import torch_free_run
from bushenv.metrics import rms_ratio
from bushenv.models.hybrid import HybridBushing
from bushenv.models.narx import NarxBushing

QUICK = dict(
    teacher_steps=150,
    window_lengths=(10, 30),
    iters_per_length=(20, 20),
    batch_windows=8,
    eval_every=10,
)


@pytest.fixture(scope="module")
def record():
    x = standin_drive(6.0, seed=0)
    return x, standin_force(x)


@pytest.mark.parametrize("kind", ["nn", "hybrid"])
def test_quick_training_lowers_the_losses(kind, record):
    x, f = record
    m = fit_model(kind, x, f, DT, seed=0, progress=False, **QUICK)
    tr = m.training
    assert tr["teacher_losses"][-1] < 0.7 * tr["teacher_losses"][0]
    assert tr["best_validation_rms_ratio"] <= tr["validation_after_teacher"]
    assert tr["best_validation_rms_ratio"] < 0.5
    assert isinstance(m, HybridBushing if kind == "hybrid" else NarxBushing)


def test_same_seed_same_weights_other_seed_other_weights(record):
    x, f = record
    a = fit_model("nn", x, f, DT, seed=1, progress=False, **QUICK)
    b = fit_model("nn", x, f, DT, seed=1, progress=False, **QUICK)
    c = fit_model("nn", x, f, DT, seed=2, progress=False, **QUICK)
    for name in ("w1", "b1", "w_out"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert not np.array_equal(a.w1, c.w1)


@pytest.mark.parametrize("kind,hidden", [("nn", (9,)), ("nn", (10, 9)), ("hybrid", (9,))])
def test_numba_free_run_equals_torch_free_run_of_the_same_weights(kind, hidden, record):
    x, f = record
    m = fit_model(kind, x, f, DT, seed=0, progress=False, hidden=hidden, **QUICK)
    xv = standin_drive(5.0, seed=7, peak_m=0.003)
    numba_f = m.simulate(xv)
    torch_f = torch_free_run(m, xv)
    assert np.max(np.abs(numba_f - torch_f)) < 1e-9 * np.max(np.abs(torch_f))


def test_progress_lines_are_printed(record, capsys):
    x, f = record
    fit_model("nn", x, f, DT, seed=0, progress=True, progress_every_s=0.0, **QUICK)
    out = capsys.readouterr().out
    assert "teacher forcing done" in out and "best validation free-run RMS ratio" in out


def test_unknown_training_option_is_refused(record):
    x, f = record
    with pytest.raises(ValueError, match="unknown options"):
        fit_model("nn", x, f, DT, progress=False, epochs=3)


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["nn", "hybrid"])
def test_full_training_on_reference_rubber_free_runs_near_paper_accuracy_on_n15(kind):
    # seed 000 Table 2 / seed 001 §4: identify on n = 1, verify in free run on n = 1.5.
    from bushenv.machine import random_test
    from bushenv.reference.rubber import RubberBushing

    ref = RubberBushing.preset("axial")
    ident = random_test(ref, 1.0, seed=0)
    verify = random_test(ref, 1.5, seed=1)
    m = fit_model(kind, ident.displacement, ident.force, ref.dt, seed=0, progress=False)
    assert rms_ratio(verify.force, m.simulate(verify.displacement)) < 0.10
