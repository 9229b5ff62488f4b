"""Property-based fuzzing (hypothesis) of every loader and every env action space.

Each ``check_*`` function is an oracle: given one generated input it returns normally when
bushenv answered correctly (a valid result, or the loader's own ``ValueError`` subclass naming
the file) and raises otherwise. The tests below run a few hundred examples each in the fast
suite; ``scripts/fuzz.py`` runs the same oracles on thousands and prints the figures.

Targets (name: input generated -> what bushenv must answer):

- record_bytes: arbitrary bytes, maybe after a magic number and/or a valid header -> a valid
  Record or a one-line RecordError naming the file
- record_mutations: a valid record file with 1-3 of 17 corruptions -> a valid Record or a
  RecordError naming the file (and the line, for a single line-local corruption)
- model_bytes: a valid model file (linear, nn, boucwen) with bytes flipped, cut, inserted ->
  a model that runs, or a ModelError naming the file
- model_fields: a valid model file with header fields or arrays replaced by random values ->
  same
- matrix_results: a cells.jsonl of good, torn, garbage, JSON and binary lines -> rows or a
  MatrixError; what was kept reads back the same from a repaired file
- seed_lists: text for ``--seeds`` -> seeds >= 0 or a MatrixError
- bushrig_actions: sequences of any numeric action (NaN, inf, 1e38, ints; float16/32/64,
  Python float, list) -> no exception, obs in the Box, x exactly the documented clip
- bushrig_any_action: any Python object (None, text, complex, dicts, lists, arrays of any
  shape) -> a step with obs in the Box, or a RigError naming the action space
- bushrig_nan_model: random actions, a model turning NaN at a random step -> the episode ends
  at that step with diverged=True and the reason
- vector_actions: (4, 1) action arrays with NaN/inf/huge entries -> each column as one env
- quartercar_actions: sequences of any numeric action -> no exception, obs in the Box
"""

from __future__ import annotations

import io
import json
import math
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_bad_inputs_envs import BadAfter  # NaN from sample after + 1 on

from bushenv.models import BushingModel, ModelError, load_model
from bushenv.records import (
    MAX_PLAUSIBLE_DISPLACEMENT_M,
    MAX_PLAUSIBLE_FORCE_N,
    STEP_ATOL_S,
    STEP_RTOL,
    RecordError,
    load_csv,
)
from bushenv.search.matrix import MatrixError, parse_seeds, read_results

FAST = settings(
    max_examples=200,
    derandomize=True,  # the fast suite is deterministic; scripts/fuzz.py explores at random
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    database=None,
)
FINITE = {"allow_nan": False, "allow_infinity": False}


# ===== records ==================================================================================
def assert_valid_record(record) -> None:
    t, x, f = record.time, record.displacement, record.force
    assert len(record) >= 2
    assert np.all(np.isfinite(t)) and np.all(np.isfinite(x)) and np.all(np.isfinite(f))
    steps = np.diff(t)
    assert np.all(steps > 0)
    dt = float(np.median(steps))
    assert np.all(np.abs(steps - dt) <= STEP_RTOL * dt + STEP_ATOL_S)
    assert np.max(np.abs(x)) <= MAX_PLAUSIBLE_DISPLACEMENT_M
    assert np.max(np.abs(f)) <= MAX_PLAUSIBLE_FORCE_N


def load_record_bytes(data: bytes, name: str = "fuzz.csv"):
    """``load_csv`` of a file holding ``data``: the Record, or the RecordError message."""
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, name)
        with open(path, "wb") as fh:
            fh.write(data)
        try:
            return load_csv(path)
        except RecordError as exc:
            message = str(exc)
            assert name in message, message
            assert "\n" not in message.strip(), message
            return message


MAGICS = [b"", b"\x89PNG\r\n\x1a\n", b"PK\x03\x04", b"\x1f\x8b\x08", b"\xff\xfe", b"%PDF-"]
HEADERS = [b"", b"time,displacement,force\n", b"\xef\xbb\xbftime,displacement,force\r\n"]


@st.composite
def record_bytes(draw):
    prefix = draw(st.sampled_from(MAGICS)) + draw(st.sampled_from(HEADERS))
    body = draw(
        st.one_of(
            st.binary(max_size=400),
            st.text(alphabet="0123456789.,-+eE naif\n\r\t;\"'", max_size=400).map(str.encode),
        )
    )
    return prefix + body


