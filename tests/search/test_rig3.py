"""The rig3 target: planar families, the per-axis verdict and per-axis shrinking."""

import numpy as np
import pytest

from bushenv.models.base import PAPER_DT
from bushenv.models.planar_linear import PlanarLinear
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.families import FAMILIES, pad_batch
from bushenv.search.limits import COORDS, rig3_limits
from bushenv.search.shrink import shrink
from bushenv.search.targets import TARGETS

DT = PAPER_DT


def _only_axis_active(i: int) -> PlanarLinear:
    """The planar Table-1 model with negative damping in coordinate ``i`` only."""
    ref = PlanarLinear.preset()
    c = ref.c_matrix.copy()
    c[i, i] *= -0.5
    return PlanarLinear(ref.k_matrix, c, ref.dt)


def test_planar_families_are_the_rig3_targets_and_not_the_rigs():
    planar = {"preload_step", "rotation_sweep", "orbit", "random3", "any3", "one_axis"}
    assert set(TARGETS["rig3"].family_names()) == planar
    assert not planar & set(TARGETS["rig"].family_names())
    assert set(TARGETS["rig3"].random_families()) == planar - {"any3", "one_axis"}


def test_one_axis_moves_one_coordinate_only_as_a_single_axis_test_does():
    fam = FAMILIES["one_axis"]
    rng = np.random.default_rng(5)
    seen = set()
    for _ in range(30):
        u = rng.random(fam.dim)
        q = fam.profile(u, DT)
        moving = [COORDS[i] for i in range(3) if np.any(q[:, i] != 0)]
        assert len(moving) <= 1
        assert moving in ([], [fam.describe(u, DT)["axis"]])
        seen |= set(moving)
    assert seen == set(COORDS)


@pytest.mark.parametrize("name", ["preload_step", "rotation_sweep", "orbit", "random3"])
def test_every_planar_family_moves_more_than_one_axis_somewhere(name):
    fam = FAMILIES[name]
    rng = np.random.default_rng(3)
    moving = set()
    for _ in range(12):
        q = fam.profile(rng.random(fam.dim), DT)
        assert q.ndim == 2 and q.shape[1] == 3
        moving |= {i for i in range(3) if np.any(q[:, i] != 0)}
    assert len(moving) >= 2, f"{name} only ever moves {moving}"


def test_preload_step_holds_the_preload_while_the_other_axis_steps():
    u = np.array([0.5, 0.9, 1.0, 1.0, 0.0, 0.5])  # preload radial at +80 %, step the rotation
    q = FAMILIES["preload_step"].profile(u, DT)
    desc = FAMILIES["preload_step"].describe(u, DT)
    assert (desc["preload_axis"], desc["step_axis"]) == ("radial", "rotation")
    stroke = rig3_limits()[0]
    step_starts = int(np.flatnonzero(q[:, 2])[0])
    assert q[step_starts, 1] == pytest.approx(0.8 * stroke[1])
    assert np.all(q[:, 0] == 0)
    assert q[-1, 2] == pytest.approx(0.95 * stroke[2])


def test_a_circular_orbit_keeps_its_radius_between_the_fades():
    u = np.array([0.5, 1.0, 0.3, 0.2, 0.0, 0.4])  # minor/major 1: a circle
    q = FAMILIES["orbit"].profile(u, DT)
    r = np.hypot(q[:, 0], q[:, 1])
    nf = int(round(0.25 / DT))
    moving = np.flatnonzero(r > 0)
    mid = r[moving[0] + nf + 2 : moving[-1] - nf - 2]
    assert mid.size > 50 and np.ptp(mid) < 1e-9 * mid.max() + 1e-12
    assert np.all(q[:, 2] == 0)


def test_random3_lags_the_radial_behind_the_axial_as_its_coordinate_says():
    base = np.array([1.0, 1.0, 0.0, 0.5, 0.5, 0.0, 0.0, 0.3, 0.3])
    lagged = base.copy()
    lagged[5] = 1.0
    d0 = FAMILIES["random3"].describe(base, DT)
    d1 = FAMILIES["random3"].describe(lagged, DT)
    assert d0["lag_s"][1] == 0.0 and d1["lag_s"][1] > 0.1
    q = FAMILIES["random3"].profile(lagged, DT)
    lag = int(round(d1["lag_s"][1] / DT))
    first_axial = int(np.flatnonzero(q[:, 0])[0])
    assert int(np.flatnonzero(q[:, 1])[0]) == first_axial + lag


