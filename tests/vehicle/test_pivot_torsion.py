"""The arm pivots' rotation is a torsion: the reference's torsion parameter set from the bush's
geometry (reference/planar.py), the names the half car asks for, and what it does to the car's
wheel rate."""

import math

import numpy as np
import pytest

from bushenv.models import get_model, get_reference
from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_linear import PlanarLinear
from bushenv.reference.planar import (
    BUSH_INNER_RADIUS_M,
    BUSH_LENGTH_M,
    BUSH_OUTER_RADIUS_M,
    MAX_ROTATION_RAD,
    ROTATION_K_NM_PER_RAD,
    TORSION_MAX_ROTATION_RAD,
    TORSION_MAX_SHEAR_STRAIN,
    PlanarRubber,
    axial_strain_per_m,
    default_parameters,
    shear_modulus_pa,
    torsion_per_axial,
    torsion_strain_per_rad,
)
from bushenv.reference.planar_elastic import tangent_stiffness
from bushenv.reference.rubber import PRESETS as ONE_AXIS
from bushenv.rigs.halfcar_params import LINEAR, PIVOT_ROTATION, REFERENCE, HalfCarParameters
from bushenv.rigs.specs import spec_kwargs

TABLE1_AXIAL_N_PER_M = 379.68e3  # seed 000 Table 1


def bonded_bush(k_axial, a, b, length):
    """(G, K_t) of a bonded annulus from its axial stiffness: K_a = 2 pi G L / ln(b/a) (Adkins
    & Gent 1954), K_t = 4 pi G L / (1/a^2 - 1/b^2) (García Tárrago et al. 2007)."""
    g = k_axial * math.log(b / a) / (2 * math.pi * length)
    return g, 4 * math.pi * g * length / (1 / a**2 - 1 / b**2)


def test_the_torsion_preset_is_the_bonded_bush_formula_on_seed_002s_geometry():
    a, b, length = BUSH_INNER_RADIUS_M, BUSH_OUTER_RADIUS_M, BUSH_LENGTH_M
    # seed 002 Table 2: inner steel 15 mm, outer 50 mm with a 3 mm wall, 63 mm long
    np.testing.assert_allclose((a, b, length), (7.5e-3, 22e-3, 63e-3), rtol=1e-12)
    g, k_t = bonded_bush(TABLE1_AXIAL_N_PER_M, a, b, length)
    assert shear_modulus_pa(TABLE1_AXIAL_N_PER_M) == pytest.approx(g)
    assert 0.5e6 < g < 2e6  # a filled natural rubber's shear modulus, Pa
    lin = PlanarLinear.preset(rotation="torsion")
    assert lin.k_matrix[2, 2] == pytest.approx(k_t, rel=1e-12)
    assert k_t == pytest.approx(52.0, abs=0.05)  # N m/rad: 1/58 of the cardanic 3000
    assert lin.c_matrix[2, 2] == pytest.approx(4.4e3 * k_t / TABLE1_AXIAL_N_PER_M)
    ax = ONE_AXIS["axial"]
    _, k_ref = bonded_bush(ax["k_n_per_m"], a, b, length)  # the reference's axial backbone
    p = default_parameters("torsion")
    assert p["stiffness"][2] == pytest.approx(k_ref, rel=1e-12)
    # the axial row mapped: the same loss time, the same friction loop at the n = 1 amplitudes
    assert p["damping"][2] / p["stiffness"][2] == pytest.approx(ax["c_ns_per_m"] / ax["k_n_per_m"])
    theta_1, x_1 = 0.05, 2e-3
    assert p["friction_fmax"][2] / (p["stiffness"][2] * theta_1) == pytest.approx(
        ax["friction_fmax_n"] / (ax["k_n_per_m"] * x_1)
    )
    assert p["friction_x2"][2] / theta_1 == pytest.approx(ax["friction_x2_m"] / x_1)
    np.testing.assert_allclose(p["relax_weight"][:, 2], p["relax_weight"][:, 0])
    assert torsion_per_axial() == pytest.approx(k_t / TABLE1_AXIAL_N_PER_M)


