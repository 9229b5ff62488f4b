"""The adversary's finds in the half car, kept as regression cases (``corpus/``, written by
``studies/2026-11-vehicle-adversary/run.py`` through ``bushenv vehicle --search --corpus``):
each replays with the verdicts it recorded, as every case of ``tests/regressions/`` does, and
the cases hold what the study reports (the hybrid's largest difference, the network ending)."""

from pathlib import Path

import pytest

from bushenv.cli import main
from bushenv.search.corpus import case_files, check, load_case

CORPUS = Path(__file__).parent / "corpus"
FILES = case_files(CORPUS)


def _verdicts(case) -> dict[str, str]:
    """Kind (the model file's stem) -> recorded criterion ("passes" when none fired)."""
    return {Path(s).stem: e["criterion"] or "passes" for s, e in case.expect.items()}


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_each_half_car_case_keeps_its_recorded_verdicts(path):
    case = load_case(path)
    assert case.env == "halfcar" and case.profile.shape[1] == 3
    problems = check(case)
    assert not problems, "\n".join(problems)


def test_the_cases_hold_the_largest_difference_and_the_network_ending_its_car():
    """Seed 0's largest difference for the linear car is also the hybrid's (one fishhook at 7
    m/s^2, found once and kept once): both differ there; the network ends its car."""
    cases = [load_case(p) for p in FILES]
    found = {c.found_by["model"]: c for c in cases if "largest" in c.notes}
    assert {"linear", "nn"} <= {c.found_by["model"] for c in cases}
    assert _verdicts(found["linear"])["linear"] == "differs"
    assert _verdicts(found["linear"])["hybrid"] == "differs"
    assert any(_verdicts(c)["nn"] == "terminated" for c in cases)


def test_bushenv_replay_runs_a_half_car_case_like_any_other(capsys):
    smallest = min(FILES, key=lambda p: p.stat().st_size)  # the other cases replay above
    assert main(["replay", "--quiet", str(smallest)]) == 0
    assert "1 of 1 cases hold" in capsys.readouterr().out
