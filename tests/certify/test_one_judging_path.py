"""``bushenv certify`` judges a model of any number of coordinates by one path, the attack's
resolve stage (``campaign_resolve.resolve_target`` at ``judge.RIG``), and its span is the
judge's range by one rule (``judge.range_sources``, ``scales.record_range``): the reference's
card, else -- a user's reference without one, or none -- the model's, 1.5 x its training
records' peak per coordinate."""

import json
import shutil

import numpy as np
import pytest

import bushenv.commands.certify_setup as certify_setup
from bushenv.cli import main
from bushenv.identify.card import load_card
from bushenv.judge import RIG
from bushenv.search.campaign_resolve import resolve_target

from .conftest import fold_hybrid
from .test_vector_certificate import network

FAST1 = ["--holds", "9", "--passivity-mm", "0", "--energy-mm", "1", "--quiet"]
FAST3 = ["--holds", "27", "--hold-s", "4", "--quiet"]


@pytest.fixture(scope="module")
def cards(tmp_path_factory):
    """Linear fits with their cards over one and three coordinates (records of the built-in
    references), and a copy of each without its card."""
    d = tmp_path_factory.mktemp("cards")
    for axes, name in (("1", "lin1"), ("3", "lin3")):
        rec = d / f"rec{axes}"
        assert main(["measure", "--axes", axes, "--programme", "random", "--duration", "8",
                     "--out", str(rec), "--quiet"]) == 0  # fmt: skip
        train = sorted(rec.glob("*.csv"))[0]
        assert main(["fit", str(train), "--model", "linear", "--out", str(d / f"{name}.npz"),
                     "--no-plots", "--quiet"]) == 0  # fmt: skip
        shutil.copy(d / f"{name}.npz", d / f"{name}_nocard.npz")
    return d


def _peak(card_path) -> np.ndarray:
    train = [r for r in load_card(card_path).data["records"] if r["role"] == "train"]
    if "peak_deflection" in train[0]:
        return np.max([list(r["peak_deflection"].values()) for r in train], axis=0)
    return np.array([max(r["max_abs_displacement_m"] for r in train)])


def test_one_and_three_coordinates_take_the_same_judging_function(tmp_path, monkeypatch):
    calls = []

    def spy(*args, **kwargs):
        one = resolve_target(*args, **kwargs)
        calls.append((kwargs["target"], one.n_coords))
        return one

    monkeypatch.setattr(certify_setup, "resolve_target", spy)
    one = str(fold_hybrid().save(tmp_path / "fold.npz"))
    three = str(network().save(tmp_path / "nn3.npz"))
    assert main(["certify", one, "--stroke-mm", "12.5", "--out", str(tmp_path / "a"),
                 *FAST1]) in (0, 1)  # fmt: skip
    assert main(["certify", three, "--stroke-mm", "3", "--rotation-mrad", "75",
                 "--out", str(tmp_path / "b"), *FAST3]) in (0, 1)  # fmt: skip
    assert calls == [(RIG, 1), (RIG, 3)]
    docs = [json.loads((tmp_path / d / "certificate.json").read_text()) for d in "ab"]
    keys = [set(doc["judge"]) for doc in docs]
    assert keys[0] <= keys[1]  # the judge's record over one coordinate, and what judged over C
    assert docs[0]["judge"]["scales"]["stroke_m"] == pytest.approx(12.5e-3)
    assert docs[1]["judge"]["scales"]["rotation"]["stroke_mrad"] == pytest.approx(75.0)


@pytest.mark.parametrize("name,coords", [("lin1", 1), ("lin3", 3)])
def test_the_range_is_the_references_card_else_the_models_for_any_c(cards, name, coords):
    with_card, without = str(cards / f"{name}.npz"), str(cards / f"{name}_nocard.npz")
    want = tuple(1.5 * _peak(cards / f"{name}.npz"))
    axis = "axial"
    # a reference with a card: its range (the model has none)
    judged = resolve_target(without, with_card, axis=axis, target=RIG, trust_reference=True)
    assert judged.n_coords == coords and judged.judge.span == pytest.approx(want)
    assert "card" in judged.judge.scales.source
    # a user's reference without a card: the model's card, the same rule
    judged = resolve_target(with_card, without, axis=axis, target=RIG, trust_reference=True)
    assert judged.judge.span == pytest.approx(want)
    # no reference: the model's card
    judged = resolve_target(with_card, "none", axis=axis, target=RIG)
    assert judged.judge.span == pytest.approx(want) and judged.judge.reference is None


def test_a_three_axis_certificate_spans_its_references_card_as_the_attack_searches(cards, tmp_path):
    model = str(network().save(tmp_path / "nn3.npz"))
    ref = str(cards / "lin3.npz")
    out = tmp_path / "c"
    argv = ["certify", model, "--reference", ref, "--trust-reference", "--out", str(out)]
    assert main([*argv, *FAST3]) in (0, 1)
    doc = json.loads((out / "certificate.json").read_text())
    attack = resolve_target(model, ref, axis="axial", target="rig3", trust_reference=True)
    assert doc["settings"]["span"] == pytest.approx(list(attack.judge.span))
    assert doc["settings"]["span"] == pytest.approx(list(1.5 * _peak(ref)))
    assert "lin3.card.json" in doc["settings"]["span_source"]
    assert doc["judge"]["stroke"] == pytest.approx(
        dict(zip(doc["coords"], attack.judge.span, strict=True))
    )
    # judged by a registered reference, a file's span would be the machine's: refused, saying why
    code = main(["certify", model, "--reference", "rubber", "--out", str(tmp_path / "d"), *FAST3])
    assert code == 2 and not (tmp_path / "d").exists()


def test_a_model_file_without_any_card_is_refused_naming_the_flags_its_units_need(tmp_path, capsys):
    one = str(fold_hybrid().save(tmp_path / "fold.npz"))
    assert main(["certify", one, "--out", str(tmp_path / "a"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "give --stroke-mm (" in err and "--rotation-mrad" not in err
    three = str(network().save(tmp_path / "nn3.npz"))
    assert main(["certify", three, "--stroke-mm", "3", "--out", str(tmp_path / "b")]) == 2
    assert "give --rotation-mrad (" in capsys.readouterr().err


def test_the_command_builds_no_judge_of_its_own():
    import ast
    from pathlib import Path

    tree = ast.parse(Path(certify_setup.__file__).read_text())
    names = {a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names}
    assert "resolve_target" in names
    assert not names & {"build_judge", "judge_of", "vetted_within", "get_model", "search_limits"}


def test_an_fmus_certificate_is_run_over_the_span_certify_takes(tmp_path):
    """``bushenv export`` certifies as ``bushenv certify`` does: over several coordinates the
    same judge's span, not the test machine's."""
    from bushenv.export.certificate import carried_certificate

    path = network().save(tmp_path / "nn3.npz")
    model = network()
    judged = resolve_target(str(path), "none", axis="axial", target=RIG)
    carried = carried_certificate(model, str(path), "axial")
    assert carried.document["settings"]["span"] == pytest.approx(list(judged.judge.span))
    assert judged.judge.scales.source in carried.source
