"""Bad record files that tests/test_records.py does not already try: each is refused with a
``RecordError`` naming the file (and the line where there is one), quickly, never a hang.

The catalogue with the messages is docs/bad-inputs.md.
"""

import gzip
import io
import os
import time
import tracemalloc
import zipfile

import numpy as np
import pytest

from bushenv.records import MAX_RECORD_BYTES, Record, RecordError, load_csv, resample

ROWS_2000 = "".join(f"{i / 10},0,0\n" for i in range(2000))  # 2000 lines > the 8 KiB sniff
GOOD = "time,displacement,force\n0.0,0.0,0.0\n0.1,0.001,10.0\n0.2,0.002,20.0\n0.3,0.001,10.0\n"


def write_bytes(tmp_path, data: bytes, name: str = "rec.csv"):
    p = tmp_path / name
    p.write_bytes(data)
    return p


def _zip_of_csv() -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("rec.csv", GOOD)
    return buf.getvalue()


@pytest.mark.parametrize(
    ("data", "message"),
    [
        pytest.param(
            b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)),
            r"rec\.csv: binary data \(a PNG image\)",
            id="png",
        ),
        pytest.param(_zip_of_csv(), r"rec\.csv: binary data \(a zip archive", id="zip"),
        pytest.param(gzip.compress(GOOD.encode()), r"binary data \(a gzip", id="gzip"),
        pytest.param(GOOD.encode("utf-16"), r"binary data \(UTF-16 text", id="utf16"),
        pytest.param(b"%PDF-1.7\n%\xe2\xe3\xcf\xd3\n", r"binary data \(a PDF", id="pdf"),
        pytest.param(b"\x93NUMPY\x01\x00v\x00{'descr'", r"binary data \(a NumPy", id="npy"),
        pytest.param(b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1", r"old Excel/Office", id="xls"),
    ],
)
def test_non_csv_file_is_refused_saying_what_it_looks_like(tmp_path, data, message):
    with pytest.raises(RecordError, match=message):
        load_csv(write_bytes(tmp_path, data))


@pytest.mark.parametrize(
    ("text", "message"),
    [
        pytest.param(
            GOOD.replace("\n0.0,", "\ns,m,N\n0.0,", 1),
            r"rec\.csv line 2: 's,m,N' looks like a row of units under the header; put each "
            r"unit in the header instead, 'time \[s\],displacement \[m\],force \[N\]'",
            id="units-row",
        ),
        pytest.param(
            GOOD.replace("20.0", "1e400"),
            r"rec\.csv line 4: force is '1e400', expected a finite number",
            id="overflow-to-inf",
        ),
        pytest.param(
            GOOD.replace("20.0", "-Infinity"),
            r"line 4: force is '-Infinity', expected a finite number",
            id="minus-infinity",
        ),
        pytest.param(
            GOOD + "time,displacement,force\n" + "0.4,0.0,0.0\n",
            r"line 6: time 'time' is not a number",
            id="second-header-appended",
        ),
        pytest.param(
            'time,displacement,force\n"0,0,0\n0.1,0,0\n',
            r"rec\.csv: not a readable CSV file: unexpected end of data",
            id="unclosed-quote",
        ),
        pytest.param(
            "time,displacement,force\n" + "1" * 200_000 + ",0,0\n0.1,0,0\n",
            r"rec\.csv: not a readable CSV file: field larger than field limit",
            id="200k-character-field",
        ),
        pytest.param(
            "<!DOCTYPE html><html><body>404 Not Found</body></html>\n",
            r"rec\.csv line 1: header '<!DOCTYPE html>.*missing column 'time'",
            id="html-error-page",
        ),
        pytest.param(
            "\ufeff\ufefftime,displacement,force\n0,0,0\n0.1,0,0\n",
            r"line 1: header .*should be 'time'",
            id="double-bom",
        ),
        pytest.param(
            "time,displacement,force\n0.0,0,0\n0.1,0,0\n0.1000000000000000001,0,0\n",
            r"line 4: time repeats \(0\.1 twice\)",
            id="repeat-below-float-resolution",
        ),
        pytest.param(
            "time,displacement,force\n"
            + "".join(f"{i / 10},0,0\n" for i in range(2000))
            + "\x00\n",
            r"line 2002: 1 value\(s\) '\\x00', expected 3",
            id="nul-after-the-sniffed-block",
        ),
        pytest.param(
            "Time,Displacement (mm),Force (kN)\n0,0,0\n0.1,1,2\n",
            r"line 1: header .*'Time'.*expected exactly 'time,displacement,force'",
            id="units-in-column-names",
        ),
    ],
)
def test_bad_record_text_is_refused_naming_file_and_line(tmp_path, text, message):
    with pytest.raises(RecordError, match=message):
        load_csv(write_bytes(tmp_path, text.encode("utf-8")))


