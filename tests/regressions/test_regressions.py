"""Replay the divergence corpus: every kept case must keep its recorded verdicts.

Each file in ``corpus/`` (written by ``bushenv attack --save``, format in
``bushenv/search/corpus.py`` and docs/search.md) is one test: the profile is run on every model
the case names -- the shipped default files -- on the prescribed-motion batched path, or for
QuarterCar roads through the batched quarter car, and judged by ``bushenv.divergence``.
A changed verdict fails with the case's name; if the model file changed since the case was
recorded, the message says so (then either the new model fixed or broke something, or the
case needs re-recording with ``bushenv attack --save --force``).
"""

from pathlib import Path

import pytest

from bushenv.search.corpus import case_files, check, load_case

CORPUS = Path(__file__).parent / "corpus"
FILES = case_files(CORPUS)


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_recorded_verdicts_still_hold(path):
    case = load_case(path)
    problems = check(case)
    assert not problems, "\n".join(problems)


def test_corpus_covers_steps_out_of_distribution_random_and_a_quarter_car_road():
    cases = [load_case(p) for p in FILES]
    rig_families = {c.family for c in cases if c.env == "rig"}
    assert "step" in rig_families
    assert "random_ood" in rig_families
    assert any(c.env == "quartercar" for c in cases)


def test_every_case_records_the_hybrid_and_the_model_file_hashes():
    for path in FILES:
        case = load_case(path)
        assert "hybrid" in case.expect, path.name
        for name in ("nn", "hybrid"):
            if name in case.expect:
                assert case.expect[name].get("sha256"), (path.name, name)
