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
