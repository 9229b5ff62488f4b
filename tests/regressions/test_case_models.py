"""Cases that name a model file by a path relative to the corpus: replayed wherever pytest runs.

The shipped models change (retrained); the failures the old ones had stay in the corpus by
naming the old files, kept in ``tests/regressions/models/``, as ``../models/<file>.npz``.
"""

from pathlib import Path

import numpy as np
import pytest

from bushenv.models import file_hash, get_reference
from bushenv.models.linear import LinearBushing
from bushenv.search.corpus import CorpusError, case_files, check, load_case, make_case, save_case
from bushenv.search.families import get_family

HERE = Path(__file__).parent
OLD_MODELS = HERE / "models"


def _saved_case(tmp_path: Path) -> Path:
    models_dir, corpus = tmp_path / "models", tmp_path / "corpus"
    models_dir.mkdir()
    stiff = LinearBushing(k_n_per_m=400e3, c_ns_per_m=4e3)
    stiff.save(models_dir / "stiff.npz")
    spec = "../models/stiff.npz"
    x = get_family("step").profile(np.array([0.7, 0.2, 0.0, 0.5]))
    case = make_case(
        x,
        env="rig",
        axis="axial",
        family="step",
        params=[0.7, 0.2, 0.0, 0.5],
        found_by={"searcher": "cma", "seed": 0, "model": spec, "model_sha256": None},
        models={spec: stiff, "linear": LinearBushing(k_n_per_m=380e3, c_ns_per_m=4.4e3)},
        reference=get_reference("rubber", axis="axial"),
        shas={spec: file_hash(models_dir / "stiff.npz")},
    )
    return save_case(case, corpus)


def test_a_model_file_named_relative_to_the_corpus_replays_from_another_folder(
    tmp_path, monkeypatch
):
    path = _saved_case(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    case = load_case(path)
    assert "../models/stiff.npz" in case.expect
    assert check(case, resolve=_registered_linear_only) == []


def _registered_linear_only(spec, axis, dt):
    # "linear" is the registered preset; anything else must be the resolved file
    from bushenv.models import get_model

    if spec != "linear":
        assert Path(spec).is_file(), spec
    return get_model(spec, axis=axis, dt=dt)


def test_a_missing_model_file_is_replayed_from_its_kept_copy_and_refused_when_that_is_gone(
    tmp_path,
):
    path = _saved_case(tmp_path)
    (tmp_path / "models" / "stiff.npz").unlink()
    case = load_case(path)
    notes = []
    assert check(case, notes=notes) == []
    assert any("replayed the copy kept with the corpus" in n for n in notes)
    (path.parent / case.expect["../models/stiff.npz"]["file"]["kept"]).unlink()
    with pytest.raises(CorpusError, match=f"case {case.name}: a model it names cannot be loaded"):
        check(case)


def test_every_model_file_a_corpus_case_names_is_kept_with_its_hash():
    named = 0
    for path in case_files(HERE / "corpus"):
        case = load_case(path)
        for spec, verdict in case.expect.items():
            if not spec.endswith(".npz"):
                continue
            named += 1
            file = (path.parent / spec).resolve()
            assert file.parent == OLD_MODELS.resolve(), (case.name, spec)
            assert file_hash(file) == verdict["sha256"], (case.name, spec)
    assert named > 0
