"""Plausibility limits are checks a person can override; units in the header convert to SI."""

import numpy as np
import pytest

from bushenv.records import RecordError, load_csv

ROWS = "0,0,0\n0.02,0.12,0.5\n0.04,0.10,0.4\n"


def write(tmp_path, header, rows=ROWS):
    path = tmp_path / "pull.csv"
    path.write_text(header + "\n" + rows)
    return path


def test_a_metres_scale_record_is_refused_with_both_ways_to_accept_it(tmp_path):
    path = write(tmp_path, "time,displacement,force")
    with pytest.raises(RecordError, match=r"line 3: displacement 0\.12 m exceeds 0\.1 m") as exc:
        load_csv(path)
    assert "max_displacement_m=0.5" in str(exc.value) and "displacement [m]" in str(exc.value)
    assert load_csv(path, max_displacement_m=0.5).displacement[1] == 0.12


def test_units_in_the_header_are_converted_and_lift_that_columns_limit(tmp_path):
    rec = load_csv(write(tmp_path, "time [s],displacement [m],force [N]"))
    assert rec.displacement[1] == 0.12
    mm = load_csv(write(tmp_path, "time (ms),displacement [mm],force (kN)", "0,0,0\n20,120,0.5\n"))
    assert np.allclose(mm.time, [0.0, 0.02])
    assert np.allclose(mm.displacement, [0.0, 0.12]) and np.allclose(mm.force, [0.0, 500.0])


def test_an_unknown_unit_is_refused_naming_the_known_ones(tmp_path):
    with pytest.raises(RecordError, match=r"line 1: unknown unit 'inch' for displacement.*m, mm"):
        load_csv(write(tmp_path, "time,displacement [inch],force"))
