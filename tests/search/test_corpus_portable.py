"""A corpus replays from any working folder and after its folder moves (corpus_files.py)."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.models import default_model_path, file_hash, get_reference
from bushenv.models.linear import LinearBushing
from bushenv.search.corpus import CorpusError, check, load_case, make_case, save_case
from bushenv.search.families import get_family

OLD_MODELS = Path(__file__).resolve().parents[1] / "regressions" / "models"
QUICK = ["--budget", "16", "--searchers", "random", "--max-shrink", "1", "--shrink-budget", "20"]


def test_the_readme_commands_with_relative_paths_replay_here_elsewhere_and_after_a_move(
    tmp_path, monkeypatch, capsys
):
    work = tmp_path / "work"
    work.mkdir()
    shutil.copy(OLD_MODELS / "axial_nn-6f15bf3.npz", work / "my_nn.npz")
    shutil.copy(default_model_path("hybrid", "axial"), work / "my_hybrid.npz")
    monkeypatch.chdir(work)
    attack = ["attack", "--model", "my_nn.npz", "--reference", "my_hybrid.npz", "--save"]
    code = main(attack + ["--corpus", "my_corpus", "--out", "runs/a", *QUICK, "--no-plots"])
    assert code == 0
    cases = sorted(Path("my_corpus").glob("*.json"))
    assert cases, "the attack kept no case: nothing to replay"
    capsys.readouterr()
    assert main(["replay", "my_corpus", "--quiet"]) == 0  # was exit 2: corp/my_nn.npz missing
    assert "note:" not in capsys.readouterr().out  # the files are where they were

    other = tmp_path / "other"
    other.mkdir()
    monkeypatch.chdir(other)
    assert main(["replay", str(work / "my_corpus"), "--quiet"]) == 0

    moved = tmp_path / "machine2" / "corpus"
    moved.parent.mkdir()
    shutil.move(str(work / "my_corpus"), moved)
    shutil.rmtree(work)  # the models, the reference and the run are gone on the "other machine"
    capsys.readouterr()
    assert main(["replay", str(moved), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "my_nn.npz: not at" in out and "replayed the copy kept with the corpus" in out
    assert "my_hybrid.npz: not at" in out  # the reference came along too
    assert f"{len(cases)} of {len(cases)} cases hold" in out


def _models(folder: Path) -> dict:
    """Two linear model files and a card beside one of them, in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    soft = LinearBushing(k_n_per_m=370e3, c_ns_per_m=4.3e3)
    soft.save(folder / "soft.npz")
    (folder / "soft.card.json").write_text('{"format": "bushenv-model-card"}')
    LinearBushing(k_n_per_m=380e3, c_ns_per_m=4.4e3).save(folder / "ref.npz")
    return {"soft": soft}


def _case(models_dir: Path, reference: str | None = "ref.npz"):
    """A case made in memory, naming its files relative to the working folder (as attack does)."""
    models = _models(models_dir)
    spec = str(Path(models_dir.name) / "soft.npz")
    ref = None if reference is None else get_reference(str(models_dir / reference))
    x = get_family("step").profile(np.array([0.7, 0.2, 0.0, 0.5]))
    return make_case(
        x,
        env="rig",
        axis="axial",
        family="step",
        params=None,
        found_by={"searcher": "test", "seed": 0, "model": spec},
        models={spec: models["soft"]},
        reference=ref,
        reference_spec=None if reference is None else str(Path(models_dir.name) / reference),
        shas={spec: file_hash(models_dir / "soft.npz")},
    )


