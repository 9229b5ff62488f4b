import numpy as np

from bushenv.certify.certificate import non_passive_bands
from bushenv.certify.energy import energy_fires, firing_bands, sine_batch
from bushenv.models import get_model
from bushenv.models.linear import LinearBushing
from bushenv.reference.rubber import RubberBushing

from .conftest import old_nn

FREQ = np.arange(4.0, 81.0, 4.0)
AMPS = np.array([0.5e-3, 1e-3, 2e-3])


def test_the_linear_control_never_fires_the_energy_criterion_on_sines():
    fires = energy_fires(LinearBushing.preset("axial"), RubberBushing.preset("axial"), FREQ, AMPS)
    assert not any(f for row in fires for f in row if f is not None)


def test_an_nn_fires_only_inside_its_linearised_non_passive_band():
    model = get_model(old_nn("axial"), axis="axial")
    (band,) = non_passive_bands(model, 0.0)
    fires = energy_fires(model, RubberBushing.preset("axial"), FREQ, AMPS)
    fired = [f for row in fires for f, on in zip(FREQ, row, strict=True) if on]
    assert fired, "this NN is known to generate energy on fast sines"
    assert all(band[0] <= f <= band[1] for f in fired)


def test_sines_the_machine_cannot_drive_are_not_run():
    fires = energy_fires(
        LinearBushing.preset("axial"),
        RubberBushing.preset("axial"),
        np.array([10.0, 80.0]),
        np.array([4e-3]),
    )
    assert fires == [[False, None]]  # 2 pi 80 Hz 4 mm = 2.0 m/s > 1.257 m/s


def test_sine_batch_starts_at_rest_and_ends_in_a_hold():
    x = sine_batch(np.array([5.0, 20.0]), 1e-3, 1 / 204.8)
    assert np.all(x[0] == 0.0)
    assert np.all(x[-205:] == x[-1])


def test_firing_bands_groups_consecutive_grid_points():
    f = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    assert firing_bands(f, [False, True, True, None, True]) == [(2.0, 3.0), (5.0, 5.0)]
