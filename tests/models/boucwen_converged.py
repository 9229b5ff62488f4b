"""How accurate the Bouc-Wen kernel is: test cases and the error against a converged run.

Used by tests/models/test_boucwen_kernels.py, the export tests (tests/export/fmu_masters.py),
the benchmark's accuracy figure (scripts/bench.py, scripts/bench_compare.py) and the studies
studies/2026-11-boucwen-integrator/boucwen_accuracy.py and
studies/2026-11-fmu-accuracy/fmu_accuracy.py, so all of them measure the same thing. The
reference is ``boucwen_fixed_step``: classical RK4 with a fixed number of equal sub-steps per
sample on eqs. 1-4 as printed.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bushenv import excitation as ex
from bushenv.models.base import PAPER_DT
from bushenv.models.boucwen import BoucWenBushing
from bushenv.models.boucwen.reference import boucwen_fixed_step
from bushenv.models.boucwen.tables import BW_ORDER, BW_RTOL, V_REF_M_PER_S, X_REF_M

REFERENCE_SUBSTEPS = 512  # converged to ~6e-7 of the peak on the cases below


def soft_block1_sharp_block2() -> np.ndarray:
    """Table 3 with block 1 slow and non-hysteretic: only block 2's corner sets the accuracy.

    An early kernel chose its sub-steps from a stability estimate at the start of each sample,
    where d = 0 before a step: one sub-step, z2 overshot its saturation fourfold and the force
    was 7 % of the peak off on a 4 mm step.
    """
    p = BoucWenBushing.preset().vector()
    p[BW_ORDER.index("c1")] *= 100.0
    p[BW_ORDER.index("a1")] = 0.0
    return p


def parameter_sets() -> dict[str, Callable[[], np.ndarray]]:
    """Name -> 16 SI parameters (BW_ORDER): the shipped sets, Table 3, the hard case above."""
    from bushenv.models import get_model

    return {
        "shipped axial": lambda: get_model("boucwen", axis="axial").vector(),
        "shipped radial": lambda: get_model("boucwen", axis="radial").vector(),
        "Table 3 (seed 002)": lambda: BoucWenBushing.preset().vector(),
        "soft block 1, sharp block 2": soft_block1_sharp_block2,
    }


INPUTS: dict[str, Callable[[], np.ndarray]] = {
    "random n = 1 (20 s)": lambda: ex.random_rpc(1.0, 20.0, PAPER_DT, seed=0),
    "random n = 1.5 (3 s)": lambda: ex.random_rpc(1.5, 3.0, PAPER_DT, seed=1),
    "4 mm step held 1.5 s": lambda: ex.step_hold(4e-3, 1.5, PAPER_DT),
    "80 Hz at 1.2 m/s (1 s)": lambda: ex.sine(80.0, 1.2 / (2 * np.pi * 80.0), 1.0, PAPER_DT),
    "out-of-band random (2 s)": lambda: ex.random_ood(2.0, PAPER_DT, seed=0),
    "1 mm zig-zag (600 samples)": lambda: np.tile([0.0, 1e-3, 0.0, -1e-3], 150),
}


def force_scale(p: np.ndarray) -> np.ndarray:
    """F_REF of parameter vectors (..., 16): the force scale the kernel's tolerance refers to."""
    p = np.asarray(p, dtype=np.float64)
    k = np.abs(p[..., 1]) + np.abs(p[..., 3]) + np.abs(p[..., 5])
    c = np.abs(p[..., 0]) + np.abs(p[..., 2]) + np.abs(p[..., 4])
    return np.maximum(k * X_REF_M, c * V_REF_M_PER_S)


def converged(
    p: np.ndarray, x: np.ndarray, v: np.ndarray, n_sub: int = REFERENCE_SUBSTEPS, dt=PAPER_DT
) -> np.ndarray:
    """Reference free run of p (16, B) on x, v (T, B): forces (T, B)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    out = np.empty_like(x)
    boucwen_fixed_step(
        x, np.ascontiguousarray(v), np.ascontiguousarray(p, dtype=np.float64), dt, n_sub, out
    )
    return out


def error_against_converged(
    p: np.ndarray, x: np.ndarray, rtol: float = BW_RTOL, dt: float = PAPER_DT
) -> tuple[float, float, float]:
    """One parameter set (16,) on one displacement record (T,).

    Returns (max error / peak force, max error / F_REF, trial steps per sample, both blocks,
    rejected ones included). The model is stepped one sample at a time so that every sample's
    trial steps are counted; the forces are the same bits as one call over the record.
    """
    X = np.asarray(x, dtype=np.float64)
    V = np.gradient(X, dt)
    ref = converged(np.asarray(p, dtype=np.float64)[:, None], X[:, None], V[:, None], dt=dt)
    model = BoucWenBushing.from_vector(p, dt=dt, rtol=rtol)
    model.reset(1)
    out = np.empty(len(X))
    steps = 0.0
    for t in range(len(X)):
        out[t] = model.step(X[t], V[t])
        steps += model.max_substeps_last_sample()[0]
    err = float(np.max(np.abs(out - ref[:, 0])))
    return err / float(np.max(np.abs(ref))), err / float(force_scale(p)), steps / len(X)
