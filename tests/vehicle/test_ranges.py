"""The car's bushings are identified where the car uses them: the torsion set's identification
records reach its calibrated rotation (and the translations the car's pivots reach), the
cardanic programme stays as ``bushenv reproduce --planar`` identifies on; and the count of
steps beyond a range (``bushenv.vehicle.ranges``)."""

import numpy as np
import pytest

from bushenv.models.base import PAPER_DT
from bushenv.reference.planar import TORSION_MAX_ROTATION_RAD
from bushenv.reproduce import WIDE_BAND_HZ, WIDE_PEAKS, identification_records
from bushenv.rigs.halfcar_params import PIVOT_ROTATION
from bushenv.vehicle.bushings import RECIPE_VERSION, Recipe
from bushenv.vehicle.ranges import steps_outside


@pytest.fixture(scope="module")
def torsion_records():
    return identification_records(PAPER_DT, 0, 8.0, rotation="torsion")


def test_the_torsion_records_reach_the_calibrated_rotation_and_the_translations(torsion_records):
    peak = np.max([np.abs(q).max(axis=0) for q, _ in torsion_records], axis=0)
    assert peak[2] == pytest.approx(TORSION_MAX_ROTATION_RAD, rel=1e-6)
    assert peak[0] == pytest.approx(12.5e-3) and peak[1] == pytest.approx(4e-3)
    np.testing.assert_array_equal(WIDE_PEAKS[PIVOT_ROTATION], peak)
    # the n = 1 records first, as the cardanic programme's; then random and coupled at the peaks
    cardanic = identification_records(PAPER_DT, 0, 8.0)
    assert len(cardanic) == 5 and len(torsion_records) == 10
    for (q, _), (q0, _) in zip(torsion_records[:5], cardanic, strict=True):
        np.testing.assert_array_equal(q, q0)
    assert np.max([np.abs(q).max(axis=0) for q, _ in cardanic], axis=0) == pytest.approx(
        [2e-3, 2e-3, 0.05]
    )
    wide = torsion_records[5:]
    assert [q.shape[0] for q, _ in wide] == [int(round(t / PAPER_DT)) for t in (4, 4, 4, 4, 4)]
    for q, _ in wide[:2]:  # random, every coordinate to its peak
        np.testing.assert_allclose(np.abs(q).max(axis=0), peak, rtol=1e-9)


def test_the_wide_random_records_move_in_the_body_modes_band(torsion_records):
    """The car's large deflections come with its body modes and steering (below 5 Hz): the wide
    random records hold at most a few % of their power above WIDE_BAND_HZ."""
    for q, _ in torsion_records[5:7]:
        spectrum = np.abs(np.fft.rfft(q, axis=0)) ** 2
        f = np.fft.rfftfreq(q.shape[0], PAPER_DT)
        above = spectrum[f > 1.2 * WIDE_BAND_HZ[1]].sum(axis=0) / spectrum.sum(axis=0)
        assert np.all(above < 0.03), above


def test_the_records_are_deterministic_and_the_recipe_names_the_new_version(torsion_records):
    again = identification_records(PAPER_DT, 0, 8.0, rotation="torsion")
    for (q, f), (q2, f2) in zip(torsion_records, again, strict=True):
        assert np.array_equal(q, q2) and np.array_equal(f, f2)
    assert RECIPE_VERSION == 3
    assert Recipe(PAPER_DT).key("linear")["recipe_version"] == 3


def test_steps_outside_counts_any_pivot_per_coordinate():
    q = np.zeros((4, 4, 3))
    q[1, 2, 2] = 0.06  # one pivot's rotation beyond
    q[2, 0, 0] = -3e-3  # another's axial beyond
    q[3, :, 1] = 1e-3  # within
    out = steps_outside(q, np.array([2e-3, 2e-3, 0.05]))
    assert out == {"axial": 1, "radial": 0, "rotation": 1, "any": 2}
