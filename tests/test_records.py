import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bushenv.records import (
    MAX_RECORD_BYTES,
    Record,
    RecordError,
    load_csv,
    resample,
    save_csv,
)

DT = 1 / 204.8


def sample_record(n=50, dt=DT, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.normal(scale=1e-3, size=n)
    return Record.from_arrays(x, 4e5 * x + rng.normal(size=n), dt, name="sample")


def write(tmp_path, text, name="train.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


GOOD = "time,displacement,force\n0.0,0.0,0.0\n0.1,0.001,10.0\n0.2,0.002,20.0\n0.3,0.001,10.0\n"


def test_load_reads_columns_and_dt_from_time(tmp_path):
    r = load_csv(write(tmp_path, GOOD))
    assert len(r) == 4
    assert r.dt == pytest.approx(0.1)
    assert r.sample_rate_hz == pytest.approx(10.0)
    assert r.name == "train"
    assert np.array_equal(r.force, [0.0, 10.0, 20.0, 10.0])


def test_load_accepts_any_uniform_rate_spaces_bom_crlf_and_trailing_blank_lines(tmp_path):
    text = "\ufefftime, displacement ,force\r\n0,0,0\r\n0.0002,1e-3,5\r\n0.0004,2e-3,7\r\n\r\n\r\n"
    r = load_csv(write(tmp_path, text))
    assert r.sample_rate_hz == pytest.approx(5000.0)


def test_save_then_load_round_trips_exactly(tmp_path):
    r = sample_record()
    path = save_csv(r, tmp_path / "out.csv")
    back = load_csv(path)
    for key in ("time", "displacement", "force"):
        assert np.array_equal(getattr(back, key), getattr(r, key))


def test_save_refuses_existing_file_unless_overwrite(tmp_path):
    path = save_csv(sample_record(seed=1), tmp_path / "a.csv")
    before = path.read_bytes()
    with pytest.raises(RecordError, match=r"a\.csv already exists.*overwrite=True"):
        save_csv(sample_record(seed=2), path)
    assert path.read_bytes() == before
    save_csv(sample_record(seed=2), path, overwrite=True)
    assert path.read_bytes() != before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv"]  # no temp files left


def test_save_refuses_record_that_load_would_refuse(tmp_path):
    r = sample_record()
    r.displacement[3] = np.nan
    with pytest.raises(RecordError, match="sample 3.*displacement"):
        save_csv(r, tmp_path / "bad.csv")
    assert not (tmp_path / "bad.csv").exists()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", r"train\.csv: empty file"),
        ("time,displacement,force\n", r"header only, no data"),
        ("time,displacement,force\n0,0,0\n", r"only one data row"),
        ("\n\n\n", r"only blank lines"),
        (
            "time,displacment,force\n0,0,0\n1,0,0\n",
            r"line 1.*'displacment' should be 'displacement'",
        ),
        ("time,force\n0,0\n1,0\n", r"line 1.*missing column.*'displacement'"),
        ("time,displacement,force,temp\n0,0,0,0\n", r"extra column.*'temp'.*not allowed"),
        ("force,time,displacement\n0,0,0\n1,0,0\n", r"out of order"),
        ("time;displacement;force\n0;0;0\n", r"';'-separated"),
        ("0,0,0\n0.1,0,0\n", r"line 1.*is data, not a header"),
        ("hello world\nthis is not csv\n", r"line 1: header 'hello world'"),
        (
            GOOD.replace("0.2,0.002,20.0", "0.2,abc,20.0"),
            r"line 4: displacement 'abc' is not a number",
        ),
        (GOOD.replace("0.2,0.002,20.0", "0.2,0.002,nan"), r"line 4: force is 'nan'"),
        (GOOD.replace("0.2,0.002,20.0", "0.2,inf,20"), r"line 4: displacement is 'inf'"),
        (GOOD.replace("0.2,0.002,20.0", "0.2,0.002"), r"line 4: 2 value\(s\).*expected 3"),
        (GOOD.replace("0.2,", "0.05,"), r"line 4: time goes backwards \(0\.05 after 0\.1\)"),
        (GOOD.replace("0.2,", "0.1,"), r"line 4: time repeats \(0\.1 twice\)"),
        (GOOD.replace("0.3,", "0.32,"), r"line 5: time step .* tolerance"),
        (GOOD.replace("0.002,", "2.0,"), r"line 4: displacement 2\.0 .*looks like millimetres"),
        (GOOD.replace("20.0", "3e7"), r"line 4: force 30000000\.0 N.*wrong units"),
        (GOOD.replace("0.2,0.002,20.0\n", "\n0.2,0.002,20.0\n"), r"line 4: blank line inside"),
    ],
)
def test_load_refuses_bad_file_naming_file_line_and_value(tmp_path, text, message):
    with pytest.raises(RecordError, match=message):
        load_csv(write(tmp_path, text))


