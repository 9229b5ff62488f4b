import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bushenv import excitation as ex
from bushenv.models.base import PAPER_DT as DT
from bushenv.search.families import FAMILIES, get_family, pad_batch
from bushenv.search.family_base import (
    MAX_PROFILE_S,
    MIN_HOLD_S,
    ROAD_MAX_HEIGHT_M,
    ROAD_MAX_RATE_M_PER_S,
    FamilyError,
)
from bushenv.search.targets import TARGETS

RIG_FAMILIES = TARGETS["rig"].family_names()
ROAD_FAMILIES = TARGETS["quartercar"].family_names()

unit = st.floats(0.0, 1.0)


@settings(max_examples=300, deadline=None)
@given(name=st.sampled_from(RIG_FAMILIES), u=st.lists(unit, min_size=24, max_size=24))
def test_every_rig_profile_is_within_the_machine_limits_starts_at_rest_and_ends_held(name, u):
    fam = FAMILIES[name]
    x = fam.profile(np.asarray(u[: fam.dim]))
    ok, why = ex.within_limits(x, DT)
    assert ok, (fam.describe(np.asarray(u[: fam.dim])), why)
    assert x[0] == 0.0
    assert x.size <= round(MAX_PROFILE_S / DT)
    n_hold = int(round(MIN_HOLD_S / DT)) - 1
    assert np.all(x[-n_hold:] == x[-1])


@settings(max_examples=100, deadline=None)
@given(name=st.sampled_from(ROAD_FAMILIES), u=st.lists(unit, min_size=5, max_size=5))
def test_road_profiles_start_flat_and_stay_within_obstacle_height(name, u):
    fam = FAMILIES[name]
    h = fam.profile(np.asarray(u[: fam.dim]))
    assert h[0] == 0.0 and h[-1] == 0.0
    assert np.all(np.isfinite(h)) and np.max(np.abs(h)) <= ROAD_MAX_HEIGHT_M + 1e-12
    assert np.max(np.abs(np.diff(h))) <= ROAD_MAX_RATE_M_PER_S * DT * (1 + 1e-9)


def test_step_family_reaches_the_papers_4mm_step():
    fam = get_family("step")
    u = np.array([(4e-3 + 12.5e-3) / 25e-3, 0.0, 0.0, 1.0])
    params = fam.describe(u)
    assert params["size_m"] == pytest.approx(4e-3)
    x = fam.profile(u)
    assert x[-1] == pytest.approx(4e-3) and params["hold_s"] > 7.3


def test_random_ood_goes_beyond_the_training_amplitude_and_band():
    fam = get_family("random_ood")
    p = fam.describe(np.array([1.0, 1.0, 1.0, 0.5, 1.0, 0.3, 0.0]))
    assert p["n_index"] > 1.0 and p["band_hz"][1] > 20.0


def test_profiles_are_pure_functions_of_the_parameters():
    rng = np.random.default_rng(0)
    for name, fam in FAMILIES.items():
        u = rng.random(fam.dim)
        assert np.array_equal(fam.profile(u), fam.profile(u.copy())), name


def test_any_family_picks_each_family_with_its_first_coordinate():
    fam = get_family("any")
    rest = np.full(fam.dim - 1, 0.5)
    picked = {fam.describe(np.r_[k / 6 + 0.01, rest])["family"] for k in range(6)}
    assert picked == {"step", "ramp", "pulse", "sine", "chirp", "random_ood"}


def test_wrong_parameter_count_and_unknown_family_are_refused():
    with pytest.raises(FamilyError, match="step.*4 parameters"):
        get_family("step").profile(np.zeros(3))
    with pytest.raises(FamilyError, match="unknown excitation family 'nope'"):
        get_family("nope")


def test_pad_batch_holds_the_last_value_and_reports_lengths():
    x, lengths = pad_batch([np.array([0.0, 1.0]), np.array([0.0, 2.0, 3.0, 4.0])])
    assert list(lengths) == [2, 4]
    assert list(x[:, 0]) == [0.0, 1.0, 1.0, 1.0]
