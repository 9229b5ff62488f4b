"""Records that cannot be what they say are refused: an implausible sample rate under a plain
``time`` header, a units row under the header, records of different rates mixed in one ``fit``
or ``diagnose`` without ``--resample`` (docs/bad-inputs.md, rows 97-104)."""

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.record_rates import one_rate
from bushenv.records import PLAUSIBLE_RATE_HZ, Record, RecordError, load_csv, save_csv


def _motion(hz: float, seconds: float = 4.0):
    t = np.arange(int(round(seconds * hz))) / hz
    x = 2e-3 * np.sin(2 * np.pi * 3 * t) + 5e-4 * np.sin(2 * np.pi * 11 * t)
    return t, x, 4e5 * x + 2e3 * np.gradient(x, 1 / hz)


def _csv(path, hz, time_factor=1.0, header="time,displacement,force", seconds=4.0):
    t, x, f = _motion(hz, seconds)
    cols = ((t * time_factor).tolist(), x.tolist(), f.tolist())
    rows = "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in zip(*cols, strict=True))
    path.write_text(header + "\n" + rows)
    return path


def test_a_time_column_in_milliseconds_is_refused_saying_so_and_how_to_declare_it(tmp_path):
    path = _csv(tmp_path / "ms.csv", 500.0, time_factor=1e3)
    with pytest.raises(RecordError) as err:
        load_csv(path)
    msg = str(err.value)
    assert msg.startswith(f"{path} line 3: time step 2.0 s is 0.5 Hz sampling, implausible")
    assert "looks like milliseconds (500 Hz if it is)" in msg and "'time [ms]'" in msg
    assert "\n" not in msg
    rec = load_csv(_csv(tmp_path / "declared.csv", 500.0, 1e3, "time [ms],displacement,force"))
    assert rec.sample_rate_hz == pytest.approx(500.0) and rec.time[1] == pytest.approx(0.002)


def test_a_time_column_in_microseconds_is_refused_and_time_us_reads_it(tmp_path):
    with pytest.raises(RecordError, match=r"line 3: .*looks like microseconds.*'time \[us\]'"):
        load_csv(_csv(tmp_path / "us.csv", 500.0, time_factor=1e6, seconds=0.1))
    rec = load_csv(_csv(tmp_path / "ok.csv", 500.0, 1e6, "time [us],displacement,force", 0.1))
    assert rec.sample_rate_hz == pytest.approx(500.0)


def test_the_plausible_range_is_10_hz_to_100_khz_unless_the_unit_is_stated(tmp_path):
    assert PLAUSIBLE_RATE_HZ == (10.0, 100e3)
    assert load_csv(_csv(tmp_path / "a.csv", 10.0, seconds=2.0)).sample_rate_hz == 10.0
    with pytest.raises(RecordError, match="9 Hz sampling, implausible for a dynamic test"):
        load_csv(_csv(tmp_path / "b.csv", 9.0, seconds=2.0))
    fast = _csv(tmp_path / "c.csv", 200e3, seconds=1e-3)
    with pytest.raises(RecordError, match="200000 Hz .* no bushing test machine samples this"):
        load_csv(fast)
    creep = _csv(tmp_path / "d.csv", 1.0, header="time [s],displacement,force", seconds=30.0)
    assert load_csv(creep).sample_rate_hz == pytest.approx(1.0)  # stated: taken as stated


def test_save_csv_states_seconds_for_a_slow_record_so_it_reads_back(tmp_path):
    t, x, f = _motion(1.0, seconds=30.0)
    slow = save_csv(Record(time=t, displacement=x, force=f), tmp_path / "slow.csv")
    assert slow.read_text().splitlines()[0] == "time [s],displacement,force"
    back = load_csv(slow)
    assert np.array_equal(back.time, t) and np.array_equal(back.force, f)
    t, x, f = _motion(500.0)
    fast = save_csv(Record(time=t, displacement=x, force=f), tmp_path / "fast.csv")
    assert fast.read_text().splitlines()[0] == "time,displacement,force"


