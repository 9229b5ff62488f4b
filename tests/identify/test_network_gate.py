"""A hybrid keeps its network only when the network beats its backbone alone on the validation
tails of the training records (``--network if-better``, the default)."""

import numpy as np
import pytest

from bushenv.identify import fit
from bushenv.identify.mimo_options import MimoOptions as TrainOptions
from bushenv.identify.mimo_train import fit_mimo
from bushenv.models.base import PAPER_DT
from bushenv.models.planar_linear import PlanarLinear
from bushenv.motions import random_correlated
from bushenv.reference.planar import PlanarRubber

OPT = TrainOptions(hidden=9, teacher_steps=100, free_run_steps=25, windows=8, window=32)


@pytest.fixture(scope="module")
def q():
    return random_correlated(1.0, 12.0, PAPER_DT, 3)


def _misleading(q):
    """Linear force, plus a static law in the first 80 % only: the tails do not have it."""
    f = PlanarLinear.preset().simulate(q)
    n = int(0.8 * len(q))
    f[:n] += 300.0 * np.tanh(q[:n] / (0.5 * np.abs(q).max(axis=0)))
    return f


def test_a_network_worse_than_its_backbone_on_the_tails_is_dropped(q):
    f = _misleading(q)
    gated = fit_mimo(q, f, PAPER_DT, "hybrid", OPT, seed=1, may_drop=True)
    gate = gated.training["network"]
    assert gate["dropped"] and gate["backbone_alone"] < gate["with_network"]
    # the model is then its backbone alone, to round-off
    alone = gated.backbone_alone().simulate(q)
    np.testing.assert_allclose(gated.simulate(q), alone, rtol=0, atol=1e-9)
    kept = fit_mimo(q, f, PAPER_DT, "hybrid", OPT, seed=1)  # no gate: kept as trained
    assert "network" not in getattr(kept, "training", {})
    assert np.abs(kept.simulate(q) - alone).max() > 10.0


def test_a_network_that_helps_is_kept(q):
    f = PlanarRubber.preset(seed=3).simulate(q)
    model = fit_mimo(q, f, PAPER_DT, "hybrid", OPT, seed=1, may_drop=True)
    gate = model.training["network"]
    assert not gate["dropped"] and gate["with_network"] < 0.9 * gate["backbone_alone"]


@pytest.mark.parametrize("given, dropped", [({}, True), ({"network": "always"}, False)])
def test_the_fit_says_which_and_always_keeps_it(q, given, dropped):
    opts = {"hidden": 9, "teacher_steps": 100, "free_run_steps": 25, "windows": 8, "window": 32}
    result = fit([(q, _misleading(q))], "hybrid", {**opts, **given}, 1, False, dt=PAPER_DT)
    if dropped:
        assert result.info["network"].startswith("DROPPED (the backbone alone is the model)")
    else:
        assert "network" not in result.info


def test_hybrid_bw_drops_a_network_that_does_not_help(q):
    f = _misleading(q)
    opts = {"hidden": 9, "teacher_steps": 100, "free_run_steps": 25, "windows": 8, "window": 32,
            "evaluations": 4, "time_limit_s": 0.0}  # fmt: skip
    result = fit([(q, f)], "hybrid-bw", opts, 1, False, dt=PAPER_DT)
    assert result.info["network"].startswith("DROPPED")
    model = result.model
    np.testing.assert_allclose(
        model.simulate(q), model.backbone_alone().simulate(q), rtol=0, atol=1e-9
    )
