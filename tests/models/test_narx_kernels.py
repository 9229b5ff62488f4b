"""Generated NARX kernels (narx_kernels.py) against the generic reference kernel (kernels.py)."""

import copy
import pickle
import re

import numpy as np
import pytest

from bushenv.models import ModelError, get_model
from bushenv.models.kernels import narx_kernel
from bushenv.models.narx import NarxBushing
from bushenv.models.narx_kernels import (
    CACHE_ENV,
    NarxShape,
    _place_module,
    _write_module,
    cache_dir,
    column_split,
    generate_source,
    narx_kernels,
)

SHAPES = [
    NarxShape(5, 5, 9, 0),
    NarxShape(5, 5, 10, 9),
    NarxShape(2, 3, 4, 3),
    NarxShape(1, 1, 1, 0),
]


def network(shape, seed):
    rng = np.random.default_rng(seed)
    n_in = 1 + shape.n_past_x + shape.n_past_f
    h_last = shape.h2 or shape.h1
    return dict(
        w1=rng.normal(size=(shape.h1, n_in)) * 1.5,
        b1=rng.normal(size=shape.h1) * 0.3,
        w2=rng.normal(size=(shape.h2, shape.h1)),
        b2=rng.normal(size=shape.h2) * 0.3,
        w_out=rng.normal(size=h_last),
        b_out=0.1,
    )


def run(kernel, shape, net, x, v, state, k, c):
    out = np.empty_like(x)
    lags = (shape.n_past_x, shape.n_past_f) if kernel is narx_kernel else ()
    cols = (0, x.shape[1]) if kernel is narx_kernels(shape).run_rows else ()
    kernel(x, v, state, *lags, 1e-4, 2e-3, 5.0, 300.0, net["w1"], net["b1"], net["w2"],
           net["b2"], net["w_out"], net["b_out"], k, c, out, *cols)  # fmt: skip
    return out


@pytest.mark.parametrize("shape", SHAPES, ids=str)
@pytest.mark.parametrize("batch", [1, 3, 8, 37])
def test_generated_kernels_give_the_reference_kernels_bits(shape, batch):
    rng = np.random.default_rng(batch)
    net = network(shape, seed=batch)
    T = 97
    x = np.cumsum(rng.normal(size=(T, batch)), axis=0) * 1e-3
    x[5, 0] = 40.0  # deep in tanh saturation
    v = rng.normal(size=(T, batch))
    n_state = 1 + shape.n_past_x + shape.n_past_f
    start = rng.normal(size=(n_state, batch))
    start[0] = 7.0  # mid-period ring counter
    ref_state = start.copy()
    ref = run(narx_kernel, shape, net, x, v, ref_state, 3e5, 900.0)
    kern = narx_kernels(shape)
    for variant in (kern.run_rows, kern.run_cols):
        state = start.copy()
        got = run(variant, shape, net, x, v, state, 3e5, 900.0)
        assert np.array_equal(got, ref)
        assert np.array_equal(state, ref_state)
    if batch == 1:
        state = start.copy()
        got = [
            kern.step_one(x[t, 0], v[t, 0], state, 1e-4, 2e-3, 5.0, 300.0, net["w1"], net["b1"],
                          net["w2"], net["b2"], net["w_out"], net["b_out"], 3e5, 900.0)
            for t in range(T)
        ]  # fmt: skip
        assert np.array_equal(got, ref[:, 0])
        assert np.array_equal(state, ref_state)


def test_generated_kernels_resume_mid_run_like_one_long_run():
    shape = SHAPES[2]
    net = network(shape, seed=1)
    rng = np.random.default_rng(2)
    x = rng.normal(size=(60, 9)) * 1e-3
    kern = narx_kernels(shape)
    state = np.zeros((1 + shape.n_past_x + shape.n_past_f, 9))
    whole = run(kern.run_rows, shape, net, x, x, state.copy(), 0.0, 0.0)
    parts = []
    for lo, hi, variant in (
        (0, 13, kern.run_cols),
        (13, 14, kern.run_rows),
        (14, 60, kern.run_cols),
    ):
        parts.append(run(variant, shape, net, x[lo:hi].copy(), x[lo:hi].copy(), state, 0.0, 0.0))
    assert np.array_equal(np.concatenate(parts), whole)


def test_nan_input_gives_nan_in_every_variant():
    shape = SHAPES[0]
    net = network(shape, seed=0)
    x = np.full((4, 2), 1e-3)
    x[1, 1] = np.nan
    kern = narx_kernels(shape)
    n_state = 1 + shape.n_past_x + shape.n_past_f
    for kernel in (narx_kernel, kern.run_rows, kern.run_cols):
        out = run(kernel, shape, net, x, x, np.zeros((n_state, 2)), 0.0, 0.0)
        assert np.all(np.isfinite(out[:, 0]))
        assert np.all(np.isnan(out[1:, 1]))


