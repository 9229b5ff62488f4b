"""Vectorised Bouc-Wen kernel against the original scalar one; lanes independent of tiles."""

import time

import numpy as np
import pytest

from bushenv.excitation import random_rpc
from bushenv.models import PAPER_DT, get_model
from bushenv.models.boucwen import BoucWenBushing
from bushenv.models.boucwen_kernels import (
    BW_MAX_SUBSTEPS,
    BW_N_STATE,
    BW_TILE,
    boucwen_kernel,
    boucwen_kernel_reference,
)

DT = PAPER_DT


def run(kernel, p, x, v, max_substeps=BW_MAX_SUBSTEPS):
    """p (16, B), x and v (T, B): forces, final state, n_bad."""
    x = np.ascontiguousarray(x)
    v = np.ascontiguousarray(v)
    p = np.ascontiguousarray(p)
    state = np.zeros((BW_N_STATE, x.shape[1]))
    out = np.empty_like(x)
    n_bad = kernel(x, v, state, p, DT, max_substeps, out)
    return out, state, n_bad


def profiles(n_index, B, duration_s=10.0):
    x = np.stack([random_rpc(n_index, duration_s, DT, seed=s) for s in range(B)], axis=1)
    return x, np.gradient(x, DT, axis=0)


@pytest.mark.parametrize("axis", ["axial", "radial"])
@pytest.mark.parametrize("n_index", [1.0, 1.5])
def test_vectorised_kernel_matches_the_reference_on_the_shipped_parameters(axis, n_index):
    m = get_model("boucwen", axis=axis)
    x, v = profiles(n_index, BW_TILE + 3)  # one full tile and a partial one
    p = np.repeat(m.vector()[:, None], x.shape[1], axis=1)
    ref, ref_state, ref_bad = run(boucwen_kernel_reference, p, x, v)
    new, new_state, new_bad = run(boucwen_kernel, p, x, v)
    assert ref_bad == new_bad == 0
    # same algorithm, pow rounded differently (~1e-14): measured below 1e-15 of the peak
    assert np.max(np.abs(new - ref)) < 1e-12 * np.max(np.abs(ref))
    assert np.allclose(new_state[:6], ref_state[:6], rtol=1e-9, atol=1e-15)


def test_identification_candidates_match_the_reference_and_fail_in_the_same_columns():
    from bushenv.identify.global_search import SEARCH_BOUNDS, search_to_parameters

    rng = np.random.default_rng(7)
    lo, hi = np.array(SEARCH_BOUNDS).T
    u = lo + (hi - lo) * rng.random((3 * BW_TILE + 5, len(lo)))
    p = search_to_parameters(u, 3.0e5, 2.0e3).T
    x1 = random_rpc(1.0, 2.0, DT, seed=11)
    x = np.repeat(x1[:, None], p.shape[1], axis=1)
    v = np.gradient(x, DT, axis=0)
    ref, _, ref_bad = run(boucwen_kernel_reference, p, x, v, max_substeps=400)
    new, _, new_bad = run(boucwen_kernel, p, x, v, max_substeps=400)
    bad_ref = ~np.all(np.isfinite(ref), axis=0)
    bad_new = ~np.all(np.isfinite(new), axis=0)
    assert np.array_equal(bad_ref, bad_new)
    assert ref_bad == new_bad
    assert 0 < bad_ref.sum() < len(bad_ref)  # the draw has both kinds
    good = ~bad_ref
    scale = np.max(np.abs(ref[:, good]), axis=0)
    assert np.all(np.max(np.abs(new[:, good] - ref[:, good]), axis=0) <= 1e-9 * scale)


def test_each_column_gives_the_same_bits_alone_in_a_full_tile_and_in_a_partial_tile():
    m = get_model("boucwen", axis="radial")
    B = 2 * BW_TILE + 5
    x, v = profiles(1.5, B, duration_s=2.0)
    p = np.repeat(m.vector()[:, None], B, axis=1)
    p[14] *= np.linspace(0.5, 1.5, B)  # different parameters per column, too
    batched, state, _ = run(boucwen_kernel, p, x, v)
    for b in (0, BW_TILE - 1, BW_TILE + 3, B - 1):
        alone, alone_state, _ = run(
            boucwen_kernel, p[:, b : b + 1], x[:, b : b + 1], v[:, b : b + 1]
        )
        assert np.array_equal(alone[:, 0], batched[:, b])
        assert np.array_equal(alone_state[:, 0], state[:, b])
    shifted, _, _ = run(boucwen_kernel, p[:, 3:], x[:, 3:], v[:, 3:])  # other tile boundaries
    assert np.array_equal(shifted, batched[:, 3:])


def test_looped_step_equals_simulate_bit_for_bit_on_a_batch():
    m = get_model("boucwen", axis="axial")
    B = BW_TILE + 1
    x, v = profiles(1.0, B, duration_s=1.0)
    f = m.simulate(x, v)
    m.reset(B)
    looped = np.stack([m.step(x[t], v[t]) for t in range(x.shape[0])])
    assert np.array_equal(looped, f)


@pytest.mark.parametrize("B", [1, BW_TILE])
def test_unintegrable_and_nan_columns_are_counted_and_nan_without_hanging(B):
    good = BoucWenBushing.preset().vector()
    p = np.repeat(good[:, None], B, axis=1)
    p[2, 0] = 1e-30  # c1 ~ 0: the rate explodes
    if B > 1:
        p[12, 1] = np.nan  # a NaN exponent
    x, v = profiles(1.0, B, duration_s=0.5)
    t0 = time.perf_counter()
    out, _, n_bad = run(boucwen_kernel, p, x, v)
    assert time.perf_counter() - t0 < 5.0
    assert np.all(np.isnan(out[:, 0]))
    if B > 1:
        assert np.all(np.isnan(out[:, 1]))
        assert np.all(np.isfinite(out[:, 2:]))
    # every sample of each bad column counts (the reference counted two fewer for c1 = 1e-30:
    # its int ceil() of the ~1e33 sub-step count overflowed to a negative, i.e. one sub-step)
    assert n_bad == x.shape[0] * (1 if B == 1 else 2)


def test_substep_limit_fails_the_same_columns_as_the_reference():
    m = get_model("boucwen", axis="radial")
    B = BW_TILE
    x, v = profiles(1.5, B, duration_s=2.0)
    p = np.repeat(m.vector()[:, None], B, axis=1)
    ref, _, ref_bad = run(boucwen_kernel_reference, p, x, v, max_substeps=20)
    new, _, new_bad = run(boucwen_kernel, p, x, v, max_substeps=20)
    assert ref_bad == new_bad > 0
    assert np.array_equal(np.isnan(ref), np.isnan(new))