def check_record_bytes(data: bytes) -> None:
    result = load_record_bytes(data)
    if not isinstance(result, str):
        assert_valid_record(result)


@st.composite
def valid_record_text(draw):
    n = draw(st.integers(2, 40))
    dt = draw(st.sampled_from([1 / 204.8, 1e-3, 0.1, 1 / 6000]))
    t0 = draw(st.floats(-5, 5, **FINITE))
    x = draw(st.lists(st.floats(-0.0125, 0.0125, **FINITE), min_size=n, max_size=n))
    f = draw(st.lists(st.floats(-25e3, 25e3, **FINITE), min_size=n, max_size=n))
    rows = [f"{t0 + i * dt!r},{x[i]!r},{f[i]!r}" for i in range(n)]
    return ["time,displacement,force", *rows]


LINE_LOCAL = {"nan", "text", "repeat", "backwards", "millimetres", "jitter", "too_many"}
MUTATIONS = [
    "nan",
    "text",
    "repeat",
    "backwards",
    "millimetres",
    "jitter",
    "too_many",
    "too_few",
    "single_row",
    "empty",
    "header_typo",
    "header_order",
    "blank_inside",
    "cut_mid_line",
    "binary_magic",
    "semicolons",
    "quote",
]


def _number(line: str) -> float | None:
    """The first field of ``line`` as a finite float, or None."""
    try:
        value = float(line.split(",")[0])
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def mutate(lines: list[str], kind: str, data) -> list[str]:
    """Apply one corruption to a record's lines (header first)."""
    lines = list(lines)
    n = len(lines)
    row = data.draw(st.integers(1, n - 1), label="row")
    col = data.draw(st.integers(0, 2), label="col")
    fields = lines[row].split(",")
    if kind == "nan" and len(fields) == 3:
        fields[col] = data.draw(st.sampled_from(["nan", "NaN", "inf", "-Infinity", "1e999"]))
    elif kind == "text" and len(fields) == 3:
        fields[col] = data.draw(st.sampled_from(["abc", "", "1,2", "0x1F", "--", "mm", "1.2.3"]))
    elif kind == "repeat" and row >= 2:
        fields[0] = lines[row - 1].split(",")[0]
    elif kind == "backwards" and row >= 2 and _number(lines[row - 1]) is not None:
        prev = _number(lines[row - 1])
        fields[0] = repr(prev - abs(prev) - 1.0)
    elif kind == "millimetres" and len(fields) == 3:
        fields[1] = repr(data.draw(st.floats(0.2, 12.5, **FINITE)))
    elif (
        kind == "jitter" and row >= 2 and None not in (_number(lines[row - 1]), _number(fields[0]))
    ):
        t_prev, t_here = _number(lines[row - 1]), _number(fields[0])
        fields[0] = repr(t_here + 0.3 * (t_here - t_prev))
    elif kind == "too_many":
        fields.append("0")
    elif kind == "too_few":
        fields = fields[:2]
    elif kind == "single_row":
        return lines[:2]
    elif kind == "empty":
        return []
    elif kind == "header_typo":
        lines[0] = data.draw(
            st.sampled_from(["time,displacment,force", "t,x,F", "Time,Displacement,Force"])
        )
        return lines
    elif kind == "header_order":
        lines[0] = "force,time,displacement"
        return lines
    elif kind == "blank_inside" and row < n - 1:
        lines.insert(row, "")
        return lines
    elif kind == "cut_mid_line":
        text = "\n".join(lines)
        cut = data.draw(st.integers(1, len(text)), label="cut")
        return text[:cut].split("\n")
    elif kind == "binary_magic":
        lines[0] = data.draw(st.sampled_from(["\x89PNG", "PK\x03\x04", "\x00"])) + lines[0]
        return lines
    elif kind == "semicolons":
        return [line.replace(",", ";") for line in lines]
    elif kind == "quote" and col < len(fields):
        fields[col] = '"' + fields[col]
    lines[row] = ",".join(fields)
    return lines


@st.composite
def mutated_record(draw):
    lines = draw(valid_record_text())
    kinds = draw(st.lists(st.sampled_from(MUTATIONS), min_size=1, max_size=3))
    data = draw(st.data())
    for kind in kinds:
        lines = mutate(lines, kind, data) if len(lines) >= 2 else lines
    return "\n".join(lines) + ("\n" if lines else ""), kinds


