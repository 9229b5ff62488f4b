"""3-axis records as a user's own rig writes them: column order, units, time unit, offsets."""

import numpy as np
import pytest
from standin import bushing, user_columns, write

from bushenv.record_columns import THREE_AXES
from bushenv.record_files import load_record, save_columns
from bushenv.record_notes import start_notes
from bushenv.records import RecordError


def test_a_header_in_another_order_and_units_reads_as_the_si_record(tmp_path):
    t, q, f = bushing()
    si = load_record(save_columns(tmp_path / "si.csv", t, q, f), coords=3)
    user = load_record(write(tmp_path / "user.csv", *user_columns(t, q, f)), coords=3)
    np.testing.assert_allclose(user.time, si.time, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(user.q, si.q, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(user.f, si.f, rtol=1e-8, atol=1e-9)
    assert user.dt == pytest.approx(0.002)


@pytest.mark.parametrize(
    ("header", "match"),
    [
        (
            THREE_AXES.header_text.replace("displacement_radial", "displacment_radial"),
            r"column 3 'displacment_radial' is not a planar record column \(did you mean "
            r"'displacement_radial'\?\)",
        ),
        (
            THREE_AXES.header_text.replace("moment", "force_axial"),
            r"force_axial appears twice in the header .*columns 5 and 7",
        ),
        (
            THREE_AXES.header_text.replace(",", ";"),
            r"line 1: header .* looks ';'-separated; save the file with commas",
        ),
        (
            THREE_AXES.header_text.replace(",", "\t"),
            r"line 1: header .* looks tab-separated; save the file with commas",
        ),
        (
            THREE_AXES.header_text + ",temperature",
            r"column 8 'temperature' is not a planar record column",
        ),
    ],
)
def test_a_wrong_header_is_named_with_its_fix(tmp_path, header, match):
    path = tmp_path / "rig.csv"
    path.write_text(header + "\n0,0,0,0,0,0,0\n0.002,0,0,0,0,0,0\n")
    with pytest.raises(RecordError, match=match) as err:
        load_record(path, coords=3)
    assert str(err.value).startswith(f"{path} line 1:")


def test_a_one_axis_record_given_to_the_planar_loader_says_which_kind_it_is(tmp_path):
    path = tmp_path / "one.csv"
    path.write_text("time,displacement,force\n0,0,0\n0.002,1e-3,500\n")
    with pytest.raises(RecordError, match=r"is a one-axis record's; expected 'time,displacement_"):
        load_record(path, coords=3)


def test_a_plain_time_column_in_milliseconds_is_refused_with_the_unit_to_write(tmp_path):
    t, q, f = bushing(seconds=1.0)
    path = write(tmp_path / "ms.csv", THREE_AXES.header_text, [1e3 * t, q, f])
    with pytest.raises(
        RecordError, match=r"ms.csv line 3: time step 2.0 s is 0.5 Hz.*'time \[ms\]'"
    ):
        load_record(path, coords=3)


def test_a_small_rotation_in_degrees_under_a_plain_header_is_refused(tmp_path):
    t, q, f = bushing(seconds=1.0)  # 0.04 rad = 2.3 deg: below pi, read as radians before
    cols = [t, q[:, :2], np.degrees(q[:, 2]), f]
    path = write(tmp_path / "deg.csv", THREE_AXES.header_text, cols)
    with pytest.raises(RecordError, match=r"rotation .* exceeds 0.5 rad; degrees\? write "):
        load_record(path, coords=3)


def test_a_slow_record_is_saved_with_its_time_unit_and_reads_back(tmp_path):
    t, q, f = bushing(fs=5.0, seconds=20.0)
    path = save_columns(tmp_path / "slow.csv", t, q, f)
    assert path.read_text().splitlines()[0].startswith("time [s],")
    rec = load_record(path, coords=3)
    np.testing.assert_array_equal(rec.q, q)


def test_a_record_from_rest_gets_no_notes(tmp_path):
    rec = load_record(save_columns(tmp_path / "r.csv", *bushing()), coords=3)
    assert start_notes(rec) == []


def test_a_record_that_starts_preloaded_is_noted_with_its_deflection(tmp_path):
    t, q, f = bushing(preload=(0.0, 2e-3, 0.0), rest_s=0.0)
    t, q, f = t[300:] - t[300], q[300:], f[300:]  # the recording began after the preload
    rec = load_record(save_columns(tmp_path / "pre.csv", t, q, f), coords=3)
    (note,) = start_notes(rec)
    assert note.startswith(f"{rec.source} line 2: starts deflected (")
    assert f"displacement_radial {1e3 * q[:5, 1].mean():.3g} mm" in note


def test_a_force_offset_at_rest_is_noted_with_its_value(tmp_path):
    t, q, f = bushing()
    rec = load_record(save_columns(tmp_path / "off.csv", t, q, f + [0.0, -150.0, 0.0]), coords=3)
    (note,) = start_notes(rec)
    assert "reads force_radial -150 N at rest" in note and "load-cell offset" in note


def test_plain_numbers_read_fast_equal_the_line_by_line_reading_bit_for_bit(tmp_path):
    from bushenv.records import _load_line_by_line, _load_plain, _plain_numbers

    plain = save_columns(tmp_path / "plain.csv", *bushing())
    assert _plain_numbers(plain, THREE_AXES)
    fast, slow = _load_plain(plain, THREE_AXES), _load_line_by_line(plain, THREE_AXES)
    for key in ("time", "displacement", "force"):
        np.testing.assert_array_equal(getattr(fast, key), getattr(slow, key))
    path = write(tmp_path / "user.csv", *user_columns(*bushing()))  # any order: line by line
    assert not _plain_numbers(path, THREE_AXES)
    text = path.read_text()
    crlf = path.with_name("crlf.csv")
    crlf.write_bytes(text.replace("\n", "\r\n").encode())
    a, b = load_record(path, coords=3), load_record(crlf, coords=3)
    np.testing.assert_array_equal(a.f, b.f)


def test_a_blank_line_inside_the_data_is_named(tmp_path):
    t, q, f = bushing(seconds=1.0)
    path = save_columns(tmp_path / "r.csv", t, q, f)
    lines = path.read_text().splitlines()
    path.write_text("\n".join([*lines[:10], "", *lines[10:]]) + "\n")
    with pytest.raises(RecordError, match=r"r.csv line 11: blank line inside the data"):
        load_record(path, coords=3)


def test_an_axis_holding_only_sensor_noise_is_neither_deflected_nor_loaded(tmp_path):
    t, q, f = bushing()
    rng = np.random.default_rng(1)
    q[:, 0] = 1e-6 * rng.standard_normal(t.size)  # the axial actuator held, its sensor noise
    f[:, 0] = 2.0 * rng.standard_normal(t.size)
    q[:5, 0] += 4e-6  # a start a few sigmas off: noise, not a preload
    rec = load_record(save_columns(tmp_path / "held.csv", t, q, f), coords=3)
    assert start_notes(rec) == []


def test_a_torsion_only_header_names_the_missing_columns_and_the_zeros_fix(tmp_path):
    path = tmp_path / "torsion.csv"
    path.write_text("time,rotation [deg],moment\n0,0,0\n0.002,0.1,0.2\n")
    with pytest.raises(RecordError, match=r"lacks displacement_axial, displacement_radial, "
                       r"force_axial, force_radial; .* as columns of zeros"):  # fmt: skip
        load_record(path, coords=3)
