"""Motions of several coordinates: amplitude index per coordinate, correlation, preload sets,
machine limits; the machine's programmes over C."""

import numpy as np
import pytest

from bushenv.excitation import MAX_DISPLACEMENT_M, MAX_VELOCITY_M_PER_S
from bushenv.motions import (
    PEAK_AT_N1,
    preload_sweep,
    random_correlated,
    random_independent,
    verification_motions,
)
from bushenv.programmes import PROGRAMMES, ProgrammeError, programme_items
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
    for q in verification_motions(DT, seed=0).values():
        assert np.abs(q[:, :2]).max() <= MAX_DISPLACEMENT_M
        assert np.abs(np.diff(q[:, :2], axis=0)).max() / DT <= MAX_VELOCITY_M_PER_S
        assert np.abs(q[:, 2]).max() <= MAX_ROTATION_RAD


def test_benchmark_table_reports_ratio_and_axes_at_rest_in_newtons():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).parents[1] / "scripts" / "planar_benchmark.py"
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


def test_the_motions_take_their_number_of_coordinates_from_the_peaks():
    peaks = np.array([1e-3, 2e-3])
    for make in (random_independent, random_correlated):
        q = make(1.0, 4.0, DT, 0, peaks)
        assert q.shape == (int(round(4.0 / DT)), 2)
        np.testing.assert_allclose(np.abs(q).max(axis=0), peaks, rtol=1e-12)
    assert preload_sweep(0, 1e-3, 1e-3, 4.0, DT, n_coords=2).shape[1] == 2


@pytest.mark.parametrize("n_coords", [1, 3])
def test_every_programme_gives_items_of_the_bushings_coordinates_within_the_limits(n_coords):
    for kind, forms in PROGRAMMES.items():
        if n_coords not in forms:
            with pytest.raises(ProgrammeError, match=f"no form for {n_coords} coordinate"):
                programme_items(kind, n_coords, DT)
            continue
        items = programme_items(kind, n_coords, DT, duration_s=2.0 if kind != "papers" else None)
        assert items and len({i.name for i in items}) == len(items), kind
        for item in items:
            q = item.x.reshape(len(item.x), -1)
            assert q.shape[1] == n_coords, (kind, item.name)
            moved = q[:, : min(2, n_coords)]
            assert np.abs(moved).max() <= MAX_DISPLACEMENT_M + 1e-12, item.name


def test_the_three_axis_programmes_keep_their_names_and_order():
    names = [i.name for i in programme_items("papers", 3, DT, seed=4)]
    assert names[:4] == [
        "random_independent_n1_40s_seed4",
        "random_correlated_n1_40s_seed4",
        "random_independent_n1.5_20s_seed5",
        "random_correlated_n1.5_20s_seed5",
    ]
    assert names[-2:] == ["axial_preload_3mm_radial_sweep", "axial_preload_2mm_radial_sweep"]
    combined = programme_items("combined", 3, DT, duration_s=2.0)
    assert len(combined) == 12 and combined[0].name == "axial_held_+_radial_sweep"
