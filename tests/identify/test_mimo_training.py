"""The MIMO networks (three axes): per-axis independence, step = simulate, files, hybrid
bound, training."""

import numpy as np
import pytest

from bushenv.excitation import random_rpc
from bushenv.identify.mimo_options import MimoOptions as TrainOptions
from bushenv.identify.mimo_train import fit_mimo
from bushenv.metrics import rms_ratio
from bushenv.models import load_model
from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_narx import N_IN, PlanarHybrid, PlanarNarx, PlanarNarxPerAxis, axis_masks
from bushenv.reference.planar import THETA_N1_RAD, PlanarRubber

DT = 1 / 204.8
PEAKS = np.array([2e-3, 2e-3, THETA_N1_RAD])


def _arrays(hidden=27, seed=0, per_axis=False):
    rng = np.random.default_rng(seed)
    w1 = rng.normal(0, 0.3, (hidden, N_IN))
    w_out = rng.normal(0, 0.3, (3, hidden))
    if per_axis:
        m1, mo = axis_masks(hidden)
        w1, w_out = w1 * m1, w_out * mo
    return dict(
        q_offset=np.zeros(3),
        q_scale=PEAKS,
        f_offset=np.array([1.0, -2.0, 0.5]),
        f_scale=np.array([500.0, 2000.0, 150.0]),
        w1=w1,
        b1=rng.normal(0, 0.1, hidden),
        w_out=w_out,
        b_out=rng.normal(0, 0.1, 3),
    )


def _drive(T=300, B=None, seed=0):
    q = np.stack(
        [random_rpc(1.0, T * DT, DT, seed + i, peak_m_at_n1=PEAKS[i]) for i in range(3)], 1
    )
    return q if B is None else np.stack([np.roll(q, 7 * b, axis=0) for b in range(B)], axis=1)


def test_per_axis_output_ignores_the_other_axes_and_mimo_does_not():
    q = _drive()
    other = q.copy()
    other[:, 1:] *= -0.5
    per_axis = PlanarNarxPerAxis(**_arrays(per_axis=True))
    mimo = PlanarNarx(**_arrays())
    np.testing.assert_array_equal(per_axis.simulate(q)[:, 0], per_axis.simulate(other)[:, 0])
    assert np.abs(mimo.simulate(q)[:, 0] - mimo.simulate(other)[:, 0]).max() > 1.0


def test_per_axis_refuses_weights_across_axes():
    with pytest.raises(PlanarModelError, match="across axes"):
        PlanarNarxPerAxis(**_arrays())


@pytest.mark.parametrize("cls", [PlanarNarx, PlanarHybrid])
def test_step_loop_equals_batched_simulate(cls):
    extra = (
        {"k_matrix": np.diag([2e5, 7e5, 3e3]), "c_matrix": np.eye(3)} if cls is PlanarHybrid else {}
    )
    m = cls(**_arrays(), **extra)
    q = _drive(80, B=3)
    v = np.gradient(q, DT, axis=0)
    f = m.simulate(q, v)
    m.reset(3)
    np.testing.assert_array_equal(np.stack([m.step(q[t], v[t]) for t in range(80)]), f)


def test_hybrid_stays_within_its_bound_under_wild_input():
    k = np.diag([2e5, 7e5, 3e3])
    m = PlanarHybrid(k_matrix=k, c_matrix=np.zeros((3, 3)), **_arrays(seed=4))
    q = np.random.default_rng(2).uniform(-1, 1, (500, 3)) * np.array([12.5e-3, 12.5e-3, 0.15])
    resid = m.simulate(q, np.zeros_like(q)) - q @ k.T
    assert np.all(np.abs(resid) <= m.nn_bound() + 1e-9)


@pytest.mark.parametrize("cls", [PlanarNarx, PlanarNarxPerAxis, PlanarHybrid])
def test_save_load_roundtrip(tmp_path, cls):
    extra = {"k_matrix": np.eye(3), "c_matrix": np.eye(3)} if cls is PlanarHybrid else {}
    m = cls(**_arrays(per_axis=cls is PlanarNarxPerAxis), **extra)
    back = load_model(m.save(tmp_path / "m.npz"))
    assert type(back) is cls
    q = _drive(50)
    np.testing.assert_array_equal(back.simulate(q), m.simulate(q))


