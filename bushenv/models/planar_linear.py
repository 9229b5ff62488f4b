"""Linear planar bushing: full 3x3 stiffness and damping matrices.

    f = K q + C v,   q = (axial m, radial m, rotation rad),  f = (N, N, N m)

The constant-matrix element of the vehicle tools (Adams FIELD, Chrono's generic bushing) in
the plane; seed 000 eq. 1 per axis when K and C are diagonal. ``preset`` gives seed 000
Table 1 on the diagonal and the rotation of one of the reference's named parameter sets
(``reference/planar.py``: ``"cardanic"`` assumed, ``"torsion"`` from the bush's geometry).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.models.base import PAPER_DT
from bushenv.models.planar_base import PlanarModel, PlanarModelError, as_matrix
from bushenv.models.planar_kernels import planar_linear_kernel
from bushenv.reference.planar import ROTATION_K_NM_PER_RAD, ROTATIONS, torsion_per_axial


class PlanarLinear(PlanarModel):
    """Kelvin-Voigt in three coordinates; stateless, so batched and looped runs agree."""

    name = "linear"
    param_names = ("k_matrix", "c_matrix")

    def __init__(self, k_matrix: Any, c_matrix: Any, dt: float = PAPER_DT) -> None:
        self.k_matrix = as_matrix("linear: k_matrix", k_matrix)
        self.c_matrix = as_matrix("linear: c_matrix", c_matrix)
        super().__init__(dt)

    @classmethod
    def preset(cls, dt: float = PAPER_DT, rotation: str = "cardanic") -> PlanarLinear:
        """Seed 000 Table 1 on the diagonal (axial, radial); no coupling. The rotation
        (``rotation``, the reference's parameter sets): ``"cardanic"`` the reference's assumed
        3000 N m/rad with Table 1's radial loss time c/k (29.6 N m s/rad); ``"torsion"`` Table
        1's axial k and c through the bush's K_t / K_a (52.0 N m/rad, 0.60 N m s/rad)."""
        if rotation not in ROTATIONS:
            raise PlanarModelError(f"linear: rotation {rotation!r}; known: {list(ROTATIONS)}")
        k_a, c_a, k_r, c_r = 379.68e3, 4.4e3, 1518.73e3, 15.0e3
        if rotation == "cardanic":
            k_t, c_t = ROTATION_K_NM_PER_RAD, ROTATION_K_NM_PER_RAD * c_r / k_r
        else:
            k_t, c_t = k_a * torsion_per_axial(), c_a * torsion_per_axial()
        return cls(np.diag([k_a, k_r, k_t]), np.diag([c_a, c_r, c_t]), dt=dt)

    def _advance(self, q: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        # compiled: at one sample the two numpy products cost more than the arithmetic
        planar_linear_kernel(q, v, self.k_matrix, self.c_matrix, out)


def fit_linear(q: np.ndarray, v: np.ndarray, f: np.ndarray, dt: float = PAPER_DT) -> PlanarLinear:
    """Least-squares K, C from records: f ~ K q + C v over every sample.

    ``q``, ``v``, ``f`` of shape (T, 3) or (T, B, 3); one least-squares problem for the three
    force rows (each row of [K C] is the solution for its force).
    """
    q2 = np.asarray(q, dtype=np.float64).reshape(-1, 3)
    v2 = np.asarray(v, dtype=np.float64).reshape(-1, 3)
    f2 = np.asarray(f, dtype=np.float64).reshape(-1, 3)
    if not (q2.shape == v2.shape == f2.shape) or q2.shape[0] < 6:
        raise PlanarModelError(
            f"fit_linear: q, v, f must be equal (T, 3) arrays with T >= 6, got "
            f"{np.shape(q)}, {np.shape(v)}, {np.shape(f)}"
        )
    a = np.hstack([q2, v2])
    scale = np.maximum(np.abs(a).max(axis=0), 1e-300)  # mm and rad differ by orders
    coef, *_ = np.linalg.lstsq(a / scale, f2, rcond=None)
    coef = (coef / scale[:, None]).T  # (3, 6): force row i = [K_i, C_i]
    return PlanarLinear(coef[:, :3], coef[:, 3:], dt=dt)
