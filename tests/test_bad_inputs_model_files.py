"""Bad model files: each is refused with a ``ModelError`` naming the file and what was expected;
pickled data is never unpickled (a malicious payload in an .npz is not executed).

The catalogue with the messages is docs/bad-inputs.md.
"""

import json
import pickle
import subprocess
import sys

import numpy as np
import pytest

from bushenv.models import ModelError, get_model, load_model
from bushenv.models.hybrid import HybridBushing
from bushenv.models.linear import LinearBushing
from bushenv.models.narx import NarxBushing

DT = 1 / 204.8


@pytest.fixture()
def linear_file(tmp_path):
    return LinearBushing.preset("axial").save(tmp_path / "linear.npz")


def small_narx(hidden=(9,), seed=0) -> NarxBushing:
    return NarxBushing.initialised((-4e-3, 4e-3), (-2e3, 2e3), seed=seed, hidden=hidden)


def arrays_and_meta(path):
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    return arrays, json.loads(str(arrays.pop("__meta__")))


def write_model_file(path, meta, arrays):
    np.savez(path, __meta__=np.array(json.dumps(meta)), **arrays)
    return path


# ----- not a model file at all -------------------------------------------------------------
@pytest.mark.parametrize(
    ("content", "message"),
    [
        pytest.param(b"k = 4e5\nc = 4e3\n", "a text file", id="text"),
        pytest.param(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "a PNG image", id="png"),
        pytest.param(pickle.dumps({"k": 4e5}), "a Python pickle", id="pickle"),
        pytest.param(b"", "empty file", id="empty"),
        pytest.param(b"\x1f\x8b\x08\x00", "a gzip file", id="gzip"),
        pytest.param(b"\xde\xad\xbe\xef" * 8, "unknown binary data", id="random-bytes"),
    ],
)
def test_non_archive_is_refused_saying_what_it_is(tmp_path, content, message):
    path = tmp_path / "model.npz"
    path.write_bytes(content)
    with pytest.raises(ModelError, match=rf"model\.npz: not a bushenv model file: {message}"):
        load_model(path)


def test_lone_npy_array_is_refused_as_not_an_archive(tmp_path):
    path = tmp_path / "weights.npy"
    np.save(path, np.zeros((9, 11)))
    with pytest.raises(ModelError, match=r"weights\.npy: .*a single \.npy array"):
        load_model(path)


def test_missing_file_and_folder_are_refused(tmp_path):
    with pytest.raises(ModelError, match=r"nope\.npz: no such model file"):
        load_model(tmp_path / "nope.npz")
    with pytest.raises(ModelError, match="not a regular file"):
        load_model(tmp_path)


def test_zip_without_meta_is_refused(tmp_path):
    path = tmp_path / "plain.npz"
    np.savez(path, w=np.zeros(3))
    with pytest.raises(ModelError, match=r"plain\.npz: not a bushenv model file \(no __meta__"):
        load_model(path)


# ----- damaged ---------------------------------------------------------------------------------
@pytest.mark.parametrize("fraction", [0.05, 0.5, 0.99])
def test_truncated_file_is_refused(tmp_path, linear_file, fraction):
    data = linear_file.read_bytes()
    cut = tmp_path / "cut.npz"
    cut.write_bytes(data[: int(len(data) * fraction)])
    with pytest.raises(ModelError, match=r"cut\.npz: damaged or truncated \.npz archive"):
        load_model(cut)


def test_flipped_byte_inside_a_parameter_is_refused_by_the_checksum(tmp_path, linear_file):
    data = bytearray(linear_file.read_bytes())
    i = data.find(b"\x93NUMPY", data.find(b"k_n_per_m")) + 128  # inside the array's payload
    data[i] ^= 0xFF
    bad = tmp_path / "flipped.npz"
    bad.write_bytes(bytes(data))
    with pytest.raises(ModelError, match=r"flipped\.npz: damaged.*CRC"):
        load_model(bad)


