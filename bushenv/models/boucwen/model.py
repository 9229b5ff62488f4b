"""Bouc-Wen bushing: two hysteretic variables on a modified Spencer-type element.

seed 002 §3, eqs. 1-5:

    z1' = (x' - y') [A1 - {gamma1 + beta1 sgn(x' - y') sgn(z1)} |z1|^n1]      (1)
    z2' = (x' - w') [A2 - {gamma2 + beta2 sgn(x' - w') sgn(z2)} |z2|^n2]      (2)
    y'  = {c1 x' + k1 (x - y) - k0 y + a1 z1} / c1                             (3)
    w'  = {c2 x' + k2 (x - w) + a2 z2} / (c0 + c2)                             (4)
    F   = k0 y + c0 w'                                                          (5)

16 parameters (c0, k0, c1, k1, c2, k2, A1, A2, beta1, beta2, gamma1, gamma2, n1, n2, a1, a2),
all stored in SI (N, m, s). Eq. 3 divides by c1 and eq. 4 by c0 + c2: both must be nonzero,
which the constructor checks.

Units of seed 002 Table 3 (the preset, identified on the RADIAL direction only): read as
N, mm, s -- k in N/mm, c in N s/mm, a in N/mm (a z is a force, z in mm), A and n
dimensionless. That reading puts k0 = 2187 N/mm next to Table 1 (seed 000) radial stiffness
1519 N/mm; in N/m every stiffness would be a thousand times too soft. To SI with s = 1000 mm/m:
k, c, a times s; beta, gamma times s^n (because |z_mm|^n = s^n |z_m|^n); A, n unchanged. Time
constants (k / c) do not change. NOTE: Table 3 has beta1 + gamma1 = -9.12 < 0, against the
paper's own constraint (eq. 6, beta1 + gamma1 > 0): z1 then hardens instead of saturating.
We keep the printed values (see ``tests/models/test_boucwen.py`` for the size of the forces
they give on a 2 mm record).

Integration (``boucwen_kernels.boucwen_kernel``; docs/boucwen-integration.md): z is advanced
along the relative travel by an exact map tabulated once per parameter set
(``boucwen_tables``), which leaves one stiff scalar ODE per block (eqs. 3 and 4), integrated by
error-controlled exponential collocation with x and x' linear within each sample; reversals of
the relative velocity are located on the step's dense output. ``rtol`` (default ``BW_RTOL``)
bounds each step's error in the force relative to F_REF = max(sum |k| x 1 mm, sum |c| x 10
mm/s); at the default the free run agrees with a converged fixed-step RK4 to 2e-3 of the peak
on random, step, 80 Hz, out-of-band and zig-zag inputs for the shipped sets and the Table 3
preset (``tests/models/test_boucwen_kernels.py``). Nothing is clamped: a parameter set outside
what the map covers (A <= 0, n <= 0, an unloading branch that runs away, a block that relaxes
faster than 1e-8 of a sample) is refused when the model is built; a history whose hardening z
runs away (its force beyond 1e3 F_REF), that needs more than ``BW_MAX_SUBSTEPS`` trial steps in
one sample, or whose state is no longer finite gives NaN and ``simulate`` raises.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.errors import ModelRefused
from bushenv.models.base import PAPER_DT, BushingModel, ModelError
from bushenv.models.boucwen.kernels import BW_MAX_SUBSTEPS, BW_N_STATE, boucwen_kernel
from bushenv.models.boucwen.tables import BW_ORDER, BW_RTOL, prepare

MM_PER_M = 1000.0

# seed 002 Table 3, as printed (N, mm, s)
TABLE3_N_MM = {
    "c0": 299.401,
    "k0": 2186.63,
    "c1": 0.805,
    "k1": 1453.895,
    "c2": 1.825,
    "k2": 0.526,
    "A1": 2436.323,
    "A2": 79.536,
    "beta1": 1.875,
    "beta2": 5.023,
    "gamma1": -10.991,
    "gamma2": -1.758,
    "n1": 0.7795,
    "n2": 0.969,
    "a1": 0.6125,
    "a2": 5.983,
}


def n_mm_to_si(p: dict[str, float]) -> dict[str, float]:
    """Convert a parameter set read in N, mm, s to SI (see the module docstring)."""
    s = MM_PER_M
    out = dict(p)
    for key in ("c0", "k0", "c1", "k1", "c2", "k2", "a1", "a2"):
        out[key] = p[key] * s
    out["beta1"] = p["beta1"] * s ** p["n1"]
    out["gamma1"] = p["gamma1"] * s ** p["n1"]
    out["beta2"] = p["beta2"] * s ** p["n2"]
    out["gamma2"] = p["gamma2"] * s ** p["n2"]
    return out


class BoucWenError(ModelError):
    """These Bouc-Wen parameters cannot be integrated (a refused set: bad input)."""


class BoucWenRunaway(BoucWenError, ModelRefused):
    """The integration refused to go on (step limit, or the solution ran away): a divergence."""


class BoucWenBushing(BushingModel):
    """seed 002 eqs. 1-5, 16 parameters in SI; z along the travel, exponential collocation.

    ``rtol``: error tolerance on the force (see the module docstring); saved with the model.
    """

    name = "boucwen"
    param_names = BW_ORDER
    # every state row is its history's own (the rigs' probe could take the direction of travel
    # or the carried step size, equal by chance in two histories, for a shared row)
    shared_state_rows: tuple[int, ...] = ()

    def __init__(self, dt: float = PAPER_DT, rtol: float = BW_RTOL, **params: float) -> None:
        try:
            rtol = float(rtol)
        except (TypeError, ValueError):
            raise ModelError(f"boucwen: rtol must be a number, got {rtol!r}") from None
        if not (0.0 < rtol < 1.0):
            raise ModelError(f"boucwen: rtol must lie in (0, 1), got {rtol!r}")
        self.rtol = rtol
        missing = [k for k in BW_ORDER if k not in params]
        unknown = [k for k in params if k not in BW_ORDER]
        if missing or unknown:
            raise ModelError(f"boucwen: missing parameters {missing}, unknown {unknown}")
        for key in BW_ORDER:
            a = np.asarray(params[key], dtype=np.float64)
            if a.shape != ():
                raise ModelError(f"boucwen: parameter {key!r} must be a scalar, got {a.shape}")
            if not np.isfinite(a):
                raise ModelError(f"boucwen: parameter {key!r} is {float(a)}")
            setattr(self, key, float(a))
        if self.c1 == 0.0:
            raise ModelError("boucwen: c1 = 0 (eq. 3 divides by c1)")
        if self.c0 + self.c2 == 0.0:
            raise ModelError("boucwen: c0 + c2 = 0 (eq. 4 divides by c0 + c2)")
        self._p = np.array([[getattr(self, k)] for k in BW_ORDER])
        self._tabs, self._bc, why = prepare(self._p.T, float(dt), rtol)
        if why[0]:
            raise BoucWenError(f"boucwen: cannot integrate these parameters: {why[0]}")
        self._tab_index = np.array([[0], [1]], dtype=np.int64)
        super().__init__(dt)

    @classmethod
    def from_vector(
        cls, vector: np.ndarray, dt: float = PAPER_DT, rtol: float = BW_RTOL
    ) -> BoucWenBushing:
        """Build from 16 SI values in BW_ORDER."""
        vector = np.asarray(vector, dtype=np.float64)
        if vector.shape != (len(BW_ORDER),):
            raise ModelError(f"boucwen: need {len(BW_ORDER)} values, got shape {vector.shape}")
        return cls(dt=dt, rtol=rtol, **dict(zip(BW_ORDER, vector.tolist(), strict=True)))

    def vector(self) -> np.ndarray:
        return self._p[:, 0].copy()

    @classmethod
    def preset(cls, axis: str = "radial", dt: float = PAPER_DT) -> BoucWenBushing:
        """seed 002 Table 3 (radial), read in N, mm, s and converted to SI."""
        if axis != "radial":
            raise ModelError(
                f"boucwen: seed 002 identified the radial direction only; no Table 3 preset for "
                f"axis {axis!r} (use get_model('boucwen', axis=...) for the identified default)"
            )
        return cls(dt=dt, **n_mm_to_si(TABLE3_N_MM))

    @property
    def n_state(self) -> int:
        return BW_N_STATE

    def reset(self, batch_size: int = 1) -> None:
        super().reset(batch_size)
        if self._tab_index.shape[1] != self.batch_size:
            self._tab_index = np.repeat(np.array([[0], [1]], dtype=np.int64), self.batch_size, 1)

    def _advance(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        n_bad = boucwen_kernel(
            x, v, self.state, self._tabs, self._bc, self._tab_index, self.dt, BW_MAX_SUBSTEPS, out
        )
        if n_bad:
            raise BoucWenRunaway(
                f"boucwen: {n_bad} of {x.shape[1]} histories could not be integrated: more "
                f"than {BW_MAX_SUBSTEPS} trial steps in one sample, or the solution ran away "
                f"(z beyond its table, or not finite); parameters {self.params}"
            )

    def max_substeps_last_sample(self) -> np.ndarray:
        """Trial steps (both blocks, rejected ones included) in the last sample (diagnostic)."""
        return self.state[6].copy()

    def extra_meta(self) -> dict[str, Any]:
        return {"rtol": self.rtol}

    @classmethod
    def from_params(
        cls, params: dict[str, np.ndarray], dt: float, extra: dict[str, Any]
    ) -> BoucWenBushing:
        rtol = extra.get("rtol", BW_RTOL)
        return cls(dt=dt, rtol=rtol, **{k: float(params[k]) for k in BW_ORDER})

    def __repr__(self) -> str:
        return "BoucWenBushing(" + ", ".join(f"{k}={getattr(self, k):.4g}" for k in BW_ORDER) + ")"


def simulate_population(
    vectors: np.ndarray,
    x: np.ndarray,
    v: np.ndarray,
    dt: float = PAPER_DT,
    max_substeps: int = BW_MAX_SUBSTEPS,
    rtol: float = BW_RTOL,
) -> tuple[np.ndarray, np.ndarray]:
    """Free-run P parameter sets (P, 16) on one record (T,) at once: forces (T, P), bad (P,).

    Columns whose set is refused (outside what the kernel covers) or whose integration failed
    (more than ``max_substeps`` trial steps in a sample, or a runaway) hold NaN and are flagged
    in ``bad``; no error is raised: the identification treats them as infeasible.
    """
    vectors = np.atleast_2d(np.asarray(vectors, dtype=np.float64))
    P = vectors.shape[0]
    tabs, bc, _ = prepare(vectors, float(dt), float(rtol))
    index = np.ascontiguousarray(np.stack([2 * np.arange(P), 2 * np.arange(P) + 1]))
    xx = np.ascontiguousarray(np.repeat(np.asarray(x, dtype=np.float64)[:, None], P, axis=1))
    vv = np.ascontiguousarray(np.repeat(np.asarray(v, dtype=np.float64)[:, None], P, axis=1))
    state = np.zeros((BW_N_STATE, P))
    out = np.empty_like(xx)
    boucwen_kernel(xx, vv, state, tabs, bc, index, float(dt), int(max_substeps), out)
    bad = ~np.all(np.isfinite(out), axis=0)
    return out, bad
