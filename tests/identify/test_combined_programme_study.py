"""studies/2026-11-combined-programme/combined_programme.py: its outside bushing is passive,
stable and of car-bushing size, and its training sets differ in the held combinations the card
reports (A shows 3 of the 12, B all)."""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from bushenv.motions import random_independent


@pytest.fixture(scope="module")
def mod():
    path = Path(__file__).parents[2] / "studies" / "2026-11-combined-programme"
    spec = importlib.util.spec_from_file_location(
        "combined_programme", path / "combined_programme.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclass looks its module up
    spec.loader.exec_module(module)
    return module


def test_outside_bushing_is_passive_stable_and_convex(mod):
    bushing = mod.OutsideBushing()
    checks = mod.check_outside(bushing, mod.DT_S)  # raises on a failed check
    assert checks["tangent_min_eig_J"] > 0
    assert all(w > 0 for cycles in checks["cycle_work_J"].values() for w in cycles)
    assert checks["worst_slack_share"] >= -1e-3
    # relaxed to rest after the hold: force rates far below a newton per second
    assert max(checks["random_independent_force_rate_after_hold"]) < 1e-2


def test_outside_bushing_has_table_1_stiffness(mod):
    q = random_independent(1.0, 40.0, mod.DT_S, 0)
    f, _ = mod.OutsideBushing().simulate(q, noise_seed=1)
    k_a, k_r, _ = mod.dynamic_stiffness(q, f, mod.DT_S)
    assert k_a == pytest.approx(379.68e3, rel=0.05)  # seed 000 Table 1, N/m
    assert k_r == pytest.approx(1518.73e3, rel=0.05)


def test_outside_bushing_is_causal_and_deterministic(mod):
    q = random_independent(1.0, 4.0, mod.DT_S, 3)
    b = mod.OutsideBushing()
    f1, _ = b.simulate(q, noise_seed=2)
    f2, _ = b.simulate(q, noise_seed=2)
    np.testing.assert_array_equal(f1, f2)
    q2 = q.copy()
    q2[500:] *= 1.3  # a change later leaves earlier forces alone
    v = np.gradient(q, mod.DT_S, axis=0)
    g1, _ = b.simulate(q, v=v)
    g2, _ = b.simulate(q2, v=np.where(np.arange(len(q))[:, None] < 499, v, 0.0))
    np.testing.assert_array_equal(g1[:499], g2[:499])


def test_set_a_leaves_nine_held_combinations_unshown_and_b_none(mod):
    from bushenv.identify.coverage import coverage

    sets, names = mod.training_sets(mod.DT_S, 0, 4.0, 3.0)
    assert len(names) == 12
    a = coverage([q for q, _ in sets["reference"]["A"]], mod.DT_S, mod.COORDS)
    b = coverage([q for q, _ in sets["outside"]["B"]], mod.DT_S, mod.COORDS)
    assert len(a["held_shown"]) == 3 and len(a["held_not_shown"]) == 9
    assert b["held_not_shown"] == []
