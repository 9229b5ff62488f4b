"""Structured MIMO networks (identify/mimo_structure.py): the mirror network holds, and runs,
exactly zero force in a coordinate kept at rest where the free one does not; the rate network's held
recurrence is the same at every hold; the certified term's gradients reach the tied
parameters; and a certified mirror hybrid keeps its network where the free one falls silent."""

import numpy as np
import pytest
import torch

from bushenv.certify.fixed_points import fixed_points
from bushenv.certify.network import narx_net
from bushenv.identify import fit
from bushenv.identify.mimo_certified import MimoCertifiedHolds, MimoProblem
from bushenv.identify.mimo_structure import SIGNS, StructuredNet, fit_diagonal_linear
from bushenv.identify.mimo_train import _Net
from bushenv.identify.static_estimate import static_estimate
from bushenv.models.base import PAPER_DT
from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_narx import PlanarHybrid, input_axes
from bushenv.motions import random_independent
from bushenv.reference.planar import PlanarRubber

Q_SCALE = np.array([2e-3, 2e-3, 0.05])
F_SCALE = np.array([300.0, 1000.0, 100.0])


def _lively(net):
    """Weights large enough that the network's output is far from linear, biases non-zero."""
    with torch.no_grad():
        for p in net.parameters():
            if p.requires_grad:
                p.mul_(3.0)
        b = net.bh if isinstance(net, StructuredNet) else net.b1
        b.copy_(torch.linspace(-0.4, 0.3, b.numel(), dtype=torch.float64))
    return net


def _net(structure, seed=0, hidden=6):
    gen = torch.Generator().manual_seed(seed)
    net = _Net(hidden, False, gen) if structure == "free" else StructuredNet(structure, hidden, gen)
    return _lively(net)


K = np.diag([3e5, 1.2e6, 3e3])


def _hybrid(net):
    return PlanarHybrid(
        k_matrix=K, c_matrix=np.zeros((3, 3)), q_offset=np.zeros(3), q_scale=Q_SCALE,
        f_offset=np.zeros(3), f_scale=F_SCALE, dt=PAPER_DT, **net.arrays(),
    )  # fmt: skip


def test_the_mirror_network_is_equivariant_under_each_coordinates_mirror():
    net = _net("mirror")
    z = torch.randn(7, 33, generator=torch.Generator().manual_seed(1), dtype=torch.float64)
    y = net(z)
    assert y.abs().min() > 1e-3  # a lively network, not a silent one
    for s in SIGNS:
        flipped = net(z * torch.from_numpy(s[input_axes()]))
        assert torch.allclose(flipped, y * torch.from_numpy(s), atol=1e-13, rtol=0)
    assert net.w1.shape == (8, 33) and np.all(net.arrays()["b_out"] == 0.0)


@pytest.mark.parametrize("still", [0, 1, 2])
def test_a_coordinate_at_rest_carries_exactly_no_force_in_the_mirror_hybrid(still):
    q = random_independent(1.0, 3.0, PAPER_DT, 4)
    q[:, still] = 0.0
    free, mirror = _hybrid(_net("free")), _hybrid(_net("mirror"))
    assert np.abs(mirror.simulate(q)[:, still]).max() < 1e-6  # moving, every sample (rounding)
    assert np.abs(free.simulate(q)[:, still]).max() > 1.0  # N (or N m): the free one does not
    held = np.array([[8e-3, -5e-3, 0.1], [-12e-3, 2e-3, -0.04]])
    held[:, still] = 0.0
    fp = fixed_points(mirror, held)
    assert np.all(fp.count == 1)
    assert np.abs(fp.force[:, still]).max() < 1e-9
    assert np.abs(fixed_points(free, held).force[:, still]).max() > 1.0


def test_the_rate_networks_held_recurrence_is_the_same_at_every_hold():
    for structure in ("rate", "mirror-rate"):
        model = _hybrid(_net(structure, seed=2))
        held = narx_net(model)
        q = np.array([[0.0, 0.0, 0.0], [12e-3, -7e-3, 0.15], [-3e-3, 12e-3, -0.1]])
        c = held.held(q)
        assert np.allclose(c, c[0], atol=1e-12, rtol=0)
        fp = fixed_points(model, q)  # the same fixed points at every hold, on the backbone
        assert np.all(fp.count == fp.count[0])
        net_force = np.round(fp.force - q[fp.hold] @ model.k_matrix.T, 6).reshape(3, -1, 3)
        each = [f[np.lexsort(f.T[::-1])] for f in net_force]
        assert np.allclose(each, each[0], atol=1e-5, rtol=0)
    # and a free network's is not
    c = narx_net(_hybrid(_net("free"))).held(q)
    assert np.abs(c - c[0]).max() > 0.1