def test_jitter_within_tolerance_is_accepted_and_gives_the_median_step(tmp_path):
    text = "time,displacement,force\n0,0,0\n0.1,0,0\n0.2005,0,0\n0.3,0,0\n0.4,0,0\n"
    r = load_csv(write_bytes(tmp_path, text.encode()))
    assert len(r) == 5
    assert r.dt == pytest.approx(0.1)


def test_jitter_just_beyond_tolerance_is_refused_naming_the_line(tmp_path):
    # 1 % of 0.1 s plus 1 ns is the tolerance: 0.0011 s off is beyond it
    text = "time,displacement,force\n0,0,0\n0.1,0,0\n0.2011,0,0\n0.3,0,0\n0.4,0,0\n"
    with pytest.raises(RecordError, match=r"rec\.csv line 4: time step .* tolerance"):
        load_csv(write_bytes(tmp_path, text.encode()))


def test_mm_record_is_refused_even_when_the_peak_is_only_a_fraction_of_a_mm(tmp_path):
    # 0.5 mm written as 0.5 (mm) is 0.5 m: refused; the stated limit of the check is 0.1
    text = "time,displacement,force\n0,0,0\n0.1,0.5,10\n0.2,-0.2,5\n"
    with pytest.raises(RecordError, match=r"line 3: displacement 0\.5 m.*millimetres"):
        load_csv(write_bytes(tmp_path, text.encode()))


@pytest.mark.parametrize("device", ["fifo", "/dev/zero", "/dev/urandom"])
def test_endless_stream_is_refused_at_once_instead_of_hanging(tmp_path, device):
    if device == "fifo":
        path = tmp_path / "pipe.csv"
        os.mkfifo(path)  # opening it for reading would block forever
    else:
        path = device
    t0 = time.monotonic()
    with pytest.raises(RecordError, match="not a regular file"):
        load_csv(path)
    assert time.monotonic() - t0 < 1.0


def test_symlink_loop_is_refused_as_missing(tmp_path):
    loop = tmp_path / "loop.csv"
    loop.symlink_to(loop)
    with pytest.raises(RecordError, match=r"loop\.csv: no such record file"):
        load_csv(loop)


@pytest.mark.parametrize(
    ("head", "size", "message"),
    [
        pytest.param(
            GOOD.encode(),
            MAX_RECORD_BYTES + 1,
            r"sparse\.csv: 256\.0 MiB is larger than",
            id="just-over-the-limit",
        ),
        pytest.param(  # holes read as NUL bytes: refused from the first 8 KiB, not parsed
            b"time,displacement,force\n0,0,0\n",
            200 * 2**20,
            r"sparse\.csv: binary data \(NUL byte at byte 30\)",
            id="200MiB-under-the-limit",
        ),
    ],
)
def test_sparse_file_is_refused_fast_without_reading_it_whole(tmp_path, head, size, message):
    path = tmp_path / "sparse.csv"
    with open(path, "wb") as fh:
        fh.write(head)
        fh.truncate(size)
    tracemalloc.start()
    t0 = time.monotonic()
    try:
        with pytest.raises(RecordError, match=message):
            load_csv(path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert time.monotonic() - t0 < 1.0
    assert peak < 1 << 20


def test_max_bytes_argument_lowers_the_limit(tmp_path):
    path = write_bytes(tmp_path, GOOD.encode())
    with pytest.raises(RecordError, match=r"larger than the 0 MiB limit"):
        load_csv(path, max_bytes=10)


@pytest.mark.parametrize("dt", [0.0, -0.1, float("nan"), float("inf")])
def test_record_from_arrays_refuses_a_non_positive_or_non_finite_dt(dt):
    with pytest.raises(RecordError, match="dt must be a positive number"):
        Record.from_arrays(np.zeros(3), np.zeros(3), dt, name="r")


def test_record_refuses_columns_that_disagree_on_the_coordinates():
    with pytest.raises(RecordError, match=r"r: displacement has shape \(3, 2\), expected \(T,\)"):
        Record(np.arange(3.0), np.zeros((3, 2)), np.zeros((3, 2)), name="r", coords=("x",))
    with pytest.raises(RecordError, match=r"r: force has shape \(3,\), expected \(T, 2\)"):
        Record(time=np.arange(3.0), displacement=np.zeros((3, 2)), force=np.zeros(3), name="r")
    with pytest.raises(RecordError, match=r"r: time has shape \(3, 1\), expected \(T,\)"):
        Record(np.zeros((3, 1)), np.zeros(3), np.zeros(3), name="r")


def test_validate_names_the_sample_of_a_repeat_in_an_in_memory_record():
    r = Record(time=np.array([0.0, 0.1, 0.1]), displacement=np.zeros(3), force=np.zeros(3))
    with pytest.raises(RecordError, match=r"record sample 2: time repeats"):
        r.validate()


@pytest.mark.parametrize(("dt", "message"), [(0.0, "positive"), (10.0, "shorter than one step")])
def test_resample_refuses_a_bad_or_too_long_step(tmp_path, dt, message):
    r = load_csv(write_bytes(tmp_path, GOOD.encode()))
    with pytest.raises(RecordError, match=message):
        resample(r, dt)