def test_pad_batch_stacks_planar_profiles_holding_their_last_row():
    a, b = np.ones((4, 3)), np.arange(6.0).reshape(2, 3)
    x, lengths = pad_batch([a, b])
    assert x.shape == (4, 2, 3) and lengths.tolist() == [4, 2]
    assert np.array_equal(x[:, 1], [[0, 1, 2], [3, 4, 5], [3, 4, 5], [3, 4, 5]])


@pytest.mark.parametrize("i", range(3))
def test_the_verdict_names_the_axis_that_failed(i):
    ref = PlanarLinear.preset()
    orbit = FAMILIES["random3"].profile(np.full(9, 0.7), DT)
    with BatchEvaluator(_only_axis_active(i), ref, "rig3") as ev:
        row = ev.evaluate([orbit]).verdict.row(0)
    assert row["diverged"] and row["axis"] == COORDS[i]
    assert row["axis_robustness"][COORDS[i]] < 0
    others = [row["axis_robustness"][c] for c in COORDS if c != COORDS[i]]
    assert all(r > 0 for r in others)


def test_a_moment_error_is_judged_on_the_moments_scale_not_the_forces():
    """60 N m of extra moment is nothing next to 200 N but a failure next to 20 N m."""
    ref = PlanarLinear.preset()

    class Offset(PlanarLinear):
        def _advance(self, q, v, out):
            super()._advance(q, v, out)
            out[..., 2] += 60.0 * (np.abs(q[..., 1]) > 1e-3)

    model = Offset(ref.k_matrix, ref.c_matrix, ref.dt)
    u = np.array([0.5, 0.0, 1.0, 0.5, 0.0, 1.0])  # radial preload, no rotation at all
    q = FAMILIES["preload_step"].profile(u, DT)
    with BatchEvaluator(model, ref, "rig3") as ev:
        row = ev.evaluate([q]).verdict.row(0)
    assert row["diverged"] and row["axis"] == "rotation"


def test_the_linear_reference_of_itself_is_never_flagged():
    ref = PlanarLinear.preset()
    rng = np.random.default_rng(0)
    profiles = []
    for name in TARGETS["rig3"].random_families():
        fam = FAMILIES[name]
        profiles += [fam.profile(rng.random(fam.dim), DT) for _ in range(3)]
    with BatchEvaluator(PlanarLinear.preset(), ref, "rig3") as ev:
        assert not ev.evaluate(profiles).verdict.diverged.any()


def test_shrinking_puts_the_axes_that_do_not_matter_at_rest():
    ref = PlanarLinear.preset()
    q = FAMILIES["random3"].profile(np.full(9, 0.7), DT)
    assert all(np.any(q[:, i] != 0) for i in range(3))
    with BatchEvaluator(_only_axis_active(2), ref, "rig3") as ev:
        small = shrink(q, ev, budget=120)
    assert small.verdict["diverged"] and small.verdict["axis"] == "rotation"
    assert np.all(small.profile[:, :2] == 0), "the axial and radial motion should be gone"
    assert np.any(small.profile[:, 2] != 0)
    assert small.final < small.original


def test_the_controls_are_never_flagged_against_the_coupled_reference():
    """The planar Table-1 linear model and the measured reference (load-cell noise) against
    the coupled reference: no planar family's corners, centre or random points flag them."""
    from bushenv.reference.planar import PlanarRubber
    from bushenv.search.checks import family_profiles

    target = TARGETS["rig3"]
    profiles = [x for _, x in family_profiles(target)]
    rng = np.random.default_rng(11)
    for name in target.family_names():
        fam = FAMILIES[name]
        profiles += [fam.profile(rng.random(fam.dim), DT) for _ in range(6)]
    ref = PlanarRubber.preset(measurement=False)
    for control in (PlanarLinear.preset(), PlanarRubber.preset(measurement=True)):
        with BatchEvaluator(control, ref, "rig3") as ev:
            v = ev.evaluate(profiles).verdict
        assert not v.diverged.any(), [v.row(b) for b in np.flatnonzero(v.diverged)][:2]