def check_record_mutation(case) -> None:
    text, kinds = case
    result = load_record_bytes(text.encode("utf-8", "surrogatepass"))
    if isinstance(result, str):
        if len(kinds) == 1 and kinds[0] in LINE_LOCAL:
            assert " line " in result, result
        return
    assert_valid_record(result)  # a corruption that still gives a valid record is fine


# ===== model files ==============================================================================
def _seed_model_files() -> dict[str, bytes]:
    from bushenv.models.boucwen import BoucWenBushing
    from bushenv.models.linear import LinearBushing
    from bushenv.models.narx import NarxBushing

    models = {
        "linear": LinearBushing.preset("axial"),
        "nn": NarxBushing.initialised((-4e-3, 4e-3), (-2e3, 2e3), seed=0),
        "boucwen": BoucWenBushing.preset("radial"),
    }
    out = {}
    with tempfile.TemporaryDirectory() as d:
        for name, model in models.items():
            out[name] = model.save(Path(d) / f"{name}.npz").read_bytes()
    return out


_MODEL_FILES: dict[str, bytes] = {}


def model_files() -> dict[str, bytes]:
    if not _MODEL_FILES:
        _MODEL_FILES.update(_seed_model_files())
    return _MODEL_FILES


def load_model_bytes(data: bytes, name: str = "fuzz.npz"):
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, name)
        with open(path, "wb") as fh:
            fh.write(data)
        try:
            model = load_model(path)
        except ModelError as exc:
            assert name in str(exc), str(exc)
            return str(exc)
    assert isinstance(model, BushingModel)
    try:  # a loaded model runs, or refuses to go on with its own clear error
        force = model.simulate(np.linspace(0.0, 1e-3, 16))
    except ModelError as exc:
        assert str(exc) and "\n" not in str(exc).strip()
        return model
    assert force.shape == (16,)
    return model


@st.composite
def model_byte_damage(draw):
    name = draw(st.sampled_from(["linear", "nn", "boucwen"]))
    data = bytearray(model_files()[name])
    for _ in range(draw(st.integers(1, 4))):
        how = draw(st.sampled_from(["flip", "cut", "insert", "zero_run"]))
        i = draw(st.integers(0, max(len(data) - 1, 0)))
        if how == "flip" and data:
            data[i] ^= draw(st.integers(1, 255))
        elif how == "cut":
            del data[i:]
        elif how == "insert":
            data[i:i] = draw(st.binary(min_size=1, max_size=16))
        elif how == "zero_run":
            data[i : i + draw(st.integers(1, 64))] = b"\x00" * 8
    return bytes(data)


def check_model_bytes(data: bytes) -> None:
    load_model_bytes(data)


JSON_VALUES = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(2**70), 2**70)
    | st.floats()
    | st.text(max_size=8)
    | st.sampled_from(["linear", "nn", "hybrid", "boucwen", "rubber", "bushenv-model"]),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner),
    max_leaves=6,
)
ARRAYS = st.sampled_from(
    [
        np.array(1.0),
        np.array(np.nan),
        np.zeros(0),
        np.ones((2, 3)),
        np.array("text"),
        np.array([1 + 1j]),
        np.array([True]),
        np.arange(5, dtype=np.int8),
        np.full(3, np.inf),
        np.array(1e308),
    ]
)


@st.composite
def model_field_damage(draw):
    name = draw(st.sampled_from(["linear", "nn", "boucwen"]))
    with np.load(_as_file(model_files()[name])) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays.pop("__meta__")))
    for _ in range(draw(st.integers(1, 3))):
        where = draw(st.sampled_from(["meta", "shapes", "array", "drop", "extra"]))
        if where == "meta":
            meta[draw(st.sampled_from(["format", "version", "model", "dt", "extra"]))] = draw(
                JSON_VALUES
            )
        elif where == "shapes" and isinstance(meta.get("shapes"), dict) and meta["shapes"]:
            key = draw(st.sampled_from(sorted(meta["shapes"])))
            meta["shapes"][key] = draw(JSON_VALUES)
        elif where == "array" and arrays:
            arrays[draw(st.sampled_from(sorted(arrays)))] = draw(ARRAYS)
        elif where == "drop" and arrays:
            del arrays[draw(st.sampled_from(sorted(arrays)))]
        elif where == "extra":
            arrays[draw(st.text("abcxyz_", min_size=1, max_size=6))] = draw(ARRAYS)
    buf = io.BytesIO()
    text = json.dumps(meta, allow_nan=True)
    np.savez(buf, __meta__=np.array(text), **arrays)
    return buf.getvalue()


