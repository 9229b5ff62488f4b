"""The one model contract (``bushenv.models.checks``) catches a broken three-axis model too."""

import pytest

from bushenv.models import MODELS, ModelEntry
from bushenv.models.checks import CHECKS


def test_a_broken_three_axis_model_fails_the_contract():
    from bushenv.models.planar_linear import PlanarLinear
    from bushenv.models.registry import Form

    class Drifting(PlanarLinear):
        """Its step and its batched run disagree: a counter outside the state."""

        calls = 0

        def _advance(self, q, v, out):
            super()._advance(q, v, out)
            Drifting.calls += 1
            out += Drifting.calls

    with MODELS.temporarily("drifting", ModelEntry(None, "test", wider={3: Form(Drifting)})):
        assert MODELS["drifting"].coordinate_counts() == (3,)
        with pytest.raises(AssertionError, match="differs from the first"):
            CHECKS["reset_reruns_identically"](Drifting.preset)
