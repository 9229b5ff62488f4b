"""A reference of any number of coordinates is checked before it judges (``bushenv.vetting``)."""

import json

import numpy as np
import pytest

from bushenv.cli import main
from bushenv.models import MODELS
from bushenv.models.linear import LinearBushing
from bushenv.models.planar_linear import PlanarLinear
from bushenv.vetting import HOLDS, vet_reference
from bushenv.vetting_holds import held_vectors, hold_check

STROKES = {1: 0.0125, 3: np.array([0.0125, 0.0125, 0.15])}
FLOORS = {1: 200.0, 3: np.array([200.0, 200.0, 20.0])}


def _linear(n_coords=3, k_scale=1.0, c_scale=1.0, radial_into_axial=0.0):
    """The preset linear bushing of ``n_coords`` coordinates, its stiffness and damping
    diagonals scaled (a number, or one per coordinate)."""
    if n_coords == 1:
        ref = LinearBushing.preset()
        k, c = ref.k_n_per_m * np.ravel(k_scale)[0], ref.c_ns_per_m * np.ravel(c_scale)[0]
        return LinearBushing(k_n_per_m=k, c_ns_per_m=c, dt=ref.dt)
    ref = PlanarLinear.preset()
    k, c = ref.k_matrix.copy(), ref.c_matrix.copy()
    k[np.diag_indices(3)] *= k_scale
    c[np.diag_indices(3)] *= c_scale
    k[0, 1] += radial_into_axial * k[0, 0]
    return PlanarLinear(k, c, ref.dt)


def _vet(reference, n_coords, **kw):
    return vet_reference(reference, "m", STROKES[n_coords], FLOORS[n_coords], **kw)


def _checks(vetting):
    return {c.name: c for c in vetting.checks}


@pytest.mark.parametrize("n_coords", [1, 3])
def test_the_reference_rubber_and_a_linear_bushing_pass_their_holds_and_passivity(n_coords):
    dt = _linear(n_coords).dt
    rubber = MODELS["reference"].model_class(n_coords).preset(dt=dt, measurement=False)
    for model in (rubber, _linear(n_coords)):
        v = _vet(model, n_coords)
        checks = _checks(v)
        assert v.passed and checks["holds"].passed is True, v.lines()
        assert checks["passivity"].passed is True, v.lines()
        assert [c.name for c in v.checks] == ["holds", "records", "passivity", "compatibility"]


def test_holds_cover_every_coordinate_alone_and_the_corners_of_the_stroke_box():
    qs = held_vectors(STROKES[3])
    assert qs.shape == (3 * (HOLDS - 1) + 1 + 8, 3)
    assert np.all(np.abs(qs) <= STROKES[3] + 1e-12)
    alone = np.count_nonzero(qs, axis=1) <= 1
    assert alone.sum() == 3 * (HOLDS - 1) + 1 and np.all(np.abs(qs[~alone]) > 0)
    assert len({tuple(q) for q in qs}) == len(qs)  # the rest held once
    # one coordinate: the one-axis holds exactly
    np.testing.assert_array_equal(held_vectors(0.0125)[:, 0], np.linspace(-0.0125, 0.0125, HOLDS))


@pytest.mark.parametrize("n_coords", [1, 3])
def test_a_reference_with_a_negative_stiffness_axis_is_refused_naming_the_hold(n_coords):
    scale = -0.5 if n_coords == 1 else (1.0, -0.5, 1.0)
    v = _vet(_linear(n_coords, k_scale=scale), n_coords)
    holds = _checks(v)["holds"]
    assert not v.passed and holds.passed is False
    assert "wrong sign" in holds.detail and "mm" in holds.detail
    assert bool(holds.ranges_m) is (n_coords == 1)  # a range of x only on one axis


@pytest.mark.parametrize("n_coords", [1, 3])
def test_a_reference_with_negative_damping_holds_still_but_is_refused_as_active(n_coords):
    scale = -0.5 if n_coords == 1 else (1.0, 1.0, -0.5)
    v = _vet(_linear(n_coords, c_scale=scale), n_coords)
    checks = _checks(v)
    assert checks["holds"].passed is True  # a hold cannot show a negative damper
    assert checks["passivity"].passed is False
    assert "gives energy back" in checks["passivity"].detail
    assert not v.passed


@pytest.mark.parametrize("n_coords", [1, 3])
def test_a_reference_three_times_as_stiff_as_the_model_is_undecided_not_a_refusal(n_coords):
    v = _vet(_linear(n_coords, k_scale=3.0), n_coords, model=_linear(n_coords))
    comp = _checks(v)["compatibility"]
    assert comp.passed is None and comp.detail.startswith("undecided") and "factor" in comp.detail
    assert v.passed  # the model is the only word on which bushing it is


@pytest.mark.parametrize("n_coords", [1, 3])
def test_the_threshold_is_the_references_own_per_coordinate_capped_at_its_floor(n_coords):
    model = _linear(n_coords)
    _, limits = hold_check(model, STROKES[n_coords], FLOORS[n_coords])
    assert limits.shape == (n_coords,) and np.all(limits <= FLOORS[n_coords])
    # a noiseless linear bushing: 1 % of its largest held force per coordinate
    _, coarse = hold_check(model, STROKES[n_coords], np.full(n_coords, np.inf))
    k = np.atleast_1d(model.k_n_per_m) if n_coords == 1 else np.diag(model.k_matrix)
    np.testing.assert_allclose(coarse, 0.01 * k * STROKES[n_coords], rtol=1e-3)