def _record(T=2048, seed=0):
    q = _drive(T, seed=seed)
    return q, PlanarRubber.preset(measurement=False).simulate(q)


def test_tiny_training_learns_the_record_and_is_deterministic():
    q, f = _record()
    opt = TrainOptions(
        hidden=9, teacher_steps=150, free_run_steps=4, windows=8, window=32, eval_every=2
    )
    a = fit_mimo(q, f, DT, kind="nn", options=opt, seed=1)
    b = fit_mimo(q, f, DT, kind="nn", options=opt, seed=1)
    np.testing.assert_array_equal(a.w1, b.w1)
    pred = a.simulate(q)
    assert max(rms_ratio(f[:, i], pred[:, i]) for i in range(3)) < 0.5


def test_training_rejects_short_or_misshapen_records():
    with pytest.raises(PlanarModelError, match="100 samples in 1 record"):
        fit_mimo(np.zeros((100, 3)), np.zeros((100, 3)), DT)
    with pytest.raises(PlanarModelError, match=r"\(T, 3\)"):
        fit_mimo(np.zeros((4000, 2)), np.zeros((4000, 2)), DT)
    with pytest.raises(PlanarModelError, match="record 2: 30 samples cannot be split"):
        records = [np.zeros((4000, 3)), np.zeros((30, 3))]
        fit_mimo(records, records, DT)
    with pytest.raises(PlanarModelError, match="two lists of equal length"):
        fit_mimo([np.zeros((4000, 3))] * 2, [np.zeros((4000, 3))], DT)


def test_a_list_of_one_record_is_the_record_and_two_records_keep_their_own_tails():
    q, f = _record()
    opt = TrainOptions(hidden=9, teacher_steps=40, free_run_steps=4, windows=8, window=32,
                       eval_every=2)  # fmt: skip
    one = fit_mimo(q, f, DT, kind="nn", options=opt, seed=1)
    listed = fit_mimo([q], [f], DT, kind="nn", options=opt, seed=1)
    np.testing.assert_array_equal(one.w1, listed.w1)


def test_each_record_keeps_its_own_tail_out_of_training():
    q, f = _record()
    opt = TrainOptions(hidden=9, teacher_steps=40, free_run_steps=0, windows=8, window=32,
                       eval_every=2)  # fmt: skip
    half = len(q) // 2
    qs, fs = [q[:half], q[half:]], [f[:half], f[half:]]
    n = int(0.2 * half)

    def fit_with(k, rows):  # record k's force reversed in time over ``rows``: same range
        g = [a.copy() for a in fs]
        g[k][rows] = fs[k][rows][::-1]
        return fit_mimo(qs, g, DT, "nn", opt, seed=1).w1

    plain = fit_mimo(qs, fs, DT, "nn", opt, seed=1).w1
    # the first record's tail only validates (joined end to end it would have trained) ...
    np.testing.assert_array_equal(fit_with(0, slice(half - n, half)), plain)
    # ... and the second record's head trains (joined, the tail was all of it that counted)
    assert not np.array_equal(fit_with(1, slice(0, n)), plain)


def test_free_run_windows_never_reach_across_two_records():
    from bushenv.identify.mimo_train import _window_starts

    starts = _window_starts([100, 40, 70], 32)
    ends = np.array([100, 140, 210])
    assert len(starts) == (100 - 32) + (40 - 32) + (70 - 32)
    for s in starts:
        record = np.searchsorted(ends, s, side="right")  # the record the window starts in
        assert s + 32 <= ends[record]  # its last row is inside the same record
    assert len(_window_starts([20, 100], 32)) == 100 - 32  # too short for a window: none
    with pytest.raises(PlanarModelError, match="known"):
        fit_mimo(np.zeros((4000, 3)), np.zeros((4000, 3)), DT, kind="lstm")


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["nn", "nn-axis", "hybrid"])
def test_default_training_reaches_15_percent_on_unseen_record(kind):
    q, f = _record(T=8192, seed=10)
    m = fit_mimo(q, f, DT, kind=kind, seed=0)
    qt, ft = _record(T=2048, seed=40)
    pred = m.simulate(qt)
    assert max(rms_ratio(ft[:, i], pred[:, i]) for i in range(3)) < 0.15
