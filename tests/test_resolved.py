"""A model or reference is resolved once, where it enters: one immutable value, and an attack
reads each model card exactly once."""

import dataclasses
import json
from collections import Counter
from pathlib import Path

import pytest

from bushenv.cli import main
from bushenv.models import file_hash
from bushenv.resolved import ResolvedModel, resolve_model


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """A reference and a model under attack, each a linear fit with its card and record."""
    from bushenv.machine import random_test
    from bushenv.records import save_csv
    from bushenv.reference.rubber import RubberBushing

    folder = tmp_path_factory.mktemp("fitted")
    out = {}
    for name, seed in (("ref", 3), ("mine", 4)):
        rec = random_test(RubberBushing.preset("axial", seed=seed), 1.0, 8.0, seed=seed)
        train = save_csv(rec, folder / f"{name}-train.csv")
        path = folder / f"{name}.npz"
        argv = ["fit", str(train), "--model", "linear", "--out", str(path), "--quiet"]
        assert main(argv) == 0
        out[name] = path
    return out


def test_a_resolved_model_is_immutable_and_names_its_file_hash_and_card(fitted):
    r = resolve_model(str(fitted["ref"]), "axial", card=True)
    assert isinstance(r, ResolvedModel)
    assert r.key == "ref" and r.spec == str(fitted["ref"]) and r.file == Path(fitted["ref"])
    assert r.sha256 == file_hash(fitted["ref"]) and r.card["model"] == "linear"
    assert r.card_file.name == "ref.card.json"
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.key = "other"
    shipped = resolve_model("nn", "axial")
    assert shipped.registered and shipped.key == "nn" and shipped.card is None
    assert shipped.sha256 == file_hash(shipped.file)


def test_an_attack_reads_each_model_card_exactly_once(fitted, tmp_path, monkeypatch):
    import bushenv.identify.card as card_module

    reads: Counter = Counter()
    load = card_module.load_card

    def counted(path, *args, **kwargs):
        card = load(path, *args, **kwargs)
        reads[card.path.name] += 1
        return card

    monkeypatch.setattr(card_module, "load_card", counted)
    out = tmp_path / "a"
    argv = ["attack", "--model", str(fitted["mine"]), "--reference", str(fitted["ref"])]
    argv += ["--searchers", "random", "--budget", "8", "--max-shrink", "0", "--no-plots"]
    assert main([*argv, "--quiet", "--out", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    # the control was fitted to the reference's card's records: the card was used there too
    assert report["models"]["linear-fit"]["role"] == "control"
    assert any("model card" in n for n in report["notes"])
    assert reads == {"ref.card.json": 1, "mine.card.json": 1}