@pytest.mark.parametrize("name", ["nn", "hybrid"])
def test_one_profile_path_equals_its_column_in_a_wide_batch(name):
    m = get_model(name, axis="radial")
    rng = np.random.default_rng(5)
    x = np.cumsum(rng.normal(size=(500, 70)), axis=0) * 1e-4
    batched = m.simulate(x)
    for b in (0, 33, 69):
        assert np.array_equal(m.simulate(x[:, b]), batched[:, b])
    v = np.gradient(x[:, 69], m.dt)  # what simulate uses
    m.reset(1)
    stepped = [m.step(x[t, 69], v[t]) for t in range(500)]
    assert np.array_equal(stepped, batched[:, 69])


def test_pickled_and_deep_copied_models_give_the_same_forces():
    m = NarxBushing.initialised((-0.002, 0.002), (-900.0, 1100.0), seed=3)
    x = np.linspace(0.0, 0.002, 80)
    before = m.simulate(x)
    assert np.array_equal(pickle.loads(pickle.dumps(m)).simulate(x), before)
    assert np.array_equal(copy.deepcopy(m).simulate(x), before)


def test_generated_source_names_its_shape_and_is_deterministic():
    a = generate_source(NarxShape(2, 3, 4, 3))
    assert a == generate_source((2, 3, 4, 3))
    assert "(2, 3, 4, 3)" in a.splitlines()[0]
    assert a != generate_source(NarxShape(2, 3, 4, 0))


def test_module_file_is_rewritten_only_when_its_source_changes(tmp_path):
    path = _write_module(tmp_path / "k", "mod_a", "X = 1\n")
    stamp = path.stat().st_mtime_ns
    assert _write_module(tmp_path / "k", "mod_a", "X = 1\n").stat().st_mtime_ns == stamp
    _write_module(tmp_path / "k", "mod_a", "X = 2\n")
    assert path.read_text() == "X = 2\n"
    assert [p.name for p in (tmp_path / "k").iterdir()] == ["mod_a.py"]  # no temp files left


def test_cache_folder_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "kc"))
    assert cache_dir() == tmp_path / "kc"
    monkeypatch.delenv(CACHE_ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "xdg" / "bushenv" / "kernels"


@pytest.mark.parametrize("name", ["nn", "hybrid"])
def test_step_gives_simulate_bits_for_floats_numpy_scalars_and_arrays(name):
    m = get_model(name, axis="axial")
    rng = np.random.default_rng(8)
    x = np.cumsum(rng.normal(size=120)) * 1e-4
    v = np.gradient(x, m.dt)
    ref = m.simulate(x, v)
    for convert in (float, np.float64, lambda a: np.array([a])):
        m.reset(1)
        got = np.array([m.step(convert(x[t]), convert(v[t])) for t in range(120)]).ravel()
        assert np.array_equal(got, ref)
    m.reset(1)
    assert isinstance(m.step(0.001, 0.0), float)
    assert isinstance(m.step(0, 1), float)  # ints take the generic path


def test_scalar_step_on_a_batch_is_refused():
    m = get_model("nn", axis="axial")
    m.reset(3)
    with pytest.raises(ModelError, match="scalar step on a batch of 3"):
        m.step(0.001, 0.0)


def test_run_rows_on_a_column_range_advances_only_those_columns():
    shape = SHAPES[0]
    net = network(shape, seed=4)
    rng = np.random.default_rng(4)
    x = rng.normal(size=(30, 40)) * 1e-3
    kern = narx_kernels(shape)
    start = np.zeros((1 + shape.n_past_x + shape.n_past_f, 40))
    whole_state = start.copy()
    whole = run(kern.run_rows, shape, net, x, x, whole_state, 0.0, 0.0)
    state, out = start.copy(), np.full_like(x, -1.0)
    for lo, hi in ((16, 40), (0, 16), (40, 40)):
        kern.run_rows(x, x, state, 1e-4, 2e-3, 5.0, 300.0, net["w1"], net["b1"], net["w2"],
                      net["b2"], net["w_out"], net["b_out"], 0.0, 0.0, out, lo, hi)  # fmt: skip
        if lo == 16:
            assert np.all(out[:, :16] == -1.0) and np.all(state[:, :16] == 0.0)
    assert np.array_equal(out, whole)
    assert np.array_equal(state, whole_state)


@pytest.mark.parametrize("batch", [9, 37, 1000])
@pytest.mark.parametrize("threads", [2, 3])
def test_threaded_simulate_gives_the_single_thread_bits(batch, threads):
    m = get_model("hybrid", axis="radial")
    rng = np.random.default_rng(batch)
    x = np.cumsum(rng.normal(size=(200, batch)), axis=0) * 1e-4
    one = m.simulate(x)
    state = m.state.copy()
    assert np.array_equal(m.simulate(x, threads=threads), one)
    assert np.array_equal(m.state, state)
    assert m._threads == 1  # the setting lasts one call


@pytest.mark.parametrize("bad", [0, -2, 1.5, True, "2"])
def test_threads_must_be_a_positive_integer(bad):
    m = get_model("nn", axis="axial")
    with pytest.raises(ModelError, match="threads must be a positive integer"):
        m.simulate(np.zeros((5, 16)), threads=bad)


def test_column_split_uses_whole_vectors_and_covers_every_column_once():
    for batch in (1, 7, 8, 9, 100, 1000, 1024, 1025):
        for parts in (1, 2, 3, 4):
            ranges = column_split(batch, parts)
            assert ranges[0][0] == 0 and ranges[-1][1] == batch
            assert all(a[1] == b[0] for a, b in zip(ranges[:-1], ranges[1:], strict=True))
            assert all(lo % 8 == 0 and hi > lo for lo, hi in ranges)
            assert len(ranges) <= parts
    assert column_split(1024, 2) == [(0, 512), (512, 1024)]


def test_unwritable_cache_folder_falls_back_to_a_temp_folder(monkeypatch, tmp_path):
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("")
    monkeypatch.setenv(CACHE_ENV, str(blocker / "kernels"))
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    path = _place_module("mod_b", "X = 3\n")
    assert path.parent.parent == tmp_path / "tmp"
    assert path.read_text() == "X = 3\n"


# ----- float32 (simulate(..., dtype="float32")) ---------------------------------------------
def shaped_model(shape, seed=0):
    # Weights scaled down so the recurrence forgets (contracts) like a trained model's: a
    # random net at full scale is chaotic, and there float32 and float64 runs part ways, as
    # any two runs with different rounding would.
    net = network(shape, seed)
    net["w1"] *= 0.2
    net["w_out"] *= 0.5
    return NarxBushing(
        x_offset_m=1e-4, x_scale_m=2e-3, f_offset_n=5.0, f_scale_n=300.0,
        n_past_x=shape.n_past_x, n_past_f=shape.n_past_f, **net,
    )  # fmt: skip


def random_drive(T, batch, seed):
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.normal(size=(T, batch)), axis=0) * 2e-4
    return x, np.gradient(x, 1 / 204.8, axis=0)


