"""Bouc-Wen global search: batched population = single runs, constraints, reproducibility."""

import numpy as np
import pytest
from standin import DT, standin_drive

from bushenv.identify import fit_model
from bushenv.identify.global_search import (
    SEARCH_BOUNDS,
    satisfies_constraints,
    search_to_parameters,
)
from bushenv.models.boucwen import BoucWenBushing, simulate_population

K_REF, C_REF = 3.0e5, 2.0e3


def random_search_vectors(n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = np.array(SEARCH_BOUNDS).T
    return lo + (hi - lo) * rng.random((n, len(lo)))


def test_every_search_vector_maps_to_parameters_meeting_eq6_constraints():
    vectors = search_to_parameters(random_search_vectors(500, 0), K_REF, C_REF)
    assert all(satisfies_constraints(p) for p in vectors)
    assert not satisfies_constraints(BoucWenBushing.preset().vector())  # Table 3 breaks one


def test_population_simulation_equals_each_model_alone_bit_for_bit():
    vectors = search_to_parameters(random_search_vectors(6, 1), K_REF, C_REF)
    x = standin_drive(2.0, seed=3)
    v = np.gradient(x, DT)
    out, bad = simulate_population(vectors, x, v, DT)
    for i, p in enumerate(vectors):
        if bad[i]:
            continue
        assert np.array_equal(out[:, i], BoucWenBushing.from_vector(p).simulate(x, v))
    assert not bad.all()


@pytest.fixture(scope="module")
def bw_record():
    truth = search_to_parameters(
        np.array([0.0, -0.3, -2.5, 0.0, -0.5, -2.0, -3.5, -3.0, 0.5, 1.0, 1.0, 1.5, -1.0, -1.5]),
        K_REF,
        C_REF,
    )
    x = standin_drive(3.0, seed=4)
    return x, BoucWenBushing.from_vector(truth).simulate(x)


def test_quick_search_improves_and_is_reproducible(bw_record):
    x, f = bw_record
    opts = dict(generations=4, population=4, fit_seconds=1.5, polish_evaluations=30, progress=False)
    a = fit_model("boucwen", x, f, DT, seed=5, **opts)
    b = fit_model("boucwen", x, f, DT, seed=5, **opts)
    assert np.array_equal(a.vector(), b.vector())
    assert satisfies_constraints(a.vector())
    tr = a.training
    assert tr["cost_n"] <= tr["cost_before_polish_n"]
    assert tr["rms_ratio"] < 1.0  # better than predicting zero force
    assert np.all(np.isfinite(a.simulate(x)))