def test_the_cardanic_set_stays_the_default_and_unknown_sets_are_refused():
    assert default_parameters()["stiffness"][2] == ROTATION_K_NM_PER_RAD
    assert PlanarRubber.preset().stiffness[2] == ROTATION_K_NM_PER_RAD
    assert PlanarLinear.preset().k_matrix[2, 2] == ROTATION_K_NM_PER_RAD
    with pytest.raises(PlanarModelError, match="rotation 'tilt'"):
        PlanarRubber.preset(rotation="tilt")
    with pytest.raises(PlanarModelError, match="rotation 'tilt'"):
        PlanarLinear.preset(rotation="tilt")
    with pytest.raises(PlanarModelError, match="0 < a < b"):
        torsion_per_axial(0.02, 0.01)


def test_the_car_asks_for_the_torsion_set_by_its_registered_names():
    assert PIVOT_ROTATION == "torsion"
    ref = get_reference(REFERENCE, coords=3)
    assert isinstance(ref, PlanarRubber) and "noise" not in ref.effects
    assert ref.stiffness[2] == pytest.approx(default_parameters("torsion")["stiffness"][2])
    lin = get_model(LINEAR, coords=3)
    np.testing.assert_array_equal(lin.k_matrix, PlanarLinear.preset(rotation="torsion").k_matrix)
    kw = spec_kwargs("HalfCar-v0", {})
    assert (kw["model"], kw["reference"]) == (LINEAR, REFERENCE)
    p = HalfCarParameters(kw)
    assert p.references.stiffness[2] == ref.stiffness[2]
    assert p.k_in[2] == lin.k_matrix[2, 2]  # the split's in-sub-step part


def test_the_torsion_sets_energy_stays_convex_over_the_stroke_and_rotation_range():
    p = PlanarRubber.preset(rotation="torsion").elastic_params()
    for ua in np.linspace(-12.5e-3, 12.5e-3, 5):
        for ur in np.linspace(-12.5e-3, 12.5e-3, 9):
            for th in np.linspace(-TORSION_MAX_ROTATION_RAD, TORSION_MAX_ROTATION_RAD, 13):
                assert np.linalg.eigvalsh(tangent_stiffness(np.array([ua, ur, th]), p)).min() > 0


def test_the_torsion_range_is_the_rotation_that_shears_the_inner_radius_to_strain_one():
    """Torsion of a bonded annulus: shear stress T / (2 pi r^2 L), strain gamma(r) = T / (2 pi
    G L r^2), the twist the integral of gamma / r from a to b; gamma at a over the twist is
    2 / (1 - a^2/b^2). Filled rubber stays near-linear in shear to gamma ~ 1: 0.442 rad."""
    a, b = BUSH_INNER_RADIUS_M, BUSH_OUTER_RADIUS_M
    r = np.linspace(a, b, 200_001)
    gamma = (a / r) ** 2  # per unit strain at a
    theta = float(np.sum((gamma / r)[:-1] + (gamma / r)[1:]) * (r[1] - r[0]) / 2)
    assert torsion_strain_per_rad() == pytest.approx(1 / theta, rel=1e-8)
    assert torsion_strain_per_rad() == pytest.approx(2.263, abs=1e-3)  # the brief's 2.26
    assert TORSION_MAX_SHEAR_STRAIN == 1.0
    assert TORSION_MAX_ROTATION_RAD == pytest.approx((1 - (a / b) ** 2) / 2, rel=1e-12)
    assert TORSION_MAX_ROTATION_RAD == pytest.approx(0.442, abs=1e-3)
    # each set its own range: the torsion preset's, the cardanic one's 0.15 rad unchanged
    torsion = get_reference(REFERENCE, coords=3)
    assert torsion.calibrated_rotation_rad == TORSION_MAX_ROTATION_RAD
    assert PlanarRubber.preset().calibrated_rotation_rad == MAX_ROTATION_RAD == 0.15
    assert torsion.copy().calibrated_rotation_rad == TORSION_MAX_ROTATION_RAD
    assert torsion.only_effects("coupling").calibrated_rotation_rad == TORSION_MAX_ROTATION_RAD
    with pytest.raises(PlanarModelError, match="calibrated_rotation_rad"):
        PlanarRubber((1.0, 1.0, 1.0), (0.0, 0.0, 0.0), calibrated_rotation_rad=0.0)