@pytest.mark.parametrize("shape", SHAPES, ids=str)
def test_float32_source_has_no_float64_constant_and_float64_source_is_unchanged(shape):
    src32 = generate_source(shape, "float32")
    body = src32.split("import numpy as np", 1)[1]
    # every float constant is wrapped in np.float32(...), but the 0.0 of the sign test (a
    # comparison, which promotes nothing)
    bare = re.findall(r"(?<!np\.float32\()(?<![\w.])(\d+\.\d*(?:e-?\d+)?)", body)
    assert set(bare) <= {"0.0"}, set(bare)
    assert "np.float32(" in body
    assert "float32" not in generate_source(shape)
    with pytest.raises(ValueError, match="dtype must be one of"):
        generate_source(shape, "float16")


@pytest.mark.parametrize("shape", SHAPES, ids=str)
def test_float32_run_is_single_precision_and_close_to_float64(shape):
    model = shaped_model(shape, seed=1)
    x, v = random_drive(400, 16, seed=2)
    f64 = model.simulate(x, v)
    f32 = model.simulate(x.astype(np.float32), v.astype(np.float32), dtype="float32")
    assert f32.dtype == np.float32 and f32.shape == f64.shape
    err = np.max(np.abs(f32 - f64)) / np.max(np.abs(f64))
    assert 0 < err < 1e-4, err  # the shipped models: ~3e-6 (docs/benchmarks.md)


@pytest.mark.parametrize("name", ["nn", "hybrid"])
def test_float32_shipped_models_stay_within_the_stated_error(name):
    model = get_model(name, axis="radial")
    x, v = random_drive(2048, 24, seed=3)
    f64 = model.simulate(x, v)
    f32 = model.simulate(x, v, dtype="float32")  # float64 in: cast on the way
    assert np.max(np.abs(f32 - f64)) < 1e-5 * np.max(np.abs(f64))


@pytest.mark.parametrize("batch", [37, 64])
def test_float32_columns_threads_and_one_profile_give_the_same_bits(batch):
    model = get_model("nn", axis="axial")
    x, v = random_drive(300, batch, seed=4)
    x, v = x.astype(np.float32), v.astype(np.float32)
    wide = model.simulate(x, v, dtype="float32")
    assert np.array_equal(model.simulate(x, v, dtype="float32", threads=2), wide)
    for b in (0, batch // 2, batch - 1):  # alone: the one-profile (register) kernel
        assert np.array_equal(model.simulate(x[:, b], v[:, b], dtype="float32"), wide[:, b])


def test_float32_run_leaves_its_final_state_and_float64_runs_are_untouched():
    model = get_model("nn", axis="axial")
    x, v = random_drive(200, 3, seed=5)
    before = model.simulate(x, v)
    model.simulate(x, v, dtype="float32")
    assert model.state.dtype == np.float64 and model.state.shape[1] == 3
    ring = model.state[1 + model.n_past_x :, :]
    assert np.array_equal(ring, ring.astype(np.float32))  # the float32 run's own history
    assert np.array_equal(model.simulate(x, v), before)


@pytest.mark.parametrize("bad", ["float16", np.float32, "f4", None])
def test_unknown_dtype_is_refused_naming_the_choices(bad):
    model = get_model("nn", axis="axial")
    with pytest.raises(ModelError, match=r"dtype must be one of \('float64', 'float32'\)"):
        model.simulate(np.zeros(10), dtype=bad)