@pytest.mark.parametrize(
    ("header", "row", "message"),
    [
        (
            "time,displacement,force",
            "s,mm,kN",
            "line 2: 's,mm,kN' looks like a row of units under the header; put each unit in the "
            "header instead, 'time [s],displacement [mm],force [kN]', and delete this row",
        ),
        (
            "time,displacement,force",
            "(s), (m), (N)",
            "'time [s],displacement [m],force [N]'",
        ),
        (
            "time [s],displacement [mm],force [kN]",
            "[s],[mm],[kN]",
            "line 2: '[s],[mm],[kN]' looks like a row of units; the header already states",
        ),
    ],
)
def test_a_units_row_under_the_header_is_refused_saying_how_to_write_units(
    tmp_path, header, row, message
):
    path = tmp_path / "r.csv"
    path.write_text(f"{header}\n{row}\n0.0,0.0,0.0\n0.002,0.001,10.0\n0.004,0.0,0.0\n")
    with pytest.raises(RecordError) as err:
        load_csv(path)
    assert message in str(err.value) and str(err.value).startswith(str(path))


def test_text_that_is_not_units_is_still_named_as_not_a_number(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("time,displacement,force\nfoo,bar,baz\n0.0,0.0,0.0\n0.002,0.001,10.0\n")
    with pytest.raises(RecordError, match="line 2: time 'foo' is not a number"):
        load_csv(path)


def _records(tmp_path):
    a = load_csv(_csv(tmp_path / "train.csv", 500.0))
    b = load_csv(_csv(tmp_path / "held.csv", 1000.0))
    return a, b


def test_records_of_different_rates_are_refused_naming_both_and_the_fix(tmp_path):
    a, b = _records(tmp_path)
    with pytest.raises(RecordError) as err:
        one_rate([[a], [b]], None, "fit")
    msg = str(err.value)
    assert msg.startswith(f"{b.path} line 3: sampled at 1000 Hz (time step 0.001 s), {a.path}")
    assert "at 500 Hz: records at different sample rates in one fit" in msg
    assert "--resample 500 (linear interpolation)" in msg and "keep" not in msg
    with pytest.raises(RecordError, match="or --resample keep"):
        one_rate([[a], [b]], None, "diagnose")


def test_resample_brings_every_record_to_the_rate_asked_and_keep_leaves_them(tmp_path):
    a, b = _records(tmp_path)
    [[a2], [b2]] = one_rate([[a], [b]], 500.0, "fit")
    assert a2 is a  # already at 500 Hz: untouched
    assert b2.sample_rate_hz == pytest.approx(500.0) and "resampled 1000 -> 500 Hz" in b2.name
    assert np.allclose(b2.force, np.interp(b2.time, b.time, b.force))
    assert one_rate([[a], [b]], "keep", "diagnose") == [[a], [b]]


def test_fit_refuses_mixed_rates_in_one_line_and_fits_with_resample(tmp_path, capsys):
    train = _csv(tmp_path / "train.csv", 500.0)
    held = _csv(tmp_path / "held.csv", 1000.0)
    args = ["fit", str(train), "--validate", str(held), "--model", "linear", "--no-plots"]
    assert main(args + ["--out", str(tmp_path / "m.npz"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and f"{held} line 3: sampled at 1000 Hz" in err and "--resample" in err
    assert main(args + ["--out", str(tmp_path / "m.npz"), "--quiet", "--resample", "500"]) == 0
    assert (tmp_path / "m.npz").is_file()


def test_fit_and_diagnose_refuse_a_millisecond_record_in_one_line(tmp_path, capsys):
    good = _csv(tmp_path / "good.csv", 500.0)
    ms = _csv(tmp_path / "ms.csv", 500.0, time_factor=1e3)
    assert main(["fit", str(ms), "--model", "linear", "--out", str(tmp_path / "m.npz")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"bushenv fit: error: {ms} line 3: time step 2.0 s is 0.5 Hz")
    assert main(["diagnose", str(good), str(ms), "--out", str(tmp_path / "d"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "'time [ms]'" in err and not (tmp_path / "d").exists()


def test_diagnose_refuses_mixed_rates_before_writing_anything(tmp_path, capsys):
    train = _csv(tmp_path / "train.csv", 500.0)
    test = _csv(tmp_path / "test.csv", 1000.0)
    out = tmp_path / "d"
    assert main(["diagnose", str(train), str(test), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert f"{test} line 3: sampled at 1000 Hz" in err and "--resample keep" in err
    assert not out.exists()


def test_resample_option_refuses_a_bad_value(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["fit", "a.csv", "--model", "linear", "--out", "m.npz", "--resample", "-5"])
    assert exc.value.code == 2
    assert "expected a positive rate in Hz or 'keep', got '-5'" in capsys.readouterr().err