def test_a_saved_torsion_reference_keeps_its_range_and_a_cardanic_file_is_as_before(tmp_path):
    from bushenv.models import load_model

    torsion = PlanarRubber.preset(rotation="torsion", measurement=False)
    back = load_model(torsion.save(tmp_path / "t.npz"), coords=3)
    assert back.calibrated_rotation_rad == TORSION_MAX_ROTATION_RAD
    assert "calibrated_rotation_rad" not in PlanarRubber.preset().extra_meta()


def test_the_torsion_hardening_is_the_axial_rows_at_the_same_inner_strain():
    """Hardening is the rubber's at a strain: at the torsion range's end (strain 1 at the inner
    radius) the secant stiffening k theta^3 / L^2 over k theta is the axial row's at strain 1
    (an axial deflection u shears the inner radius by u / (a ln(b/a))): +25 %."""
    a, b = BUSH_INNER_RADIUS_M, BUSH_OUTER_RADIUS_M
    p = default_parameters("torsion")
    assert axial_strain_per_m() == pytest.approx(1 / (a * math.log(b / a)))
    u = TORSION_MAX_SHEAR_STRAIN / axial_strain_per_m()  # axial deflection at strain 1, m
    axial = (u / p["hardening_m"][0]) ** 2
    torsion = (TORSION_MAX_ROTATION_RAD / p["hardening_m"][2]) ** 2
    assert torsion == pytest.approx(axial, rel=1e-12)
    assert 0.2 < torsion < 0.3  # near-linear at the range's end, stiffening beyond
    # the coupling keeps its shape over the range: its dip at the cardanic share of the range
    theta_m = p["coupling"][2]
    cardanic = default_parameters("cardanic")["coupling"][2]
    assert theta_m / TORSION_MAX_ROTATION_RAD == pytest.approx(cardanic / MAX_ROTATION_RAD)


def test_in_the_half_car_the_spring_carries_the_wheel_rate_and_the_bushings_a_minority():
    """A control arm's bushings add a few % to a passenger car's wheel rate; here the four
    pivots' torsion (52 N m/rad through the arms' 3.05 and 4.70 rad/m) is 5.5 % of it, the coil
    the rest. Bound: at most 10 % (with the cardanic 3000 N m/rad the bushings were 77 %).
    Body bounce on the tyre 1.0-1.5 Hz (a passenger car's ride frequency)."""
    p = HalfCarParameters(spec_kwargs("HalfCar-v0", {}), resolve_models=False)
    eq = p.equivalent_corner()
    k_w = eq["wheel_rate_n_per_m"]
    coil = p.k_s * eq["dspring"] ** 2
    bushings = k_w - coil
    assert 0 < bushings < 0.10 * k_w
    assert bushings == pytest.approx(p.k_in[2] * (eq["dalpha"] ** 2 + eq["dbeta"] ** 2))
    cardanic = p.equivalent_corner(k_bushing=(0.0, 0.0, ROTATION_K_NM_PER_RAD))
    assert (cardanic["wheel_rate_n_per_m"] - coil) / cardanic["wheel_rate_n_per_m"] > 0.7
    ride = k_w * p.k_t / (k_w + p.k_t)
    f_body = math.sqrt(ride / (p.m_s / 2)) / (2 * math.pi)
    assert 1.0 <= f_body <= 1.5
