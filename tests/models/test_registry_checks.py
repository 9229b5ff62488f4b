"""Every registered model, every axis, through every check of the model contract
(``bushenv.models.checks``): registering a model is the one step that tests it."""

import pytest

from bushenv.models import AXES, MODELS, get_model, get_reference
from bushenv.models.checks import CHECKS

ENTRIES = [(name, axis) for name in MODELS.names() for axis in AXES]


@pytest.mark.parametrize("check", sorted(CHECKS))
@pytest.mark.parametrize(("name", "axis"), ENTRIES, ids=[f"{n}-{a}" for n, a in ENTRIES])
def test_every_registered_model_keeps_the_contract(name, axis, check):
    # a model with a reference preset is checked as it judges (the rubber without its
    # measurement chain's noise, whose stream is per batch)
    if MODELS[name].reference_preset:
        CHECKS[check](lambda: get_reference(name, axis=axis))
    else:
        CHECKS[check](lambda: get_model(name, axis=axis))


def test_a_model_registered_at_run_time_is_checked_too():
    import numpy as np

    from bushenv.models import ModelEntry
    from bushenv.models.base import BushingModel

    class SharedMemory(BushingModel):
        """k (x - x_previous): a state, and a copy() that shares it (the bug to catch)."""

        name = "shared_memory"
        param_names = ()

        @property
        def n_state(self):
            return 1

        def _advance(self, x, v, out):
            for t in range(x.shape[0]):
                out[t] = 1e6 * (x[t] - self.state[0])
                self.state[0] = x[t]

        def copy(self):
            return self

        @classmethod
        def preset(cls, axis="axial", dt=1 / 204.8):
            return cls(dt)

    with MODELS.temporarily("shared_memory", ModelEntry(SharedMemory, "test")):
        make = lambda: get_model("shared_memory", axis="axial")  # noqa: E731
        with pytest.raises(AssertionError, match="shared_memory: copies share state"):
            CHECKS["copy_is_independent"](make)
        CHECKS["reset_reruns_identically"](make)  # the other checks it passes
        assert np.isfinite(make().simulate(np.zeros(3))).all()
