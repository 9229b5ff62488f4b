import numpy as np
import pytest

from bushenv.identify import IdentificationError, fit_model

DT = 1 / 204.8


def test_least_squares_recovers_k_and_c_exactly_on_linear_data():
    rng = np.random.default_rng(0)
    x = np.cumsum(rng.normal(size=2000)) * 1e-5
    v = np.gradient(x, DT)
    f = 3.7e5 * x + 2.1e3 * v
    m = fit_model("linear", x, f, DT, progress=False)
    assert m.k_n_per_m == pytest.approx(3.7e5, rel=1e-10)
    assert m.c_ns_per_m == pytest.approx(2.1e3, rel=1e-10)
    np.testing.assert_allclose(m.simulate(x), f, rtol=1e-9, atol=1e-9)


def test_fit_model_dispatches_linear_and_uses_given_velocity():
    x = np.sin(np.arange(500) * 0.05) * 1e-3
    v = np.cos(np.arange(500) * 0.05) * 1e-3 * 0.05 / DT
    m = fit_model("linear", x, 1e5 * x + 500.0 * v, DT, v=v, progress=False)
    assert (m.name, round(m.k_n_per_m), round(m.c_ns_per_m)) == ("linear", 100000, 500)


def test_bad_records_are_refused_naming_the_problem():
    x = np.zeros(100)
    with pytest.raises(IdentificationError, match="x is constant"):
        fit_model("linear", x, x, DT)
    y = np.linspace(0, 1, 100)
    f = y.copy()
    f[17] = np.nan
    with pytest.raises(IdentificationError, match=r"f\[17\] is nan"):
        fit_model("linear", y, f, DT)
    with pytest.raises(IdentificationError, match="equal length"):
        fit_model("linear", y, f[:50], DT)
    with pytest.raises(IdentificationError, match="no identification for model 'rubber'"):
        fit_model("rubber", y, y, DT)


@pytest.mark.parametrize("coords", [1, 3])
def test_one_least_squares_recovers_the_stiffness_and_damping_of_any_number_of_coordinates(coords):
    # the same function for every C: k, c for one coordinate, the C x C matrices for several
    rng = np.random.default_rng(1)
    q = np.cumsum(rng.normal(size=(2000, coords)), axis=0) * 1e-5
    q = q[:, 0] if coords == 1 else q
    v = np.gradient(q, DT, axis=0)
    k = 3.7e5 * np.eye(coords) + 2e4 * np.triu(np.ones((coords, coords)), 1)
    c = 2.1e3 * np.eye(coords)
    f = (q.reshape(-1, coords) @ k.T + v.reshape(-1, coords) @ c.T).reshape(q.shape)
    m = fit_model("linear", q, f, DT, progress=False)
    assert m.n_coords == coords
    np.testing.assert_allclose(m.simulate(q), f, rtol=1e-8, atol=1e-6)


@pytest.mark.parametrize("coords", [1, 3])
def test_a_record_constant_in_every_coordinate_or_with_a_nan_is_refused_whatever_c(coords):
    shape = (100,) if coords == 1 else (100, coords)
    with pytest.raises(IdentificationError, match="x is constant"):
        fit_model("linear", np.full(shape, 1e-3), np.ones(shape), DT)
    y = np.linspace(0, 1e-3, 100 * coords).reshape(shape)
    f = y.copy()
    f[17] = np.nan
    with pytest.raises(IdentificationError, match=r"f\[17.*\] is nan"):
        fit_model("linear", y, f, DT)