def _as_file(data: bytes) -> io.BytesIO:
    return io.BytesIO(data)


def check_model_fields(data: bytes) -> None:
    load_model_bytes(data)


# ===== campaign results and arguments =====================================================
GOOD_ROW = {
    "model": "linear",
    "axis": "axial",
    "searcher": "random",
    "seed": 0,
    "budget": 8,
    "env": "rig",
    "diverged": False,
    "evaluations": 8,
    "evaluations_to_failure": None,
}


@st.composite
def results_file(draw):
    parts = []
    for i in range(draw(st.integers(0, 6))):
        kind = draw(st.sampled_from(["good", "torn", "garbage", "json", "binary", "blank"]))
        if kind == "good":
            parts.append(json.dumps({**GOOD_ROW, "seed": i}).encode() + b"\n")
        elif kind == "torn":
            line = json.dumps({**GOOD_ROW, "seed": i})
            parts.append(line[: draw(st.integers(0, len(line)))].encode())
        elif kind == "garbage":
            parts.append(draw(st.text(max_size=30)).encode("utf-8", "surrogatepass") + b"\n")
        elif kind == "json":
            parts.append(json.dumps(draw(JSON_VALUES)).encode() + b"\n")
        elif kind == "binary":
            parts.append(draw(st.binary(max_size=30)))
        else:
            parts.append(b"\n")
    return b"".join(parts)


def check_matrix_results(data: bytes) -> None:
    import contextlib
    import io

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "cells.jsonl"
        path.write_bytes(data)
        try:
            with contextlib.redirect_stdout(io.StringIO()):
                rows = read_results(path, require_results=True)
        except MatrixError as exc:
            assert "cells.jsonl" in str(exc)
            return
        for row in rows.values():
            assert all(k in row for k in ("model", "seed", "diverged"))
        # whatever was kept reads back the same (the repair left a clean file)
        with contextlib.redirect_stdout(io.StringIO()):
            assert read_results(path, require_results=True) == rows
        text = path.read_text()
        assert text == "" or text.endswith("\n")


def check_seed_list(text: str) -> None:
    try:
        seeds = parse_seeds(text)
    except MatrixError:
        return
    assert seeds and all(isinstance(s, int) and s >= 0 for s in seeds)


SEED_TEXT = st.one_of(st.text(max_size=12), st.text(alphabet="0123456789-, ", max_size=12))


# ===== environments ===========================================================================
ACTION_VALUES = st.one_of(
    st.floats(width=32),
    st.floats(),
    st.sampled_from([np.nan, np.inf, -np.inf, 1e38, -1e38, 0.0, -0.0, 1.0, -1.0]),
    st.integers(-(10**6), 10**6),
)
ACTION_FORMS = st.sampled_from(["float32", "float64", "float16", "python", "list"])


def as_action(value, form):
    if form == "python":
        return float(value)
    if form == "list":
        return [float(value)]
    with np.errstate(over="ignore"):
        return np.array([value], dtype=form)


def _clean(a) -> float:
    a = float(np.asarray(a, dtype=np.float64).reshape(-1)[0])
    return 0.0 if math.isnan(a) else max(-1.0, min(1.0, a))


_ENVS: dict[str, object] = {}


def cached_env(env_id: str, **kwargs):
    import gymnasium as gym

    import bushenv  # noqa: F401

    key = env_id + repr(sorted(kwargs.items()))
    if key not in _ENVS:
        _ENVS[key] = gym.make(env_id, **kwargs)
    return _ENVS[key]


def check_bushrig_actions(case) -> None:
    values, form = case
    env = cached_env("BushRig-v0")
    env.reset(seed=0)
    p = env.unwrapped.params
    x = 0.0
    for value in values:
        action = as_action(value, form)
        obs, reward, term, trunc, info = env.step(action)
        assert env.observation_space.contains(obs)
        assert math.isfinite(reward)
        x = max(-p.max_x, min(p.max_x, x + _clean(action) * p.max_step))
        assert info["displacement_m"] == x
        assert abs(info["displacement_m"]) <= p.max_x
        if term or trunc:
            break


