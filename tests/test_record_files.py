"""Multi-axis CSV records: round trip, units in the header, errors naming file, line, value."""

import numpy as np
import pytest

from bushenv.record_columns import THREE_AXES
from bushenv.record_files import load_record, save_columns
from bushenv.records import RecordError

DT = 1 / 204.8


def _data(T=20):
    rng = np.random.default_rng(0)
    q = rng.normal(size=(T, 3)) * np.array([1e-3, 1e-3, 0.02])
    f = rng.normal(size=(T, 3)) * np.array([300.0, 1500.0, 60.0])
    return np.arange(T) * DT, q, f


def test_save_load_roundtrip_bit_for_bit(tmp_path):
    t, q, f = _data()
    rec = load_record(save_columns(tmp_path / "r.csv", t, q, f), coords=3)
    np.testing.assert_array_equal(rec.q, q)
    np.testing.assert_array_equal(rec.f, f)
    assert rec.dt == pytest.approx(DT)
    with pytest.raises(RecordError, match="overwrite=True"):
        save_columns(tmp_path / "r.csv", t, q, f)


def test_units_in_the_header_are_converted(tmp_path):
    p = tmp_path / "u.csv"
    p.write_text(
        "time [ms],displacement_axial [mm],displacement_radial [mm],rotation [deg],"
        "force_axial [kN],force_radial [N],moment [N mm]\n0,1,2,90,1,5,1000\n5,0,0,0,0,0,0\n"
    )
    rec = load_record(p, coords=3)
    np.testing.assert_allclose(rec.q[0], [1e-3, 2e-3, np.pi / 2])
    np.testing.assert_allclose(rec.f[0], [1000.0, 5.0, 1.0])
    np.testing.assert_allclose(rec.time, [0.0, 0.005])


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (
            "time,displacement,force\n0,0,0\n",
            r"line 1: header .* expected 'time,displacement_axial",
        ),
        (
            THREE_AXES.header_text.replace("rotation", "rotation [grad]") + "\n",
            r"line 1: unknown unit 'grad'",
        ),
        (
            THREE_AXES.header_text + "\ns,m,m,rad,N,N,N m\n",
            r"line 2: 's,m,m,rad,N,N,N m' looks like a row of units under the header",
        ),
        (
            THREE_AXES.header_text + "\n0,0,0,0,0,0,0\n0.1,0,0,0,0,0\n",
            r"line 3: 6 value\(s\) '0.1,0,0,0,0,0', expected 7",
        ),
        (
            THREE_AXES.header_text + "\n0,0,0,0,0,0,0\n0.1,0,0,nan,0,0,0\n",
            r"line 3: rotation is 'nan', expected a finite number",
        ),
        (
            THREE_AXES.header_text + "\n0,0,0,0,0,0,0\n0.1,0,0,45,0,0,0\n",
            r"line 3: rotation 45.0 .*\[deg\]",
        ),
        (
            THREE_AXES.header_text + "\n0,0,0,0,0,0,0\n0.1,2,0,0,0,0,0\n",
            r"line 3: displacement_axial .*mm",
        ),
        (
            THREE_AXES.header_text + "\n0.1,0,0,0,0,0,0\n0.0,0,0,0,0,0,0\n",
            r"line 3: time goes backwards",
        ),
        (THREE_AXES.header_text + "\n0,0,0,0,0,0,0\n", r"only one data row"),
        (
            THREE_AXES.header_text
            + "\n0,0,0,0,0,0,0\n0.1,0,0,0,0,0,0\n0.3,0,0,0,0,0,0\n0.4,0,0,0,0,0,0\n",
            r"line 4: time step",
        ),
    ],
)
def test_bad_records_name_file_line_and_value(tmp_path, text, match):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(RecordError, match=match) as err:
        load_record(p, coords=3)
    assert "bad.csv" in str(err.value)


def test_missing_file_is_named(tmp_path):
    with pytest.raises(RecordError, match="no such record file"):
        load_record(tmp_path / "none.csv", coords=3)


@pytest.mark.parametrize("written, wanted", [(1, 3), (3, 1)])
def test_a_record_of_the_other_number_of_coordinates_is_refused_saying_which_it_is(
    tmp_path, written, wanted
):
    from bushenv.record_files import load_record, save_record
    from bushenv.records import Record

    t = np.arange(100) / 204.8
    q = 1e-3 * np.sin(np.outer(t, np.arange(1, written + 1)))
    rec = Record(t, q[:, 0] if written == 1 else q, (q * 1e5)[:, 0] if written == 1 else q * 1e5)
    path = save_record(rec, tmp_path / "r.csv")
    assert load_record(path).n_coords == written  # read as it is when nothing is wanted
    with pytest.raises(RecordError, match=f"line 1: .*{'one' if written == 1 else written}-axis"):
        load_record(path, coords=wanted)
