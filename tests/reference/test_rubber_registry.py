"""The reference's effects have one registry; every list of names derives from it."""

from bushenv.reference import rubber


def test_effect_lists_and_parameters_derive_from_the_one_registry():
    reg = rubber.REFERENCE_EFFECTS
    assert rubber.EFFECTS == tuple(reg)
    assert set(rubber.PHYSICAL_EFFECTS) | set(rubber.MEASUREMENT_EFFECTS) == set(reg)
    assert all(reg[e].kind == "physical" for e in rubber.PHYSICAL_EFFECTS)
    assert rubber.EFFECT_PARAMS == {n: e.params for n, e in reg.items()}
    for e in reg.values():
        assert all(p in rubber.RubberBushing.param_names for p in e.params)


def test_an_effect_is_configured_exactly_when_its_registry_entry_says_so():
    full = rubber.RubberBushing.preset("axial")
    for name, entry in rubber.REFERENCE_EFFECTS.items():
        assert entry.configured(full), name
    bare = rubber.RubberBushing(k_n_per_m=1e5, c_ns_per_m=1e3)
    assert bare.effects == ()
    assert not any(e.configured(bare) for e in rubber.REFERENCE_EFFECTS.values())