def test_load_refuses_binary_and_non_utf8(tmp_path):
    p = tmp_path / "model.npz"
    np.savez(p, a=np.zeros(3))
    with pytest.raises(RecordError, match=r"model\.npz: binary data"):
        load_csv(p)
    q = tmp_path / "latin.csv"
    q.write_bytes(b"time,displacement,force\n0,0,\xe9\n")
    with pytest.raises(RecordError, match=r"latin\.csv: not UTF-8"):
        load_csv(q)


def test_load_refuses_missing_file_and_directory(tmp_path):
    with pytest.raises(RecordError, match="no such record file"):
        load_csv(tmp_path / "nope.csv")
    with pytest.raises(RecordError, match="not a regular file"):
        load_csv(tmp_path)


def test_load_refuses_huge_file_without_reading_it(tmp_path):
    p = tmp_path / "huge.csv"
    with open(p, "wb") as fh:
        fh.truncate(2 * 2**30)  # sparse: 2 GiB apparent size, no disk blocks
    assert p.stat().st_size > MAX_RECORD_BYTES
    with pytest.raises(RecordError, match=r"huge\.csv: 2048\.0 MiB is larger than the 256 MiB"):
        load_csv(p)


def test_record_refuses_columns_of_different_length():
    with pytest.raises(RecordError, match="differ in length"):
        Record(time=np.arange(3.0), displacement=np.zeros(3), force=np.zeros(2))


def test_resample_interpolates_onto_new_step():
    t = np.arange(0, 1.0 + 1e-12, 0.01)
    r = Record(time=t, displacement=1e-3 * t, force=5.0 * t, name="lin")
    out = resample(r, 0.025)
    assert out.dt == pytest.approx(0.025)
    assert out.time[-1] == pytest.approx(1.0)
    assert np.allclose(out.displacement, 1e-3 * out.time)
    assert np.allclose(out.force, 5.0 * out.time)


# ----- property-based ----------------------------------------------------------------------
finite = dict(allow_nan=False, allow_infinity=False)


@st.composite
def records(draw, min_size=2):
    n = draw(st.integers(min_value=min_size, max_value=60))
    dt = draw(st.floats(min_value=1e-5, max_value=1.0, **finite))
    t0 = draw(st.floats(min_value=-10.0, max_value=10.0, **finite))
    x = draw(st.lists(st.floats(-0.1, 0.1, **finite), min_size=n, max_size=n))
    f = draw(st.lists(st.floats(-1e6, 1e6, **finite), min_size=n, max_size=n))
    return Record(time=t0 + np.arange(n) * dt, displacement=np.array(x), force=np.array(f))


settings_io = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@settings_io
@given(records())
def test_any_valid_record_round_trips_exactly(record):
    with tempfile.TemporaryDirectory() as d:
        back = load_csv(save_csv(record, Path(d) / "r.csv"))
    for key in ("time", "displacement", "force"):
        assert np.array_equal(getattr(back, key), getattr(record, key))


def _corrupt(lines: list[str], kind: str, data) -> list[str]:
    lines = list(lines)
    n = len(lines)
    row = data.draw(st.integers(1, n - 1), label="row")
    if kind == "insert_text":
        where = data.draw(st.integers(0, n), label="where")
        lines.insert(where, data.draw(st.sampled_from(["hello", "a,b,c", "1,2", "x;y;z"])))
    elif kind == "text_in_number":
        fields = lines[row].split(",")
        col = data.draw(st.integers(0, 2), label="col")
        fields[col] = data.draw(st.sampled_from(["abc", "1.2.3", "", "mm", "--", "0x10"]))
        lines[row] = ",".join(fields)
    elif kind == "nan":
        fields = lines[row].split(",")
        col = data.draw(st.integers(0, 2), label="col")
        fields[col] = data.draw(st.sampled_from(["nan", "NaN", "inf", "-inf", "Infinity"]))
        lines[row] = ",".join(fields)
    elif kind == "swap_lines":
        other = data.draw(st.integers(0, n - 1).filter(lambda i: i != row), label="other")
        lines[row], lines[other] = lines[other], lines[row]
    elif kind == "delete_header":
        del lines[0]
    elif kind == "drop_column":
        col = data.draw(st.integers(0, 2), label="col")
        everywhere = data.draw(st.booleans(), label="everywhere")
        for i in range(n) if everywhere else [row]:
            fields = lines[i].split(",")
            del fields[col]
            lines[i] = ",".join(fields)
    return lines