# ----- pickles are never executed --------------------------------------------------------------
class _Payload:
    """Unpickling this creates ``marker``: proof that code ran."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


def test_malicious_pickle_inside_an_npz_is_not_executed(tmp_path):
    marker = tmp_path / "code_ran"
    payload = np.array([_Payload(marker)], dtype=object)
    # the payload is live: unpickling it does run code
    pickle.loads(pickle.dumps(_Payload(marker))).close()
    assert marker.exists()
    marker.unlink()
    meta = {"format": "bushenv-model", "version": 1, "model": "linear", "dt": DT}
    path = tmp_path / "evil.npz"
    np.savez(path, __meta__=np.array(json.dumps(meta)), k_n_per_m=payload, c_ns_per_m=1.0)
    with pytest.raises(ModelError, match=r"evil\.npz: holds pickled \(object\) data.*never loads"):
        load_model(path)
    with pytest.raises(ModelError, match="pickled"):
        get_model(str(path))
    assert not marker.exists()


def test_plain_pickle_file_is_not_executed(tmp_path):
    marker = tmp_path / "code_ran"
    path = tmp_path / "model.pkl"
    path.write_bytes(pickle.dumps(_Payload(marker)))
    with pytest.raises(ModelError, match=r"model\.pkl: .*a Python pickle"):
        load_model(path)
    assert not marker.exists()


# ----- another version, another model, another architecture, another dt ----------------------
def _meta_case(linear_file, **changes):
    arrays, meta = arrays_and_meta(linear_file)
    meta.update(changes)
    return arrays, meta


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"version": 2}, "format version 2, this bushenv reads version 1"),
        ({"version": "1"}, "format version '1'"),
        ({"format": "other"}, r"not a bushenv model file \(format tag 'other', expected"),
        (
            {"model": "lstm"},
            r"unknown model 'lstm'; known names: "
            r"linear, nn, nn-axis, hybrid, nn-paper, hybrid-paper, boucwen, hybrid-bw, rubber",
        ),
        ({"coords": "axial"}, r"corrupt __meta__ entry \(coords 'axial', expected names\)"),
        ({"model": ["linear"]}, r"unknown model \['linear'\]"),
        ({"dt": "fast"}, r"invalid dt 'fast' in the header"),
        ({"dt": -0.1}, r"invalid dt -0\.1"),
        ({"dt": None}, r"invalid dt None"),
        ({"shapes": [1, 2]}, r"corrupt __meta__ entry \('shapes' and 'extra' must be objects"),
        ({"extra": "x"}, r"corrupt __meta__ entry"),
        ({"shapes": {"k_n_per_m": [2]}}, r"'k_n_per_m' has shape \[\], the file's header says"),
    ],
)
def test_bad_header_is_refused_naming_file_and_field(tmp_path, linear_file, changes, message):
    arrays, meta = _meta_case(linear_file, **changes)
    path = write_model_file(tmp_path / "m.npz", meta, arrays)
    with pytest.raises(ModelError, match=rf"m\.npz: .*{message}"):
        load_model(path)


@pytest.mark.parametrize(
    ("meta_value", "message"),
    [
        (np.array(3.0), r"corrupt __meta__ entry \(a float64 array"),
        (np.array(b"{}"), r"corrupt __meta__ entry \(a \|S2 array"),
        (np.array(["{}", "{}"]), r"corrupt __meta__ entry \(a <U2 array of shape \[2\]"),
        (np.array("{not json"), r"corrupt __meta__ entry: Expecting property name"),
        (np.array("[1, 2]"), r"not a bushenv model file \(format tag missing"),
    ],
)
def test_corrupt_meta_entry_is_refused(tmp_path, meta_value, message):
    path = tmp_path / "m.npz"
    np.savez(path, __meta__=meta_value, k_n_per_m=1.0, c_ns_per_m=1.0)
    with pytest.raises(ModelError, match=message):
        load_model(path)


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (np.array("400000"), r"'k_n_per_m' holds <U6 data, expected real numbers"),
        (np.array(1 + 2j), r"'k_n_per_m' holds complex128 data"),
        (np.array(np.nan), r"'k_n_per_m' holds NaN or inf"),
        (np.array(-np.inf), r"'k_n_per_m' holds NaN or inf"),
        (np.ones(3), r"parameters do not fit a linear model"),
    ],
)
def test_bad_parameter_is_refused_naming_it(tmp_path, linear_file, value, message):
    arrays, meta = arrays_and_meta(linear_file)
    arrays["k_n_per_m"] = value
    meta["shapes"]["k_n_per_m"] = list(value.shape)
    path = write_model_file(tmp_path / "m.npz", meta, arrays)
    with pytest.raises(ModelError, match=rf"m\.npz: .*{message}"):
        load_model(path)


def test_missing_parameter_is_refused_naming_it(tmp_path, linear_file):
    arrays, meta = arrays_and_meta(linear_file)
    del arrays["c_ns_per_m"]
    path = write_model_file(tmp_path / "m.npz", meta, arrays)
    with pytest.raises(ModelError, match=r"m\.npz: linear model file lacks parameter 'c_ns_per_m'"):
        load_model(path)


def test_nn_file_whose_weight_shapes_do_not_chain_is_refused(tmp_path):
    arrays, meta = arrays_and_meta(small_narx().save(tmp_path / "nn.npz"))
    arrays["w1"] = np.zeros((5, arrays["w1"].shape[1]))  # 5 hidden units, but b1 has 9
    meta["shapes"]["w1"] = [5, arrays["w1"].shape[1]]
    path = write_model_file(tmp_path / "nn_bad.npz", meta, arrays)
    with pytest.raises(
        ModelError, match=r"nn_bad\.npz: parameter 'b1' has shape \[9\], expected \[5\]"
    ):
        load_model(path)


def test_hybrid_file_with_second_layer_of_other_hidden_sizes_is_refused(tmp_path):
    net = small_narx(hidden=(9,))
    hybrid = HybridBushing(
        k_n_per_m=379.68e3, c_ns_per_m=4.4e3, **{k: getattr(net, k) for k in net.param_names}
    )
    arrays, meta = arrays_and_meta(hybrid.save(tmp_path / "hybrid.npz"))
    two_layer, _ = arrays_and_meta(small_narx(hidden=(10, 9)).save(tmp_path / "nn2.npz"))
    for key in ("w2", "b2", "w_out"):  # a (10, 9) net's later layers on a (9,) net's first
        arrays[key] = two_layer[key]
        meta["shapes"][key] = list(two_layer[key].shape)
    path = write_model_file(tmp_path / "hybrid_mixed.npz", meta, arrays)
    with pytest.raises(ModelError, match=r"hybrid_mixed\.npz: parameter 'w2' has shape \[9, 10\]"):
        load_model(path)


def test_file_of_another_sample_time_is_refused_when_a_dt_is_asked(tmp_path):
    path = small_narx().save(tmp_path / "nn.npz")
    message = r"nn\.npz: model sampled at 204\.8 Hz .*expected 1000 Hz"
    with pytest.raises(ModelError, match=message):
        load_model(path, dt=1e-3)
    with pytest.raises(ModelError, match=message):
        get_model(str(path), dt=1e-3)
    assert load_model(path, dt=DT).dt == DT  # the right dt loads


def test_file_of_a_model_in_a_module_not_yet_imported_loads(tmp_path):
    # load_model must fill the registry itself: in a fresh interpreter only base is imported
    from bushenv.models.boucwen import BoucWenBushing

    path = BoucWenBushing.preset("radial").save(tmp_path / "bw.npz")
    code = (
        "import sys; from bushenv.models.files import load_model; "
        "print(type(load_model(sys.argv[1])).__name__)"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "BoucWenBushing"


@pytest.mark.parametrize(
    ("spec", "kwargs", "message"),
    [
        ("lstm", {}, r"unknown model 'lstm'; known names: linear, nn"),
        ("", {}, r"empty model name"),
        ("linear", {"axis": "sideways"}, r"unknown axis 'sideways'"),
        ("missing.npz", {}, r"missing\.npz: no such model file"),
    ],
)
def test_get_model_refuses_bad_names_axes_and_paths(spec, kwargs, message):
    with pytest.raises(ModelError, match=message):
        get_model(spec, **kwargs)


def test_model_object_of_another_dt_is_refused():
    with pytest.raises(ModelError, match=r"runs at 1000 Hz \(dt=0\.001 s\), expected 204\.8 Hz"):
        get_model(LinearBushing.preset("axial", dt=1e-3), dt=DT)
