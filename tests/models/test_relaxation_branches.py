"""The relaxation (Prony series) on the deflection vector: its law, its passivity and its files
(its identification inside the vector Bouc-Wen: tests/identify/test_vector_boucwen.py)."""

import numpy as np
import pytest

from bushenv.models import load_model
from bushenv.models.base import PAPER_DT
from bushenv.models.boucwen.planar import PlanarBoucWen
from bushenv.models.planar_base import PlanarModelError
from bushenv.motions import random_independent

K = np.diag([4.0e5, 1.5e6, 3.0e3])
C = np.diag([4.0e2, 1.0e3, 2.0])
D = np.array([0.4e-3, 0.5e-3, 0.012])


def relaxing(tau, gain, h=(100.0, 500.0, 40.0), dt=PAPER_DT) -> PlanarBoucWen:
    return PlanarBoucWen(K, C, h, D, (0.5, 0.5, 2.0), dt=dt, relax_tau=tau, relax_gain=gain)


def test_a_held_deflection_relaxes_with_each_branch_time_constant():
    tau, dt = 0.2, 1e-3
    gain = np.array([[[2.0e5, 0, 0], [0, 0, 0], [0, 0, 0]]])
    model = relaxing([tau], gain, h=(0.0, 0.0, 0.0), dt=dt)
    plain = relaxing(None, None, h=(0.0, 0.0, 0.0), dt=dt)
    T = 2000
    q = np.zeros((T, 3))
    q[:10, 0] = np.linspace(0.1, 1.0, 10) * 1e-3  # 1 mm at a constant rate over 10 dt, held
    q[10:, 0] = 1e-3
    extra = model.simulate(q, np.zeros_like(q)) - plain.simulate(q, np.zeros_like(q))
    t = np.arange(T) * dt
    want = extra[9, 0] * np.exp(-(t[9:] - t[9]) / tau)
    assert np.allclose(extra[9:, 0], want, rtol=1e-9, atol=1e-9)
    rate = 1e-3 / (10 * dt)  # a Maxwell branch at constant rate V: R V tau (1 - e^(-t / tau))
    assert extra[9, 0] == pytest.approx(2.0e5 * rate * tau * (1 - np.exp(-10 * dt / tau)))
    assert np.all(extra[:, 1:] == 0)


def test_steps_equal_a_batched_run_and_the_state_carries_the_branches():
    gain = np.stack([np.diag([1e5, 3e5, 500.0]), np.ones((3, 3)) * 2e4])  # one couples the axes
    model = relaxing([0.02, 0.5], gain)
    q = random_independent(1.0, 2.0, PAPER_DT, 3)
    v = np.gradient(q, PAPER_DT, axis=0)
    whole = model.simulate(q, v)
    assert model.state.shape == (12, 1)
    model.reset()
    stepped = np.array([model.step(q[t], v[t]) for t in range(q.shape[0])])
    assert np.array_equal(whole, stepped)


def test_a_file_from_before_the_relaxation_loads_without_it(tmp_path):
    old = relaxing(None, None)
    path = old.save(tmp_path / "bw.npz")
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files if not k.startswith("relax_")}
    np.savez(path, **arrays)  # the layout files had before the relaxation
    back = load_model(path)
    q = random_independent(1.0, 1.0, PAPER_DT, 1)
    assert back.relax_tau.shape == (0,) and np.array_equal(back.simulate(q), old.simulate(q))
    new = relaxing([0.05], np.diag([1e5, 2e5, 300.0])[None])
    again = load_model(new.save(tmp_path / "relaxing.npz"))
    assert np.array_equal(again.simulate(q), new.simulate(q))


def test_a_bad_relaxation_array_is_refused_by_name():
    with pytest.raises(PlanarModelError, match="relax_gain"):
        relaxing([0.1], np.zeros((2, 3, 3)))
    with pytest.raises(PlanarModelError, match="relax_tau"):
        relaxing([0.0], np.zeros((1, 3, 3)))