def test_the_attack_refuses_a_reference_that_fails_its_vetting_unless_trusted(tmp_path, capsys):
    bad = _linear(k_scale=(1.0, -0.5, 1.0)).save(tmp_path / "bad_ref.npz")
    argv = ["attack", "--env", "rig3", "--model", "linear", "--reference", str(bad),
            "--budget", "4", "--searchers", "random", "--quiet", "--no-plots"]  # fmt: skip
    capsys.readouterr()
    assert main(argv + ["--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err.strip()
    assert "failed its vetting" in err and "--trust-reference" in err and "\n" not in err
    assert not (tmp_path / "a" / "report.json").exists()
    assert main(argv + ["--out", str(tmp_path / "b"), "--trust-reference"]) == 0
    report = json.loads((tmp_path / "b" / "report.json").read_text())
    assert report["judge"]["trusted_by_flag"] is True
    assert report["judged"]["trusted_despite_failed_vetting"] is True
    assert report["judge"]["vetting"]["passed"] is False
    assert (
        "FAILED (--trust-reference: verdicts UNVETTED)"
        in (tmp_path / "b" / "report.md").read_text()
    )


def test_a_coordinate_held_at_rest_whose_force_is_noise_is_not_judged_by_a_ratio(tmp_path):
    """A preload sweep holds the axial coordinate at zero: its load cell reads only noise, and
    a ratio to noise would refuse the very bushing that made the record."""
    from bushenv.record_files import save_columns
    from bushenv.vetting import RECORD_LIMIT
    from bushenv.vetting_records import reference_errors

    ref = _linear()
    t = np.arange(4000) * ref.dt
    q = np.zeros((t.size, 3))
    q[:, 1] = 2e-3 * np.sin(2 * np.pi * 1.3 * t)
    q[:, 2] = 0.05 * np.sin(2 * np.pi * 0.7 * t)
    rng = np.random.default_rng(0)
    noise = rng.normal(0, 1, q.shape) * np.array([2.0, 5.0, 0.05])
    path = save_columns(tmp_path / "sweep.csv", t, q, ref.simulate(q) + noise)
    [(_, worst)] = reference_errors(ref, [path])
    assert worst < 0.05 < RECORD_LIMIT
    # an axis at rest that carries a real force (coupling) is still judged
    coupled = _linear(radial_into_axial=0.3)
    path = save_columns(tmp_path / "coupled.csv", t, q, coupled.simulate(q) + noise)
    [(_, worst)] = reference_errors(ref, [path])
    assert worst > RECORD_LIMIT


def test_a_card_gives_no_ratio_on_an_axis_at_rest_reading_noise(tmp_path):
    """The card says how much force the model invents there (N), not a ratio to noise."""
    from bushenv.identify.card_records import coordinate_metrics

    ref = _linear()
    t = np.arange(3000) * ref.dt
    q = np.zeros((t.size, 3))
    q[:, 1] = 2e-3 * np.sin(2 * np.pi * 1.3 * t)
    noise = np.random.default_rng(1).normal(0, 1, q.shape) * np.array([2.0, 5.0, 0.05])
    f = ref.simulate(q) + noise
    pred = ref.simulate(q) + np.array([30.0, 0.0, 0.0])
    m = coordinate_metrics(ref.coords, f, pred, q)
    assert m["axial"]["rms_ratio"] is None and m["axial"]["max_error"] > 25.0
    assert m["rotation"]["rms_ratio"] is None and m["radial"]["rms_ratio"] < 0.01
    assert (
        coordinate_metrics(ref.coords, f, pred)["axial"]["rms_ratio"] > 1.0
    )  # without q: a ratio to noise


@pytest.mark.parametrize("n_coords", [1, 3])
def test_the_records_check_judges_a_reference_on_its_records_whatever_its_coordinates(
    tmp_path, n_coords
):
    """One records check over C: the reference's worst coordinate's RMS ratio on the records,
    within ``RECORD_LIMIT`` for the bushing that made them, beyond it for one three times as
    stiff."""
    from bushenv.models import get_model
    from bushenv.record_files import save_record
    from bushenv.records import Record
    from bushenv.vetting import RECORD_LIMIT
    from bushenv.vetting_records import reference_errors

    ref = get_model("linear", coords=n_coords)
    t = np.arange(3000) * ref.dt
    q = 1e-3 * np.sin(2 * np.pi * np.outer(t, np.arange(1, n_coords + 1) * 0.7))
    x = q[:, 0] if n_coords == 1 else q
    path = save_record(Record(t, x, ref.simulate(x)), tmp_path / "r.csv")
    [(name, worst)] = reference_errors(ref, [path])
    assert name == "r.csv" and worst < 1e-9
    stiff = ref.copy()
    if n_coords == 1:
        stiff.k_n_per_m *= 3.0
    else:
        stiff = PlanarLinear(3.0 * ref.k_matrix, ref.c_matrix, ref.dt)
    [(_, worst)] = reference_errors(stiff, [path])
    assert worst > RECORD_LIMIT
