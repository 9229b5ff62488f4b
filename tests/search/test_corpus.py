import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bushenv import excitation as ex
from bushenv.models.base import PAPER_DT as DT
from bushenv.search.corpus import (
    CorpusError,
    check,
    decode_profile,
    encode_profile,
    load_case,
    make_case,
    save_case,
)
from bushenv.search.families import get_family

from .conftest import UnstableHoldBushing


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-0.0125, 0.0125), min_size=1, max_size=300))
def test_profile_round_trip_is_within_float32_of_the_original(values):
    x = np.array(values)
    y = decode_profile(encode_profile(x))
    assert y.shape == x.shape
    assert np.max(np.abs(y - x)) < 1e-9 * max(1, x.size)


def test_holds_decode_exactly_constant():
    x = ex.step_hold(4e-3, 2.0, DT, rise_s=0.05)
    y = decode_profile(encode_profile(x))
    n = int(1.5 / DT)
    assert np.all(y[-n:] == y[-1])


def _resolver(models):
    return lambda name, axis, dt: models[name].copy()


def _case(reference, linear):
    models = {"bad": UnstableHoldBushing(), "linear": linear}
    x = get_family("step").profile(np.array([0.9, 0.2, 0.0, 0.5]))
    case = make_case(
        x,
        env="rig",
        axis="axial",
        family="step",
        params=[0.9, 0.2, 0.0, 0.5],
        found_by={"searcher": "cma", "seed": 0, "model": "bad", "model_sha256": "a" * 64},
        models=models,
        reference=reference,
        shas={"bad": "a" * 64, "linear": None},
    )
    return case, models


def test_case_records_each_models_verdict_and_replays_clean(
    tmp_path, reference_axial, linear_axial
):
    case, models = _case(reference_axial, linear_axial)
    assert case.expect["bad"]["diverged"] and not case.expect["linear"]["diverged"]
    assert case.name.startswith("bad-axial-rig-step-")
    path = save_case(case, tmp_path)
    loaded = load_case(path)
    assert np.array_equal(loaded.profile, case.profile)
    assert check(loaded, _resolver(models), sha_of=lambda n, a: "a" * 64) == []


def test_a_changed_verdict_names_the_case_and_a_changed_model_file(
    tmp_path, reference_axial, linear_axial
):
    case, models = _case(reference_axial, linear_axial)
    loaded = load_case(save_case(case, tmp_path))
    fixed = {"bad": linear_axial, "linear": linear_axial}  # the "bad" model got fixed
    problems = check(loaded, _resolver(fixed), sha_of=lambda n, a: "b" * 64)
    assert len(problems) == 1
    assert case.name in problems[0] and "bad was expected to diverge" in problems[0]
    assert "model file changed" in problems[0] and "aaaaaaaaaaaa -> bbbbbbbbbbbb" in problems[0]


def test_cases_are_never_overwritten_without_force(tmp_path, reference_axial, linear_axial):
    case, _ = _case(reference_axial, linear_axial)
    assert save_case(case, tmp_path) is not None
    case.notes = "changed"
    assert save_case(case, tmp_path) is None
    assert json.loads((tmp_path / f"{case.name}.json").read_text())["notes"] == ""
    assert save_case(case, tmp_path, force=True) is not None
    assert json.loads((tmp_path / f"{case.name}.json").read_text())["notes"] == "changed"


def test_corrupt_case_files_are_refused_by_name(tmp_path, reference_axial, linear_axial):
    case, _ = _case(reference_axial, linear_axial)
    path = save_case(case, tmp_path)
    d = json.loads(path.read_text())
    d["profile"]["n_samples"] += 1
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(d))
    with pytest.raises(CorpusError, match="bad.json.*samples"):
        load_case(bad)
    bad.write_text("{not json")
    with pytest.raises(CorpusError, match="bad.json: not a readable JSON"):
        load_case(bad)
    d = json.loads(path.read_text())
    d["expect"]["bad"]["diverged"] = "yes"
    bad.write_text(json.dumps(d))
    with pytest.raises(CorpusError, match="expect\\['bad'\\] needs a boolean"):
        load_case(bad)


def test_replay_command_says_which_cases_hold_and_fails_on_a_changed_verdict(tmp_path, capsys):
    import json

    from bushenv.cli import main
    from bushenv.models.linear import LinearBushing
    from bushenv.search.corpus import make_case, save_case

    model = LinearBushing(k_n_per_m=380e3, c_ns_per_m=-4e3)  # negative damping: generates energy
    path = model.save(tmp_path / "active.npz")
    x = np.concatenate([np.sin(np.linspace(0, 20 * np.pi, 2000)) * 1e-3, np.zeros(300)])
    case = make_case(
        x,
        env="rig",
        axis="axial",
        family="sine",
        params=None,
        found_by={"model": str(path)},
        models={str(path): model},
        reference=None,
        reference_spec=None,
    )
    saved = save_case(case, tmp_path / "corpus")
    assert main(["replay", str(tmp_path / "corpus"), "--quiet"]) == 0
    assert "1 of 1 cases hold" in capsys.readouterr().out
    data = json.loads(saved.read_text())
    data["expect"][str(path)]["diverged"] = not data["expect"][str(path)]["diverged"]
    saved.write_text(json.dumps(data))
    assert main(["replay", str(saved), "--quiet"]) == 1
    assert "was expected to" in capsys.readouterr().out
    assert main(["replay", str(tmp_path / "nothing")]) == 2
