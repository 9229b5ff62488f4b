"""``CoordinateLimits``: one limits type over any number of coordinates, each with its name and
unit; BushRig3-v0's stroke and rate bound it over that rig's coordinates only; a bad value is
named by coordinate, unit and value; the report's keys keep each coordinate's unit."""

import numpy as np
import pytest

from bushenv.search.base import SearchError
from bushenv.search.limits import (
    COORDS,
    CoordinateLimits,
    clip_coords,
    finish_coords,
    limits_of_records,
    limits_text,
    machine_limits,
    machine_of,
    rig3_limits,
)

SIX = ("x", "y", "z", "rx", "ry", "rz")
SIX_UNITS = ("m", "m", "m", "rad", "rad", "rad")


@pytest.mark.parametrize(
    "coords,units",
    [(("axial",), ("m",)), (COORDS, ("m", "m", "rad")), (SIX, SIX_UNITS)],
)
def test_one_type_over_one_three_and_six_coordinates(coords, units):
    c = len(coords)
    stroke = tuple(1e-3 * (i + 1) for i in range(c))
    rate = tuple(0.1 * (i + 1) for i in range(c))
    lim = CoordinateLimits(stroke, rate, "given", None, coords, units)
    assert lim.n_coords == c and lim.coords == coords and lim.units == units
    assert lim.machine == machine_of(coords)
    doc = lim.to_json()
    for name, unit in zip(coords, units, strict=True):
        shown = "mm" if unit == "m" else "mrad"
        assert set(doc[name]) == {f"stroke_{shown}", f"rate_{unit}_per_s"}
    text = limits_text(doc)
    assert text.count(" +-") == c and text.endswith("(given)")
    dt = 1e-3
    q = finish_coords(np.ones((50, c)), dt, 1.0, lim)
    assert q.shape[1] == c and np.all(q[0] == 0)
    assert np.all(np.max(np.abs(q), axis=0) <= np.array(stroke) * (1 + 1e-12))
    assert np.all(np.max(np.abs(np.diff(q, axis=0)), axis=0) / dt <= np.array(rate) * (1 + 1e-9))
    assert clip_coords(np.ones((5, c)), dt, lim).shape == (5, c)


def test_the_rig3_limits_keep_the_report_keys_and_the_machine_tops():
    doc = machine_limits().to_json()
    assert set(doc["axial"]) == {"stroke_mm", "rate_m_per_s"}
    assert set(doc["rotation"]) == {"stroke_mrad", "rate_rad_per_s"}
    top_stroke = rig3_limits()[0]
    beyond = (top_stroke[0], top_stroke[1], 1.5 * top_stroke[2])
    with pytest.raises(SearchError, match=r"rotation stroke must be in \(0, 150\] mrad") as err:
        CoordinateLimits(beyond, machine_limits().rate)
    assert "BushRig3-v0's" in str(err.value) and f"{1.5e3 * top_stroke[2]:.6g} mrad" in str(
        err.value
    )
    # six coordinates have no machine: only positive and finite
    CoordinateLimits((1.0,) * 6, (100.0,) * 6, "big", None, SIX, SIX_UNITS)


@pytest.mark.parametrize(
    "kwargs,needle",
    [
        ({"stroke": (1e-3, -2e-3)}, "the b stroke must be > 0, got -2 mrad"),
        ({"rate": (0.1, float("nan"))}, "the b rate must be > 0, got nan rad/s"),
        ({"stroke": (1e-3,)}, "stroke needs 2 values (a, b)"),
        ({"units": ("m", "deg")}, "unit is m or rad, got 'deg'"),
    ],
)
def test_a_bad_limit_names_its_coordinate_unit_and_value(kwargs, needle):
    given = {"stroke": (1e-3, 2e-3), "rate": (0.1, 0.2), "source": "s", "records_peak": None,
             "coords": ("a", "b"), "units": ("m", "rad")}  # fmt: skip
    with pytest.raises(SearchError) as err:
        CoordinateLimits(**(given | kwargs))
    assert needle in str(err.value)


def test_limits_of_records_over_a_coordinate_set_without_machine():
    q = [np.column_stack([np.linspace(0, 2e-3, 100), np.linspace(0, 0.04, 100)])]
    lim = limits_of_records(q, 1e-3, "two records", ("a", "b"), ("m", "rad"))
    assert lim.machine is None and lim.coords == ("a", "b")
    assert np.allclose(lim.stroke, (3e-3, 0.06)) and np.allclose(lim.records_peak, (2e-3, 0.04))
    still = [np.column_stack([np.linspace(0, 2e-3, 100), np.zeros(100)])]
    with pytest.raises(SearchError, match="never move b"):
        limits_of_records(still, 1e-3, "the records", ("a", "b"), ("m", "rad"))


class _Spring:
    """A linear spring over any coordinates, f = K q (the static-stiffness probe's view)."""

    def __init__(self, k, coords, units):
        self.k, self.coords, self.units = np.asarray(k, dtype=float), coords, units
        self.n_coords, self.dt = len(coords), 1e-3

    def copy(self):
        return self

    def simulate(self, q):
        return np.asarray(q) * self.k


def test_force_floors_over_coordinates_without_a_builtin_reference_follow_the_one_axis_rule():
    from bushenv.scales import FLOOR_AMPLITUDE_M
    from bushenv.search.targets import reference_floors

    spring = _Spring([4e5, 2e3], ("x", "rz"), ("m", "rad"))
    floors, source = reference_floors(spring)
    assert floors == pytest.approx([4e5 * FLOOR_AMPLITUDE_M, 2e3 * FLOOR_AMPLITUDE_M / 0.04])
    assert "x 4e+05, rz 2000" in source and "0.5 mm" in source
    with pytest.raises(SearchError, match="static stiffness in rz is not a positive number"):
        reference_floors(_Spring([4e5, -1.0], ("x", "rz"), ("m", "rad")))