def check_bushrig_nan_model(case) -> None:
    import gymnasium as gym

    import bushenv  # noqa: F401

    start, values = case
    env = gym.make("BushRig-v0", model=BadAfter(after=start - 1), reference="linear")
    try:
        _nan_model_episode(env, start, values)
    finally:
        env.close()


def _nan_model_episode(env, start: int, values) -> None:
    env.reset(seed=0)
    for k, value in enumerate(values, start=1):
        obs, reward, term, trunc, info = env.step(as_action(value, "float32"))
        assert env.observation_space.contains(obs)
        if k < start:
            assert not info["diverged"] or info["model_over_force_limit"]
        else:
            assert term and info["diverged"]
            assert info["divergence_reason"] == "model force is not finite"
            assert reward == env.unwrapped.reward_fn.cap
            return


def check_vector_actions(rows) -> None:
    venv = cached_vector_env(len(rows))
    venv.reset(seed=0)
    with np.errstate(over="ignore"):  # 1e300 -> inf in float32, as an agent might send
        actions = np.array(rows, dtype=np.float32).reshape(-1, 1)
    obs, rewards, term, trunc, info = venv.step(actions)
    p = venv.params if hasattr(venv, "params") else venv.unwrapped.params
    for i, a in enumerate(actions):
        assert info["displacement_m"][i] == max(-p.max_x, min(p.max_x, _clean(a) * p.max_step))
        assert venv.single_observation_space.contains(obs[i])
    assert np.all(np.isfinite(rewards))


def cached_vector_env(n: int):
    import gymnasium as gym

    import bushenv  # noqa: F401

    key = f"vector{n}"
    if key not in _ENVS:
        _ENVS[key] = gym.make_vec("BushRig-v0", num_envs=n, vectorization_mode="vector_entry_point")
    return _ENVS[key]


def check_quartercar_actions(case) -> None:
    values, form = case
    env = cached_env("QuarterCar-v0")
    env.reset(seed=0)
    for value in values:
        obs, reward, term, trunc, info = env.step(as_action(value, form))
        assert env.observation_space.contains(obs)
        assert math.isfinite(reward)
        assert isinstance(info["diverged"], bool)
        if term or trunc:
            break


ANY_ACTION = st.one_of(
    st.none(),
    st.text(max_size=6),
    st.complex_numbers(),
    st.booleans(),
    st.dictionaries(st.text(max_size=3), st.floats(), max_size=2),
    st.lists(st.one_of(st.floats(), st.none(), st.text(max_size=2)), max_size=4),
    st.tuples(st.integers(0, 3), st.integers(0, 3), st.floats(-2, 2)).map(
        lambda t: np.full((t[0], t[1]), t[2], dtype=np.float32)
    ),
    st.sampled_from([np.float64(0.3), np.float32(np.nan), np.array(0.5), np.array([[0.5]])]),
)


def check_bushrig_any_action(action) -> None:
    """Any Python object as an action: a step in the Box, or a RigError naming the space."""
    from bushenv.rigs.common import RigError

    env = cached_env("BushRig-v0")
    env.reset(seed=0)
    try:
        with np.errstate(all="ignore"):
            obs, reward, term, trunc, info = env.step(action)
    except RigError as exc:
        assert "action" in str(exc) and "\n" not in str(exc).strip(), str(exc)
        return
    assert env.observation_space.contains(obs)
    assert math.isfinite(reward)


ACTION_SEQUENCES = st.tuples(st.lists(ACTION_VALUES, min_size=1, max_size=25), ACTION_FORMS)
NAN_MODEL_CASES = st.tuples(st.integers(1, 20), st.lists(ACTION_VALUES, min_size=20, max_size=20))
VECTOR_ROWS = st.lists(ACTION_VALUES, min_size=4, max_size=4)

