"""Registries: one list per kind of thing; an entry added at run time is seen everywhere."""

import numpy as np
import pytest

from bushenv.models import MODELS, ModelEntry, ModelError, get_model, get_reference, load_model
from bushenv.models.linear import LinearBushing
from bushenv.registry import Registry, load_entry_point


class Stiff(LinearBushing):
    """A dummy model for the registry tests: a linear bushing registered under another name."""

    name = "stiff"

    @classmethod
    def preset(cls, axis="axial", dt=1 / 204.8):
        return cls(k_n_per_m=1e6, c_ns_per_m=0.0, dt=dt)


def test_unknown_name_lists_the_known_names_in_registration_order():
    reg = Registry("thing", ValueError)
    reg.add("b", 1)
    reg.add("a", 2)
    with pytest.raises(ValueError, match="unknown thing 'c'; known names: b, a"):
        reg["c"]
    assert reg.names() == ("b", "a")


def test_a_name_is_registered_once_unless_replaced():
    reg = Registry("thing", ValueError)
    reg.add("a", 1)
    with pytest.raises(ValueError, match="registered already"):
        reg.add("a", 2)
    reg.add("a", 3, replace=True)
    assert reg["a"] == 3
    with pytest.raises(ValueError, match="non-empty"):
        reg.add(" a", 4)


def test_temporarily_registers_inside_the_block_only():
    reg = Registry("thing", ValueError)
    with reg.temporarily("x", 1):
        assert "x" in reg
    assert "x" not in reg


def test_entry_points_are_module_colon_attribute():
    assert load_entry_point("bushenv.models.linear:LinearBushing") is LinearBushing
    with pytest.raises(ValueError, match="module:attribute"):
        load_entry_point("bushenv.models.linear.LinearBushing")


def test_every_registered_model_class_has_the_registered_name():
    # a preset of another class (nn-paper: an nn network trained the papers' way) names it
    for name, entry in MODELS.items():
        for c in entry.coordinate_counts():
            assert entry.model_class(c).name == (entry.kind or name), (name, c)
        if entry.kind is not None:
            assert entry.kind in MODELS and MODELS[entry.kind].kind is None


def test_a_model_registered_at_run_time_resolves_saves_and_loads(tmp_path):
    with MODELS.temporarily("stiff", ModelEntry(Stiff, "test dummy")):
        m = get_model("stiff")
        assert isinstance(m, Stiff)
        path = m.save(tmp_path / "stiff.npz")
        again = load_model(path)
        assert isinstance(again, Stiff) and again.k_n_per_m == 1e6
        assert get_reference("stiff").k_n_per_m == 1e6
    with pytest.raises(ModelError, match="unknown model 'stiff'"):
        get_model("stiff")


def test_get_model_copies_objects_unless_told_not_to():
    m = get_model("linear")
    c = get_model(m)
    assert c is not m and c.k_n_per_m == m.k_n_per_m
    assert get_model(m, copy=False) is m


def test_the_rubber_reference_has_no_measurement_chain_but_the_model_does():
    ref = get_reference("rubber", axis="axial")
    measured = get_model("rubber", axis="axial")
    assert "noise" not in ref.effects and "noise" in measured.effects
    x = np.zeros(50)
    x[10:] = 1e-3
    assert np.all(np.isfinite(ref.simulate(x)))


def test_no_silent_fallback_for_an_unknown_reference():
    with pytest.raises(ModelError, match="unknown model 'rubbr'"):
        get_reference("rubbr")
