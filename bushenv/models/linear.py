"""Linear Kelvin-Voigt bushing: a spring and a dashpot in parallel.

    F = k x + c v                                        seed 000, eqs. 1-3

Presets are the papers' Table 1 (seed 000), converted from N/mm and N s/mm to SI:

| axis   | k [N/mm] | c [N s/mm] |
|--------|----------|------------|
| axial  | 379.68   | 4.4        |
| radial | 1518.73  | 15         |
"""

from __future__ import annotations

import numpy as np

from bushenv.models.base import PAPER_DT, BushingModel, ModelError
from bushenv.models.kernels import linear_kernel

TABLE1 = {  # seed 000 Table 1, SI
    "axial": {"k_n_per_m": 379.68e3, "c_ns_per_m": 4.4e3},
    "radial": {"k_n_per_m": 1518.73e3, "c_ns_per_m": 15.0e3},
}


class LinearBushing(BushingModel):
    """Kelvin-Voigt spring-damper; stateless, so its batched and looped runs trivially agree."""

    name = "linear"
    param_names = ("k_n_per_m", "c_ns_per_m")

    def __init__(self, k_n_per_m: float, c_ns_per_m: float, dt: float = PAPER_DT) -> None:
        self.k_n_per_m = float(k_n_per_m)
        self.c_ns_per_m = float(c_ns_per_m)
        if not (np.isfinite(self.k_n_per_m) and np.isfinite(self.c_ns_per_m)):
            raise ModelError(f"linear: k and c must be finite, got {k_n_per_m!r}, {c_ns_per_m!r}")
        super().__init__(dt)

    @classmethod
    def preset(cls, axis: str = "axial", dt: float = PAPER_DT) -> LinearBushing:
        if axis not in TABLE1:
            raise ModelError(f"linear: unknown axis {axis!r}; known: {sorted(TABLE1)}")
        return cls(dt=dt, **TABLE1[axis])

    def _advance(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        linear_kernel(x, v, self.k_n_per_m, self.c_ns_per_m, out)
