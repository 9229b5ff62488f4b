"""The 3-axis programme: amplitude index per axis, correlation, preload sets, machine limits."""

import numpy as np
import pytest

from bushenv.excitation import MAX_DISPLACEMENT_M, MAX_VELOCITY_M_PER_S
from bushenv.planar.programme import (
    PEAK_AT_N1,
    preload_sweep,
    programme,
    random_correlated,
    random_independent,
)
from bushenv.reference.planar import MAX_ROTATION_RAD

DT = 1 / 204.8


def _corr(q):
    return np.corrcoef(q.T)


def test_random_sets_peak_at_n_times_the_n1_peak_per_axis():
    for make in (random_independent, random_correlated):
        q = make(1.5, 10.0, DT, 3)
        np.testing.assert_allclose(np.abs(q).max(axis=0), 1.5 * PEAK_AT_N1, rtol=1e-12)


def test_correlated_set_moves_the_axes_together_and_independent_does_not():
    ci = _corr(random_independent(1.0, 20.0, DT, 1))
    cc = _corr(random_correlated(1.0, 20.0, DT, 1))
    assert np.abs(ci[np.triu_indices(3, 1)]).max() < 0.2
    assert cc[0, 1] > 0.5 and cc[1, 2] < -0.5


def test_preload_sweep_holds_one_coordinate_and_sweeps_the_other():
    q = preload_sweep(1, 3e-3, 0.075, 10.0, DT)
    assert np.all(q[205:, 1] == 3e-3)
    assert np.abs(q[:, 2]).max() > 0.07 and np.all(q[:, 0] == 0)
    r = preload_sweep(2, 0.075, 3e-3, 10.0, DT)
    assert np.all(r[205:, 2] == 0.075) and np.abs(r[:, 1]).max() > 2.9e-3
    a = preload_sweep(0, 3e-3, 3e-3, 10.0, DT)  # axial hold under a radial sweep
    assert np.all(a[205:, 0] == 3e-3) and np.abs(a[:, 1]).max() > 2.9e-3 and np.all(a[:, 2] == 0)
    for held, swept in ((1, 1), (0, 3)):
        with pytest.raises(ValueError, match="must be two of 0, 1, 2"):
            preload_sweep(held, 1e-3, 1e-3, 10.0, DT, swept=swept)


def test_every_record_is_within_the_machine_limits():
    for q in programme(DT, seed=0).values():
        assert np.abs(q[:, :2]).max() <= MAX_DISPLACEMENT_M
        assert np.abs(np.diff(q[:, :2], axis=0)).max() / DT <= MAX_VELOCITY_M_PER_S
        assert np.abs(q[:, 2]).max() <= MAX_ROTATION_RAD


def test_benchmark_table_reports_ratio_and_axes_at_rest_in_newtons():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).parents[2] / "scripts" / "planar_benchmark.py"
    spec = importlib.util.spec_from_file_location("planar_benchmark", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)

    def cell(rms, rest=False):
        return {"rms": rms, "max": 2 * rms, "max_abs": 7.0, "at_rest": rest}

    row = {
        k: {"axial": cell(1.0, rest=True), "radial": cell(r), "rotation": cell(r)}
        for k, r in zip(mod.MODELS, (10.0, 8.0, 4.0, 3.0, 3.0, 2.0), strict=True)
    }
    lines = mod.table({0: {"set": row}}).splitlines()
    assert "axial at rest: max error | 7 N" in lines[2]
    for k in mod.MODELS:  # the axial set: the moment at rest, in N m
        row[k]["rotation"] = cell(1.0, rest=True)
    assert "rotation at rest: max error | 7 N m" in mod.table({0: {"set": row}})
    assert lines[3].endswith("| 2.00 |")  # nn-axis 8 % over nn 4 %