def test_the_certified_terms_gradient_reaches_the_tied_parameters():
    q = random_independent(1.0, 20.0, PAPER_DT, 0)
    estimate = static_estimate([(q, PlanarRubber.preset(seed=0).simulate(q))], PAPER_DT)
    problem = MimoProblem(np.zeros(3), Q_SCALE, np.zeros(3), F_SCALE,
                            np.diag(1.2 * estimate.k), PAPER_DT, estimate)  # fmt: skip
    for structure in ("mirror", "rate"):
        net = _net(structure, seed=3)
        term = MimoCertifiedHolds(1.0, holds=7)

        def value(term=term, net=net):
            term.calls = 0
            return term(net, problem)

        net.zero_grad()
        v = value()
        assert v.item() > 0
        v.backward()
        h = 1e-6
        for name, index in (("wd", (0, 3)), ("wy", (0, 4)), ("bh", (0,)), ("v", (1, 0))):
            p = getattr(net, name)
            with torch.no_grad():
                p[index] += h
                up = value().item()
                p[index] -= 2 * h
                down = value().item()
                p[index] += h
            grad = p.grad[index].item()
            assert grad == pytest.approx((up - down) / (2 * h), rel=1e-4, abs=1e-6), name
            assert grad != 0.0 or name == "bh"


def test_the_diagonal_backbone_fits_each_coordinate_alone():
    q = random_independent(1.0, 20.0, PAPER_DT, 1)
    k, c = np.array([3e5, 1.5e6, 3e3]), np.array([4e3, 1.5e4, 30.0])
    from bushenv.models.base import velocity_of

    f = q * k + velocity_of(q, PAPER_DT) * c
    f[:, 0] += 1e4 * q[:, 1]  # a cross term, which the diagonal backbone leaves out
    lin = fit_diagonal_linear(q, f, PAPER_DT)
    assert np.all(lin.k_matrix[~np.eye(3, dtype=bool)] == 0.0)
    assert np.diag(lin.k_matrix)[1:] == pytest.approx(k[1:], rel=1e-6)
    assert np.diag(lin.c_matrix)[1:] == pytest.approx(c[1:], rel=1e-6)
    assert np.diag(lin.k_matrix)[0] == pytest.approx(k[0], rel=0.05)


def test_structure_is_an_option_of_nn_and_hybrid_only():
    from bushenv.identify.mimo_options import MimoOptions
    from bushenv.identify.options import options_of

    assert options_of(MimoOptions, {"structure": "mirror"}, "hybrid").structure == "mirror"
    with pytest.raises(Exception, match="structure must be one of"):
        options_of(MimoOptions, {"structure": "odd"}, "hybrid")
    q = random_independent(1.0, 8.0, PAPER_DT, 0)
    rec = (q, PlanarRubber.preset(seed=0).simulate(q))
    with pytest.raises(PlanarModelError, match="nn-axis takes structure 'free' only"):
        fit([rec], "nn-axis", {"structure": "mirror"}, progress=False, dt=PAPER_DT)


def _share(model, q, f):
    from bushenv.models.base import velocity_of

    part = model.simulate(q) - q @ model.k_matrix.T - velocity_of(q, model.dt) @ model.c_matrix.T
    return np.sqrt(np.mean(part**2, axis=0)) / np.sqrt(np.mean(f**2, axis=0))


@pytest.mark.slow
def test_a_certified_mirror_hybrid_keeps_its_network_where_the_free_one_falls_silent():
    q = random_independent(1.0, 30.0, PAPER_DT, 0)
    rec = (q, PlanarRubber.preset(seed=0).simulate(q))
    qu = random_independent(1.0, 10.0, PAPER_DT, 99)
    fu = PlanarRubber.preset(seed=99).simulate(qu)
    free = fit([rec], "hybrid", {"certified": "on"}, 0, progress=False, dt=PAPER_DT).model
    opts = {"certified": "on", "structure": "mirror"}
    mirror = fit([rec], "hybrid", opts, 0, progress=False, dt=PAPER_DT).model
    assert mirror.training["certified"]["admitted"]
    assert np.all(_share(mirror, qu, fu) > 0.04)
    assert np.all(_share(free, qu, fu) < 0.03)


def test_bushenv_fit_takes_structure_mirror_for_3_axis_records(tmp_path, capsys):
    from bushenv.cli import main
    from bushenv.models import load_model

    rec = tmp_path / "rec"
    assert main(["measure", "--axes", "3", "--programme", "random", "--duration", "6",
                 "--out", str(rec), "--quiet"]) == 0  # fmt: skip
    train = sorted(map(str, rec.glob("*.csv")))
    args = ["fit", *train, "--model", "hybrid", "--hidden", "6", "--teacher-steps", "8",
            "--free-run-steps", "0", "--window", "16", "--quiet"]  # fmt: skip
    assert main([*args, "--structure", "mirror", "--out", str(tmp_path / "m.npz")]) == 0
    model = load_model(tmp_path / "m.npz")
    assert model.w1.shape[0] == 8 and np.all(model.k_matrix == np.diag(np.diag(model.k_matrix)))
    q = random_independent(1.0, 2.0, PAPER_DT, 3)
    q[:, 1] = 0.0
    assert np.abs(model.simulate(q)[:, 1]).max() < 1e-6
    capsys.readouterr()
    assert main([*args, "--structure", "odd", "--out", str(tmp_path / "o.npz")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "structure must be one of free, mirror" in err[0]