# name -> (strategy, oracle); scripts/fuzz.py runs the same table with more examples
TARGETS = {
    "record_bytes": (record_bytes(), check_record_bytes),
    "record_mutations": (mutated_record(), check_record_mutation),
    "model_bytes": (model_byte_damage(), check_model_bytes),
    "model_fields": (model_field_damage(), check_model_fields),
    "matrix_results": (results_file(), check_matrix_results),
    "seed_lists": (SEED_TEXT, check_seed_list),
    "bushrig_actions": (ACTION_SEQUENCES, check_bushrig_actions),
    "bushrig_any_action": (ANY_ACTION, check_bushrig_any_action),
    "bushrig_nan_model": (NAN_MODEL_CASES, check_bushrig_nan_model),
    "vector_actions": (VECTOR_ROWS, check_vector_actions),
    "quartercar_actions": (ACTION_SEQUENCES, check_quartercar_actions),
}


def close_cached_envs() -> None:
    """Free the envs (and their pymunk spaces) while pymunk is still importable: a space
    freed during interpreter shutdown prints an ignored-exception traceback."""
    import gc

    for env in _ENVS.values():
        env.close()
    _ENVS.clear()
    gc.collect()


@pytest.fixture(scope="module", autouse=True)
def _close_cached_envs():
    yield
    close_cached_envs()


# ===== the fast-suite tests =====================================================================
@FAST
@given(record_bytes())
def test_fuzz_record_bytes_give_a_valid_record_or_a_record_error(data):
    check_record_bytes(data)


@settings(FAST, max_examples=300)
@given(mutated_record())
def test_fuzz_corrupted_records_are_refused_naming_file_and_line(case):
    check_record_mutation(case)


@FAST
@given(model_byte_damage())
def test_fuzz_damaged_model_files_load_and_run_or_give_a_model_error(data):
    check_model_bytes(data)


@FAST
@given(model_field_damage())
def test_fuzz_model_files_with_bad_fields_load_and_run_or_give_a_model_error(data):
    check_model_fields(data)


@FAST
@given(results_file())
def test_fuzz_campaign_results_files_read_or_give_a_matrix_error(data):
    check_matrix_results(data)


@FAST
@given(SEED_TEXT)
def test_fuzz_seed_lists_parse_to_non_negative_seeds_or_a_matrix_error(text):
    check_seed_list(text)


@FAST
@given(ACTION_SEQUENCES)
def test_fuzz_bushrig_any_numeric_action_is_cleaned_never_raises(case):
    check_bushrig_actions(case)


@FAST
@given(ANY_ACTION)
def test_fuzz_bushrig_any_object_as_action_steps_or_gives_a_rig_error(action):
    check_bushrig_any_action(action)


@settings(FAST, max_examples=100)
@given(NAN_MODEL_CASES)
def test_fuzz_bushrig_model_turning_nan_ends_the_episode_at_that_step(case):
    check_bushrig_nan_model(case)


@settings(FAST, max_examples=100)
@given(VECTOR_ROWS)
def test_fuzz_vector_env_cleans_every_column_like_a_single_env(rows):
    check_vector_actions(rows)


@settings(FAST, max_examples=100)
@given(ACTION_SEQUENCES)
def test_fuzz_quartercar_any_numeric_action_is_cleaned_never_raises(case):
    check_quartercar_actions(case)


def test_fuzz_targets_cover_every_loader_and_action_space():
    assert set(TARGETS) >= {"record_bytes", "model_bytes", "matrix_results", "bushrig_actions"}
    assert all(callable(check) for _, check in TARGETS.values())


@pytest.mark.parametrize("name", ["linear", "nn", "boucwen"])
def test_seed_model_files_load_untouched(name):
    assert isinstance(load_model_bytes(model_files()[name]), BushingModel)
    assert zipfile.is_zipfile(_as_file(model_files()[name]))


def test_fuzz_script_counts_crashes_and_keeps_going(monkeypatch):
    import importlib.util

    from hypothesis import strategies as hs

    path = Path(__file__).resolve().parents[1] / "scripts" / "fuzz.py"
    spec = importlib.util.spec_from_file_location("fuzz_script", path)
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)

    def odd_fails(n: int) -> None:
        if n % 2:
            raise ValueError(f"odd {n}\nsecond line")

    monkeypatch.setitem(TARGETS, "odd", (hs.integers(0, 10**6), odd_fails))
    stats = script.run_target("odd", 200, run_seed=0)
    assert stats["examples"] == 200
    assert 0 < stats["crashes"] < 200
    assert all(line.startswith("ValueError: odd ") for line in stats["errors"])
