"""The quasi-linear relaxation (``relaxation_form="qlv"``: the branches relax the elastic force
K q + G3(q)): its reduction to the constant form on a linear backbone, its law on a hardening
one, and old files that keep the constant form bit for bit (its identification:
tests/identify/test_vector_boucwen.py)."""

import json

import numpy as np
import pytest

from bushenv.models import load_model
from bushenv.models.base import PAPER_DT
from bushenv.models.boucwen import relaxation
from bushenv.models.boucwen.planar import PlanarBoucWen, vector_boucwen_kernel
from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_hybrid_bw import PlanarBoucWenHybrid
from bushenv.motions import random_independent

K = np.array([[4.0e5, 2.0e4, 1.0e3], [2.0e4, 1.5e6, 0.0], [1.0e3, 0.0, 3.0e3]])
C = np.diag([4.0e2, 1.0e3, 2.0])
D = np.array([0.4e-3, 0.5e-3, 0.012])
G = np.array([[3e11, 5e10, 1e6], [4e10, 8e11, 2e7], [1e6, 1e6, 2e4]])
TAU = [0.02, 0.5]
RATIO = np.stack([np.diag([0.3, 0.2, 0.25]), np.diag([0.1, 0.15, 0.05])])  # dimensionless


def model(form, gain, g=None, tau=TAU):
    return PlanarBoucWen(K, C, (100.0, 500.0, 40.0), D, (0.5, 0.5, 2.0), g, dt=PAPER_DT,
                         relax_tau=tau, relax_gain=gain, relaxation_form=form)  # fmt: skip


def test_on_a_linear_backbone_the_qlv_form_is_the_constant_form_with_gains_r_k():
    """With G3 = 0, F_e = K q is linear, so its increments are K times the deflection's and
    every branch s_m = K p_m: R_m s_m = (R_m K) p_m, the constant form with gains R_m K."""
    q = random_independent(1.0, 4.0, PAPER_DT, 3)
    qlv = model("qlv", RATIO).simulate(q)
    constant = model("constant", relaxation.qlv_as_constant(RATIO, K)).simulate(q)
    scale = np.abs(constant).max(axis=0)
    assert np.all(np.abs(qlv - constant).max(axis=0) <= 1e-11 * scale)
    assert np.abs(qlv - model("constant", None, tau=None).simulate(q)).max() > 1.0  # it relaxes


def test_on_a_hardening_backbone_the_relaxing_force_follows_the_tangent_stiffness():
    """A step of the same size relaxes a force proportional to the elastic force's increment:
    from a preload where the cubic backbone is stiffer it relaxes more than from rest."""
    dt = 1e-3
    k, g = np.diag([4e5, 1e6, 3e3]), np.diag([3e11, 0.0, 0.0])

    def fe(x):
        return 4e5 * x + 3e11 * x**3

    def step_force(start):
        """The relaxing force the step adds at once (a run holding the preload taken off)."""
        m = PlanarBoucWen(k, np.zeros((3, 3)), np.zeros(3), D, (0.5, 0.5, 2.0), g, dt=dt,
                          relax_tau=[0.2], relax_gain=np.diag([0.3, 0.0, 0.0])[None],
                          relaxation_form="qlv")  # fmt: skip
        held = np.zeros((300, 3))
        held[:, 0] = start
        stepped = held.copy()
        stepped[200:, 0] += 0.1e-3  # a 0.1 mm step after 0.2 s
        zero = np.zeros_like(held)
        elastic = fe(start + 0.1e-3) - fe(start)
        return m.simulate(stepped, zero)[200, 0] - m.simulate(held, zero)[200, 0] - elastic

    small, large = step_force(0.0), step_force(2.0e-3)
    a, b = relaxation.coefficients(np.array([0.2]), dt)
    assert large == pytest.approx(0.3 * b[0] * (fe(2.1e-3) - fe(2.0e-3)), rel=1e-9)
    assert small == pytest.approx(0.3 * b[0] * (fe(0.1e-3) - fe(0.0)), rel=1e-9)
    assert large / small > 3.0  # the elastic stiffness at 2 mm is 4x that at rest


def test_steps_equal_a_batched_run_and_the_form_survives_its_file(tmp_path):
    m = model("qlv", RATIO, G)
    q = random_independent(1.0, 2.0, PAPER_DT, 5)
    v = np.gradient(q, PAPER_DT, axis=0)
    whole = m.simulate(q, v)
    m.reset()
    assert np.array_equal(whole, np.array([m.step(q[t], v[t]) for t in range(len(q))]))
    back = load_model(m.save(tmp_path / "qlv.npz"))
    assert back.relaxation_form == "qlv" and np.array_equal(back.simulate(q, v), whole)
    with pytest.raises(PlanarModelError, match="relaxation_form"):
        model("maxwell", RATIO)


def test_an_old_file_loads_as_the_constant_form_and_gives_the_kernels_forces_bit_for_bit(
    tmp_path,
):
    """A file written before the setting has no ``relaxation_form``: it loads as the constant
    form, its forces are the two kernels' (the same code as before) bit for bit, and a
    constant-form model still writes the same header."""
    gain = np.stack([np.diag([1e5, 3e5, 500.0]), np.diag([2e4, 1e5, 90.0])])
    old = model("constant", gain, G)
    path = old.save(tmp_path / "old.npz")
    with np.load(path) as z:
        meta = json.loads(str(z["__meta__"]))
    assert meta["extra"] == {"yield_surface": "vector"}  # the header files always had
    back = load_model(path)
    q = random_independent(1.0, 2.0, PAPER_DT, 1)
    v = np.gradient(q, PAPER_DT, axis=0)
    qb, vb = q[:, None, :].copy(), v[:, None, :].copy()
    want = np.empty_like(qb)
    state = np.zeros((12, 1))
    vector_boucwen_kernel(qb, vb, state, K, C, G, np.array([100.0, 500.0, 40.0]), D,
                          0.5, 0.5, 2.0, True, want)  # fmt: skip
    a, b = relaxation.coefficients(np.array(TAU), PAPER_DT)
    relaxation.relaxation_kernel(qb, np.zeros((3, 1)), state[6:], a, b, gain, want)
    assert back.relaxation_form == "constant"
    assert np.array_equal(back.simulate(q, v), want[:, 0])


def test_the_hybrid_carries_the_form_to_its_backbone(tmp_path):
    bw = model("qlv", RATIO, G)
    net = PlanarBoucWenHybrid.untrained(seed=0)
    hyb = PlanarBoucWenHybrid(
        **bw.params, **{k: net.params[k] for k in net.params if k not in bw.params},
        **bw.extra_meta(), dt=PAPER_DT,
    )  # fmt: skip
    back = load_model(hyb.save(tmp_path / "hbw.npz"))
    assert back.backbone.relaxation_form == "qlv"
    assert back.backbone_alone().relaxation_form == "qlv"
    q = random_independent(1.0, 1.0, PAPER_DT, 2)
    assert np.array_equal(back.backbone_alone().simulate(q), bw.simulate(q))