@settings_io
@given(
    records(min_size=3),
    st.sampled_from(
        ["insert_text", "text_in_number", "nan", "swap_lines", "delete_header", "drop_column"]
    ),
    st.data(),
)
def test_corrupted_file_is_refused_with_record_error_only(record, kind, data):
    with tempfile.TemporaryDirectory() as d:
        path = save_csv(record, Path(d) / "r.csv")
        lines = path.read_text().splitlines()
        path.write_text("\n".join(_corrupt(lines, kind, data)) + "\n")
        with pytest.raises(RecordError, match=r"r\.csv"):
            load_csv(path)


@settings(max_examples=150, deadline=None)
@given(st.binary(max_size=300))
def test_arbitrary_bytes_give_a_record_or_record_error(blob):
    with tempfile.TemporaryDirectory() as d:
        p = os.path.join(d, "blob.csv")
        with open(p, "wb") as fh:
            fh.write(b"time,displacement,force\n" + blob)
        try:
            r = load_csv(p)
        except RecordError:
            return
        assert len(r) >= 2 and np.all(np.diff(r.time) > 0)


# ----- the plain-number fast path agrees with the line-by-line parser ---------------------------
def outcome(load, path):
    """(time, displacement, force) as bytes, or the RecordError message."""
    try:
        r = load(path)
    except RecordError as exc:
        return str(exc)
    return tuple(a.tobytes() for a in (r.time, r.displacement, r.force))


PLAIN_BODY = "0.0,0.0,0.0\n0.1,1e-3,1.5E+1\n0.2,+2.5e-3,-0.0\n0.3,.001,10.\n"
VARIANTS = {
    "plain": "time,displacement,force\n" + PLAIN_BODY,
    "crlf": ("time,displacement,force\n" + PLAIN_BODY).replace("\n", "\r\n"),
    "bom": "\ufefftime,displacement,force\n" + PLAIN_BODY,
    "blank tail": "time,displacement,force\n" + PLAIN_BODY + "\n  \n\t\n",
    "spaces": "time , displacement , force\n" + PLAIN_BODY.replace(",", " , "),
    "blank inside": "time,displacement,force\n0.0,0,0\n\n0.1,0,0\n0.2,0,0\n",
    "crlf blank inside": "time,displacement,force\r\n0.0,0,0\r\n\r\n0.1,0,0\r\n0.2,0,0\r\n",
    "blank first": "time,displacement,force\n\n0.0,0,0\n0.1,0,0\n",
    "spaces line inside": "time,displacement,force\n0.0,0,0\n   \n0.1,0,0\n0.2,0,0\n",
    "two values": "time,displacement,force\n0.0,0\n0.1,0\n",
    "four values": "time,displacement,force\n0.0,0,0,0\n0.1,0,0,0\n",
    "empty value": "time,displacement,force\n0.0,,0\n0.1,0,0\n",
    "overflow": "time,displacement,force\n0.0,0,0\n0.1,0,1e999\n",
    "nan": "time,displacement,force\n0.0,0,0\n0.1,nan,0\n",
    "backwards": "time,displacement,force\n0.0,0,0\n0.1,0,0\n0.05,0,0\n",
    "repeats": "time,displacement,force\n0.0,0,0\n0.1,0,0\n0.1,0,0\n",
    "uneven": "time,displacement,force\n0.0,0,0\n0.1,0,0\n0.2,0,0\n0.35,0,0\n0.45,0,0\n",
    "millimetres": "time,displacement,force\n0.0,0,0\n0.1,2.5,0\n0.2,0,0\n",
    "one row": "time,displacement,force\n0.0,0,0\n",
    "header only": "time,displacement,force\n",
    "quoted": 'time,displacement,force\n"0.0",0,0\n0.1,0,0\n',
    "underscore": "time,displacement,force\n0.0,0,0\n0.1,1_0,0\n",
    "lone cr": "time,displacement,force\r0.0,0,0\r0.1,0,0\r",
    "bad header": "time,displacment,force\n0.0,0,0\n0.1,0,0\n",
    "signs": "time,displacement,force\n0.0,0,0\n0.1,+-1,0\n",
    "long value": "time,displacement,force\n0.0,0,0\n0.1,0." + "0" * 140_000 + "1,0\n",
}


