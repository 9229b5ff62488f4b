import numpy as np
import pytest

from bushenv import metrics


def test_rms_ratio_matches_hand_computation():
    f_exp = np.array([1.0, -2.0, 3.0, -4.0])
    f_pre = np.array([1.5, -2.0, 2.0, -4.0])
    # errors: -0.5, 0, 1, 0 -> mean sq 1.25/4 ; signal mean sq 30/4
    assert metrics.rms_ratio(f_exp, f_pre) == pytest.approx(np.sqrt(1.25 / 30.0))


def test_esr_matches_hand_computation_and_is_one_for_the_mean():
    f_exp = np.array([1.0, 2.0, 3.0, 6.0])
    f_pre = np.array([1.0, 2.0, 4.0, 6.0])
    # error var 1/4 ; output variance: mean 3 -> (4+1+0+9)/4 = 3.5
    assert metrics.esr(f_exp, f_pre) == pytest.approx(0.25 / 3.5)
    assert metrics.esr(f_exp, np.full(4, 3.0)) == pytest.approx(1.0)


def test_max_peak_and_benchmark_metrics():
    f_exp = np.array([0.0, 10.0, -20.0, 5.0])
    f_pre = np.array([1.0, 7.0, -18.0, 5.0])
    assert metrics.max_error(f_exp, f_pre) == 3.0
    assert metrics.max_error_ratio(f_exp, f_pre) == pytest.approx(3.0 / 20.0)
    assert metrics.peak_error(f_exp, f_pre) == pytest.approx(2.0)
    rmse = np.sqrt((1 + 9 + 4 + 0) / 4)
    assert metrics.nrmse(f_exp, f_pre) == pytest.approx(rmse / np.std(f_exp))
    assert metrics.fit_index(f_exp, f_pre) == pytest.approx(100 * (1 - rmse / np.std(f_exp)))


def test_metrics_refuse_mismatched_shapes():
    with pytest.raises(ValueError, match="shape"):
        metrics.rms_ratio(np.zeros(3), np.zeros(4))