def test_model_files_are_kept_by_content_hash_with_their_cards(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    case = _case(tmp_path / "mine")
    path = save_case(case, tmp_path / "corp")
    d = json.loads(path.read_text())
    entry = d["expect"]["mine/soft.npz"]
    sha = file_hash(tmp_path / "mine" / "soft.npz")
    assert entry["file"] == {"source": "../mine/soft.npz", "kept": f"models/{sha[:16]}/soft.npz"}
    kept = tmp_path / "corp" / entry["file"]["kept"]
    assert file_hash(kept) == sha == entry["sha256"]
    assert kept.with_name("soft.card.json").is_file()
    ref = d["reference"]
    assert ref["file"]["source"] == "../mine/ref.npz"
    assert file_hash(tmp_path / "corp" / ref["file"]["kept"]) == ref["file_sha256"]


def test_a_file_recorded_without_its_hash_gets_it_when_kept(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    case = _case(tmp_path / "mine")
    case.expect["mine/soft.npz"]["sha256"] = None  # as a caller passing no shas leaves it
    path = save_case(case, tmp_path / "corp")
    entry = json.loads(path.read_text())["expect"]["mine/soft.npz"]
    assert entry["sha256"] == file_hash(tmp_path / "mine" / "soft.npz")


def test_a_moved_corpus_replays_its_kept_copies_and_says_so(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = save_case(_case(tmp_path / "mine"), tmp_path / "corp")
    shutil.move(str(tmp_path / "corp"), tmp_path / "away")
    shutil.rmtree(tmp_path / "mine")
    notes: list[str] = []
    case = load_case(tmp_path / "away" / path.name)
    assert check(case, notes=notes) == []
    assert any("mine/soft.npz: not at" in n and "kept with the corpus" in n for n in notes)
    assert any("mine/ref.npz: not at" in n for n in notes)


def test_an_altered_kept_copy_is_refused_and_a_lost_one_is_named(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = save_case(_case(tmp_path / "mine"), tmp_path / "corp")
    (tmp_path / "mine" / "soft.npz").unlink()
    case = load_case(path)
    kept = tmp_path / "corp" / case.expect["mine/soft.npz"]["file"]["kept"]
    LinearBushing(k_n_per_m=1e3, c_ns_per_m=1.0).save(kept)  # another model under the old name
    with pytest.raises(CorpusError, match="kept with the case has sha256 .* it was altered"):
        check(case)
    kept.unlink()
    with pytest.raises(CorpusError, match=f"case {case.name}: .*soft.npz: neither at .*mine"):
        check(case)


def test_a_model_refitted_in_place_is_replayed_as_it_is_now_and_named(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    case = _case(tmp_path / "mine")
    assert case.expect["mine/soft.npz"]["diverged"] is False  # close to the reference: bounded
    path = save_case(case, tmp_path / "corp")
    # "refitted": the file at its source now holds a model that fails the deviation criterion
    LinearBushing(k_n_per_m=5e6, c_ns_per_m=1.0).save(tmp_path / "mine" / "soft.npz")
    problems = check(load_case(path))
    assert len(problems) == 1
    assert "mine/soft.npz was expected to stay bounded but diverged" in problems[0]
    assert "model file changed since the case was recorded" in problems[0]


def test_a_case_written_before_models_were_kept_replays_from_the_working_folder(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    case = _case(tmp_path / "mine")
    path = save_case(case, tmp_path / "corp")
    d = json.loads(path.read_text())  # as the old writer left it: paths relative to the cwd
    for entry in d["expect"].values():
        entry.pop("file")
    d["reference"].pop("file")
    path.write_text(json.dumps(d))
    shutil.rmtree(tmp_path / "corp" / "models")
    notes: list[str] = []
    assert check(load_case(path), notes=notes) == []
    assert any("found relative to the working folder" in n for n in notes)


def test_a_case_saved_without_a_reference_replays_with_the_reference_free_criteria(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)
    path = save_case(_case(tmp_path / "mine", reference=None), tmp_path / "corp")
    assert json.loads(path.read_text())["reference"]["spec"] is None
    assert load_case(path).reference["spec"] is None
    assert main(["replay", "corp", "--quiet"]) == 0
    assert "1 of 1 cases hold" in capsys.readouterr().out


def test_the_papers_step_without_a_reference_is_kept_and_replays(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    shutil.copy(OLD_MODELS / "axial_nn-6f15bf3.npz", "my_nn.npz")
    args = ["attack", "--model", "my_nn.npz", "--paper-step", "--save", "--corpus", "corp"]
    assert main(args + ["--out", "runs/a", *QUICK, "--no-plots", "--quiet"]) == 0
    step = [p for p in Path("corp").glob("*.json") if "-step-" in p.name]
    assert step and json.loads(step[0].read_text())["reference"]["spec"] is None
    assert main(["replay", "corp", "--quiet"]) == 0