@pytest.mark.parametrize("chunk_bytes", [8 * 2**20, 7])  # the scan in one chunk or many
@pytest.mark.parametrize("name", sorted(VARIANTS))
def test_load_gives_what_the_line_by_line_parser_gives(tmp_path, monkeypatch, name, chunk_bytes):
    from bushenv import records
    from bushenv.records import _load_line_by_line

    monkeypatch.setattr(records, "_SCAN_CHUNK_BYTES", chunk_bytes)
    path = tmp_path / "r.csv"
    path.write_bytes(VARIANTS[name].encode("utf-8"))
    assert outcome(load_csv, path) == outcome(_load_line_by_line, path)


def test_files_save_csv_writes_take_the_plain_number_path(tmp_path):
    from bushenv.records import _plain_numbers

    path = save_csv(sample_record(n=2000), tmp_path / "r.csv")
    assert _plain_numbers(path)
    for name in ("crlf", "bom", "blank tail", "spaces"):
        (tmp_path / "v.csv").write_bytes(VARIANTS[name].encode("utf-8"))
        assert _plain_numbers(tmp_path / "v.csv"), name
    for name in ("blank inside", "quoted", "underscore", "lone cr", "nan", "long value"):
        (tmp_path / "v.csv").write_bytes(VARIANTS[name].encode("utf-8"))
        assert not _plain_numbers(tmp_path / "v.csv"), name


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(
        st.sampled_from(
            [
                "0.0",
                "0.1",
                "1e-3",
                "-2.5E+2",
                "+.5",
                "5.",
                "1e999",
                "",
                " 1",
                "1 ",
                "1 2",
                "-",
                "nan",
                "0x1",
                "1_0",
                '"1"',
                "\t3",
            ]  # fmt: skip
        ),
        min_size=2,
        max_size=40,
    ),
    st.lists(st.sampled_from([",", "\n", "\r\n", "\n\n", ",,", "\r"]), min_size=2, max_size=40),
    st.booleans(),
)
def test_any_mix_of_numbers_and_separators_loads_as_the_line_by_line_parser_does(
    tmp_path_factory, values, separators, bom
):
    from bushenv.records import _load_line_by_line

    body = "".join(v + s for v, s in zip(values, separators, strict=False))
    text = ("\ufeff" if bom else "") + "time,displacement,force\n" + body
    path = tmp_path_factory.mktemp("mix") / "r.csv"
    path.write_bytes(text.encode("utf-8"))
    assert outcome(load_csv, path) == outcome(_load_line_by_line, path)


def test_one_record_type_reads_either_header_and_writes_it_back(tmp_path):
    from bushenv.record_columns import THREE_AXES
    from bushenv.record_files import load_record, save_record

    one = Record.from_arrays(np.sin(np.arange(50) * 0.1) * 1e-3, np.arange(50.0), 0.01)
    save_record(one, tmp_path / "one.csv")
    t = np.arange(50) * 0.01
    q = np.column_stack([np.sin(t), np.cos(t), 0.1 * t]) * 1e-3
    three = Record(t, q, q * 1e5, name="three")
    assert three.coords == ("axial", "radial", "rotation") and three.n_coords == 3
    save_csv(three, tmp_path / "via_save_csv.csv")  # the one writer, whatever C
    save_record(three, tmp_path / "three.csv")
    assert (tmp_path / "via_save_csv.csv").read_bytes() == (tmp_path / "three.csv").read_bytes()
    assert (tmp_path / "three.csv").read_text().splitlines()[0] == THREE_AXES.header_text
    a, b = load_record(tmp_path / "one.csv"), load_record(tmp_path / "three.csv")
    assert a.n_coords == 1 and a.q.shape == (50, 1) and a.source == str(tmp_path / "one.csv")
    assert b.n_coords == 3 and b.q.shape == (50, 3)
    np.testing.assert_array_equal(b.q, q)
    np.testing.assert_array_equal(b.f, q * 1e5)
    np.testing.assert_array_equal(a.displacement, one.displacement)