def test_two_threads_give_the_verdicts_and_axes_of_one():
    ref = PlanarLinear.preset()
    rng = np.random.default_rng(2)
    profiles = []
    for name in TARGETS["rig3"].random_families():
        fam = FAMILIES[name]
        profiles += [fam.profile(rng.random(fam.dim), DT) for _ in range(2)]
    rows = []
    for threads in (1, 2):
        with BatchEvaluator(_only_axis_active(1), ref, "rig3", threads=threads) as ev:
            v = ev.evaluate(profiles).verdict
        rows.append([v.row(b) for b in range(len(profiles))])
    assert rows[0] == rows[1]
    assert any(r["diverged"] for r in rows[0]) and {r["axis"] for r in rows[0]} >= {"radial"}


def test_a_coordinate_held_while_another_moves_is_not_in_a_hold():
    """A radial step moves a coupled model's moment; the rotation was held all along, but the
    bushing was not at rest: no ``self_sustained`` verdict on it (it was, when each coordinate
    was judged on its own hold)."""
    from bushenv.search.target_base import held_vector, judge_coordinates
    from bushenv.search.targets import MACHINE_FLOORS, coordinate_scales

    ref = PlanarLinear.preset()
    k = ref.k_matrix.copy()
    k[2, 1] += 2000.0  # 6 N m of moment at 3 mm radial: above the rotation's 5 N m hold margin
    model = PlanarLinear(k, ref.c_matrix, ref.dt)
    dt = ref.dt
    n0, n1, n2 = int(1.2 / dt), 5, int(1.5 / dt)
    q = np.zeros((n0 + n1 + n2, 3))
    q[n0 : n0 + n1, 1] = np.linspace(0.0, 3e-3, n1)
    q[n0 + n1 :, 1] = 3e-3
    target = TARGETS["rig3"]
    hold = held_vector(q[:, None, :], target.shown_units)
    assert hold[n0 - 1, 0] == 0.0 and hold[-1, 0] == hold[n0 + n1, 0] > 0.0
    scales = coordinate_scales(target.env_id, target.coords, MACHINE_FLOORS)
    v = judge_coordinates(q[:, None, :], model.simulate(q)[:, None, :],
                          ref.simulate(q)[:, None, :], dt, np.array([q.shape[0]]), scales,
                          target.coords, target.shown_units)  # fmt: skip
    assert not v.flags["self_sustained"][0] and not v.diverged[0]


def test_the_floors_follow_the_judging_references_stiffness_and_the_builtin_keeps_the_papers():
    from bushenv.rigs.common import resolve_model
    from bushenv.search.targets import MACHINE_FLOORS, reference_floors

    builtin, why = reference_floors(
        resolve_model("reference", dt=DT, coords=3, what="reference", env_id="BushRig3-v0")
    )
    assert np.array_equal(builtin, MACHINE_FLOORS) and "x1," in why
    lin = PlanarLinear.preset()
    stiff = PlanarLinear(lin.k_matrix * np.array([1.0, 3.0, 1.0])[:, None], lin.c_matrix, lin.dt)
    ratio = reference_floors(stiff)[0] / reference_floors(lin)[0]
    assert ratio == pytest.approx([1.0, 3.0, 1.0], rel=1e-6)


def test_a_stiffer_reference_judges_at_its_own_floor():
    """A 300 N axial force under a radial preload (the axial coordinate at rest) fails against
    the linear preset's floor (240 N), not against that of a reference four times as stiff
    (960 N): the floor is the judging bushing's."""
    lin = PlanarLinear.preset()

    class Offset(PlanarLinear):
        def _advance(self, q, v, out):
            super()._advance(q, v, out)
            out[..., 0] += 300.0 * (np.abs(q[..., 1]) > 1e-3)

    u = np.array([0.5, 0.0, 1.0, 0.5, 0.0, 1.0])  # a radial preload step, the others at rest
    q = FAMILIES["preload_step"].profile(u, DT)
    rows = {}
    for name, k_scale in (("preset", 1.0), ("stiff", 4.0)):
        ref = PlanarLinear(lin.k_matrix * k_scale, lin.c_matrix, lin.dt)
        model = Offset(ref.k_matrix, ref.c_matrix, ref.dt)
        with BatchEvaluator(model, ref, "rig3") as ev:
            rows[name] = ev.evaluate([q]).verdict.row(0)
    assert rows["preset"]["diverged"] and rows["preset"]["axis"] == "axial"
    assert not rows["stiff"]["diverged"]
