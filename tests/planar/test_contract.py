"""Every PLANAR_MODELS entry passes the planar contract (bushenv/planar/checks.py)."""

import pytest

from bushenv.planar import PLANAR_MODELS
from bushenv.planar.checks import check_planar_model, example


@pytest.mark.parametrize("name", PLANAR_MODELS.names())
def test_registered_planar_model_meets_the_contract(name, tmp_path):
    check_planar_model(example(name), tmp_path)


def test_a_broken_model_fails_the_contract(tmp_path):
    from bushenv.planar.linear import PlanarLinear

    class Drifting(PlanarLinear):
        """Its step and its batched run disagree: a counter outside the state."""

        calls = 0

        def _advance(self, q, v, out):
            super()._advance(q, v, out)
            Drifting.calls += 1
            out += Drifting.calls

    with PLANAR_MODELS.temporarily("drifting", Drifting):
        with pytest.raises(AssertionError, match="step loop differs"):
            check_planar_model(Drifting.preset(), tmp_path)
