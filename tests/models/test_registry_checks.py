"""Every registered model, every form (one coordinate on each axis, three coordinates), through
every check of the model contract (``bushenv.models.checks``): registering a model is the one
step that tests it."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bushenv.models import MODELS, get_model
from bushenv.models.checks import CHECKS, drive, example, forms

FORMS = forms()


def checked_model(name, axis="axial", coords=1):
    return example(name, coords, axis or "axial")


@pytest.mark.parametrize("check", sorted(CHECKS))
@pytest.mark.parametrize(
    ("name", "coords", "axis"), FORMS, ids=[f"{n}-{c}{'-' * bool(a)}{a}" for n, c, a in FORMS]
)
def test_every_registered_model_keeps_the_contract(name, coords, axis, check):
    CHECKS[check](lambda: checked_model(name, axis, coords))


def test_every_form_of_three_coordinates_is_checked():
    three = {n for n, c, _ in FORMS if c == 3}
    assert {"linear", "nn", "nn-axis", "hybrid", "boucwen", "hybrid-bw", "rubber"} <= three


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), batch=st.integers(1, 5), form=st.sampled_from(FORMS))
def test_any_batch_equals_its_columns_run_alone(seed, batch, form):
    name, coords, axis = form
    m = checked_model(name, axis, coords)
    x, v = drive(40, batch, seed, m.dt, m.units)
    batched = m.simulate(x, v)
    for b in range(batch):
        assert np.array_equal(batched[:, b], m.simulate(x[:, b], v[:, b])), name


def test_a_model_without_files_or_preset_is_refused_with_the_fix():
    from bushenv.models import ModelEntry, ModelError
    from bushenv.models.base import BushingModel

    class Bare(BushingModel):
        name = "bare"

        def _advance(self, x, v, out):
            out[:] = 0.0

    with MODELS.temporarily("bare", ModelEntry(Bare, "test")):
        with pytest.raises(ModelError, match="'bare' has no preset: give it a preset"):
            get_model("bare")


def test_a_model_registered_at_run_time_is_checked_too():
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
