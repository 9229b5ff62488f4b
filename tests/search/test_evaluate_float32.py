"""BatchEvaluator(dtype="float32"): the NARX model in single precision, verdicts as in float64."""

import numpy as np
import pytest

from bushenv.models import get_model
from bushenv.search.corpus import truth_reference
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.families import get_family

from .conftest import old_nn


@pytest.fixture(scope="module")
def profiles_and_reference():
    ref = truth_reference("radial")
    fam = get_family("any")
    rng = np.random.default_rng(7)
    return [fam.profile(rng.random(fam.dim), ref.dt) for _ in range(256)], ref


def test_float32_evaluation_keeps_the_verdicts_and_nearly_the_forces(profiles_and_reference):
    profiles, ref = profiles_and_reference
    nn = get_model(old_nn("radial"), axis="radial", dt=ref.dt)  # it fails on some of them
    with BatchEvaluator(nn, ref) as ev64, BatchEvaluator(nn, ref, dtype="float32") as ev32:
        r64, r32 = ev64.evaluate(profiles), ev32.evaluate(profiles)
    assert np.asarray(r64.verdict.diverged).any()  # the batch holds failures to agree on
    assert np.array_equal(r64.verdict.diverged, r32.verdict.diverged)
    assert r32.f_model.dtype == np.float64
    assert not np.array_equal(r32.f_model, r64.f_model)  # it did run in float32
    assert np.max(np.abs(r32.f_model - r64.f_model)) < 1e-5 * np.max(np.abs(r64.f_model))
    assert np.array_equal(r32.f_ref, r64.f_ref)  # the reference stays float64


@pytest.mark.parametrize(
    ("model", "env", "message"),
    [
        ("boucwen", "rig", "not 'boucwen' on the rig"),
        ("nn", "quartercar", "not 'nn' on the quartercar"),
    ],
)
def test_float32_is_refused_where_there_is_no_float32_path(
    profiles_and_reference, model, env, message
):
    _, ref = profiles_and_reference
    with pytest.raises(ValueError, match=message):
        BatchEvaluator(get_model(model, axis="radial", dt=ref.dt), ref, target=env, dtype="float32")


def test_unknown_dtype_is_refused(profiles_and_reference):
    _, ref = profiles_and_reference
    with pytest.raises(ValueError, match="dtype must be 'float64' or 'float32', got 'float16'"):
        BatchEvaluator(get_model("nn", axis="radial", dt=ref.dt), ref, dtype="float16")
