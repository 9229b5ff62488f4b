"""narx_precision.py: the numpy NARX free run is the kernels' model, in any dtype."""

import numpy as np
import pytest
from narx_precision import float32_error, narx_free_run_numpy

from bushenv.excitation import random_rpc
from bushenv.models import get_model


def drives(model, n_index, seconds=3.0, batch=4):
    x = np.stack([random_rpc(n_index, seconds, model.dt, seed=b) for b in range(batch)], 1)
    return x, np.gradient(x, model.dt, axis=0)


@pytest.mark.parametrize("name", ["nn", "hybrid"])
@pytest.mark.parametrize("axis", ["axial", "radial"])
def test_float64_numpy_run_is_the_compiled_model(name, axis):
    model = get_model(name, axis=axis)
    x, v = drives(model, 1.5)
    model.reset(x.shape[1])
    compiled = model.simulate(x, v)
    f64 = narx_free_run_numpy(model, x, v, np.float64)
    assert f64.dtype == np.float64
    # np.tanh (libm) against the kernels' arithmetic tanh (within 1e-14): rounding only
    assert np.max(np.abs(f64 - compiled)) < 1e-11 * np.max(np.abs(compiled))


def test_float32_run_is_single_precision_and_close_but_not_equal():
    model = get_model("nn", axis="radial")
    x, v = drives(model, 1.0)
    f32 = narx_free_run_numpy(model, x, v, np.float32)
    assert f32.dtype == np.float32
    err = float32_error(model, x, v)
    assert 0.0 < err < 1e-4  # measured ~5e-7 of the peak on 20 s records (docs/benchmarks.md)


def test_shapes_that_do_not_match_are_refused():
    model = get_model("nn", axis="axial")
    x, v = drives(model, 1.0, seconds=0.5)
    with pytest.raises(ValueError, match=r"\(T, B\) arrays of one shape"):
        narx_free_run_numpy(model, x, v[:, :2], np.float32)
