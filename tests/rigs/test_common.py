"""bushenv.rigs.actions: action clean-up and refusal, reset options, numeric profiles."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from bushenv.rigs.actions import check_options, numeric_profile, unit_action, unit_actions
from bushenv.rigs.common import RigError


# ----- unit_action ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "form",
    [
        lambda v: np.array([v], np.float32),
        lambda v: np.array([v], np.float64),
        lambda v: np.array([v], np.float16),
        lambda v: np.array(v),
        lambda v: np.float32(v),
        lambda v: [v],
        lambda v: (v,),
        lambda v: v,
        lambda v: Fraction(v),
        lambda v: np.array([v], dtype=object),
    ],
    ids=["f32", "f64", "f16", "0-d", "np-scalar", "list", "tuple", "float", "fraction", "object"],
)
@pytest.mark.parametrize("value", [0.5, -0.25, 0.0, 1.0, -1.0])
def test_every_form_of_one_real_number_gives_the_same_action(form, value):
    assert unit_action(form(value)) == value


@pytest.mark.parametrize(
    ("action", "expected"),
    [
        (np.array([np.nan], np.float32), 0.0),
        (np.array([np.inf], np.float32), 1.0),
        (np.array([-np.inf]), -1.0),
        (np.array([7], np.int64), 1.0),
        (np.array([253], np.uint8), 1.0),
        (10**400, 1.0),
        ([-(10**400)], -1.0),
        (math.nan, 0.0),
    ],
    ids=repr,
)
def test_numbers_are_cleaned_never_refused(action, expected):
    assert unit_action(action) == expected


@pytest.mark.parametrize(
    "action",
    [
        None,
        "abc",
        "0.5",
        b"0.5",
        1 + 2j,
        np.array([1 + 0j]),
        True,
        np.array([True]),
        {"a": 1},
        [None],
        [[0.1], [0.2, 0.3]],
        np.array([]),
        np.array([0.1, 0.9, -0.9], np.float32),
        np.zeros((1, 1), np.float32),
        np.array(["0.5"]),
        object(),
    ],
    ids=lambda a: type(a).__name__ + (str(getattr(a, "shape", "")) or repr(a)[:12]),
)
def test_anything_but_one_real_number_is_refused_naming_the_space_and_shape(action):
    with pytest.raises(RigError) as info:
        unit_action(action, "BushRig-v0")
    text = str(info.value)
    assert text.startswith("BushRig-v0: action ")
    assert "Box(-1.0, 1.0, (1,), float32)" in text and "shape (1,)" in text
    assert "\n" not in text and len(text) < 300


def test_refusing_a_huge_array_keeps_the_message_short():
    with pytest.raises(RigError) as info:
        unit_action(np.zeros(10**6))
    assert "shape (1000000,)" in str(info.value) and len(str(info.value)) < 300
    with pytest.raises(RigError) as info:
        unit_action("x" * 10**6)
    assert len(str(info.value)) < 300


# ----- unit_actions (vector env) ---------------------------------------------------------------
@pytest.mark.parametrize(
    "actions",
    [
        np.array([[0.5], [np.nan], [-3.0]], np.float32),
        np.array([0.5, np.nan, -3.0]),
        [[0.5], [math.nan], [-3]],
        [0.5, math.nan, -3],
    ],
    ids=["(3,1) f32", "(3,) f64", "nested list", "list"],
)
def test_vector_actions_of_shape_n1_or_n_are_cleaned_alike(actions):
    np.testing.assert_array_equal(unit_actions(actions, 3), [0.5, 0.0, -1.0])


def test_vector_actions_are_not_modified_in_place():
    a = np.array([[np.nan], [2.0]], np.float32)
    unit_actions(a, 2)
    assert np.isnan(a[0, 0]) and a[1, 0] == 2.0


@pytest.mark.parametrize(
    "actions",
    [
        np.zeros((2, 1), np.float32),
        np.zeros((4, 1), np.float32),
        np.zeros((3, 2), np.float32),
        np.zeros((1, 3), np.float32),
        np.zeros((3, 1, 1), np.float32),
        None,
        "abc",
        [[0.1], [0.2], ["x"]],
        np.zeros((3, 1), complex),
    ],
    ids=lambda a: type(a).__name__ + str(getattr(a, "shape", "")),
)
def test_vector_actions_of_another_shape_or_not_numbers_are_refused_naming_n1(actions):
    with pytest.raises(RigError, match=r"BushRig-v0: actions .* shape \(3, 1\)"):
        unit_actions(actions, 3, "BushRig-v0")


# ----- options and profiles -----------------------------------------------------------------------
@pytest.mark.parametrize("options", [5, "excitation", [("excitation", [0.0])], np.zeros(3)])
def test_reset_options_other_than_a_dict_are_refused(options):
    with pytest.raises(RigError, match=r"BushRig-v0: reset options must be a dict"):
        check_options("BushRig-v0", options)


def test_reset_options_none_is_an_empty_dict():
    assert check_options("X", None) == {}
    assert check_options("X", {"excitation": None}) == {"excitation": None}


@pytest.mark.parametrize(
    "profile", ["abc", "0.1", ["0.1", "0.2"], [0.0, None], [[0.0], [0.0, 1.0]], [True, False]]
)
def test_profiles_that_are_not_numbers_are_refused_naming_them(profile):
    with pytest.raises(RigError, match=r"^excitation must be numbers"):
        numeric_profile("excitation", profile)


def test_numeric_profiles_become_float64_copies():
    src = np.arange(4, dtype=np.int32)
    out = numeric_profile("excitation", src)
    assert out.dtype == np.float64 and out.tolist() == [0.0, 1.0, 2.0, 3.0]
    out[0] = 9.0
    assert src[0] == 0
