"""HalfCarBatch's generated sub-step kernel and its result keys."""

from __future__ import annotations

import numpy as np
import pytest

from bushenv.rigs.common import RigError
from bushenv.rigs.halfcar_batch import HalfCarBatch
from bushenv.rigs.halfcar_batch_kernels import LATERAL, SPRING, TYRE
from bushenv.rigs.halfcar_batch_lanes import kernel_source
from bushenv.rigs.halfcar_batch_layout import layout
from bushenv.rigs.halfcar_batch_outputs import MODEL_KEYS, RESULT_KEYS


def test_the_kernel_source_is_the_same_for_the_same_table_and_names_its_width():
    t = layout(HalfCarBatch(1).params, "model")
    args = (t.kind, t.ia, t.ib, t.side, t.m_inv != 0, 10)
    assert kernel_source(*args) == kernel_source(*args)
    assert "one vector of 8 cars" in kernel_source(*args, width=8)
    assert kernel_source(*args, width=16) != kernel_source(*args, width=8)


def test_a_lateral_tyre_before_its_tyre_is_refused():
    kind, ia, ib, side = [SPRING, LATERAL, TYRE], [0, 3, 3], [1, 4, 4], [0, 0, 0]
    with pytest.raises(ValueError, match="lateral tyre before its tyre"):
        kernel_source(kind, ia, ib, side, np.array([True] * 4 + [False]), 10)


def test_without_twins_simulate_gives_every_key_a_step_gives():
    inputs = {"road_left": 0.01 * np.sin(np.arange(30) / 5.0)}
    batch = HalfCarBatch(2, with_reference=False)
    out = batch.simulate(**inputs)
    assert set(MODEL_KEYS) <= set(out) and not any(k.startswith("reference_") for k in out)
    assert set(batch.step(0.0, 0.0, 0.0)) == set(MODEL_KEYS)
    assert set(HalfCarBatch(2).step(0.0, 0.0, 0.0)) == set(RESULT_KEYS)
    with pytest.raises(RigError, match="unknown output key"):
        batch.simulate(**inputs, keys=["reference_roll_rad"])
