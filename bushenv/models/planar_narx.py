"""Planar NARX networks: one MIMO network, the seeds' three single-axis ones, and the hybrid.

    y_t = net(qs_t, qs_{t-1}, ..., qs_{t-5}, ys_{t-1}, ..., ys_{t-5})
    f_t = f_offset + f_scale y_t
    qs = (q - q_offset) / q_scale  (3,),   ys = scaled output (3,)
    net(z) = w_out tanh(w1 z + b1) + b_out    (one tanh hidden layer, linear output)

The input z stacks, lag by lag, all three coordinates' scaled displacements (lags 0..5) and
the network's own past scaled outputs (lags 1..5): 3 x 6 + 3 x 5 = 33 inputs, so the MIMO
network ("nn") sees every axis's history. "nn-axis" is seed 000 §4.2's kind in three axes: the
same arrays with a block mask, hidden units split in three groups, group a seeing only axis
a's lags and driving only output a (three independent 9-unit networks; the zeros are exact, so
an axis's force does not depend on the other axes at all). The hybrid ("hybrid") adds a 3x3
linear backbone, f = K q + C v + f_nn, the network fed with its own past residual outputs;
as in one axis, |f_nn,i| <= f_scale_i (sum_h |w_out[i, h]| + |b_out_i|) + |f_offset_i|.

State: the last 5 scaled displacements and the last 5 scaled outputs (30 rows), at rest the
scaled images of zero deflection and zero force.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.models.base import PAPER_DT
from bushenv.models.planar_base import PlanarModel, PlanarModelError, as_matrix
from bushenv.models.planar_kernels import planar_narx_kernel

N_PAST_Q = 5  # seed 000 §4.2
N_PAST_F = 5
N_IN = 3 * (N_PAST_Q + 1) + 3 * N_PAST_F
HIDDEN_PER_AXIS = 9  # seed 000 §4.2
# the ways training may tie the network's weights (``structure.py``); here, without torch, so
# that the command line lists them without importing it
STRUCTURES = ("free", "mirror", "rate", "mirror-rate")


def input_axes() -> np.ndarray:
    """(N_IN,) the coordinate (0, 1, 2) each network input belongs to."""
    return np.array([i for _ in range(N_PAST_Q + 1 + N_PAST_F) for i in range(3)])


def axis_masks(hidden: int) -> tuple[np.ndarray, np.ndarray]:
    """Block masks (hidden, N_IN), (3, hidden) of the per-axis kind: unit h in group h * 3 //
    hidden sees and drives its own axis only."""
    group = np.arange(hidden) * 3 // hidden
    return (group[:, None] == input_axes()[None, :]).astype(float), (
        np.arange(3)[:, None] == group[None, :]
    ).astype(float)


class PlanarNarx(PlanarModel):
    """MIMO NARX bushing, free-running on its own past outputs."""

    name = "nn"
    param_names = (
        "q_offset",
        "q_scale",
        "f_offset",
        "f_scale",
        "w1",
        "b1",
        "w_out",
        "b_out",
    )

    def __init__(
        self,
        q_offset: Any,
        q_scale: Any,
        f_offset: Any,
        f_scale: Any,
        w1: Any,
        b1: Any,
        w_out: Any,
        b_out: Any,
        dt: float = PAPER_DT,
    ) -> None:
        w1 = np.asarray(w1, dtype=np.float64)
        hidden = w1.shape[0] if w1.ndim == 2 else -1
        if hidden < 1:
            raise PlanarModelError(f"{self.name}: w1 must be (hidden, {N_IN}), got {w1.shape}")
        for key, value, shape in (
            ("q_offset", q_offset, (3,)),
            ("q_scale", q_scale, (3,)),
            ("f_offset", f_offset, (3,)),
            ("f_scale", f_scale, (3,)),
            ("w1", w1, (hidden, N_IN)),
            ("b1", b1, (hidden,)),
            ("w_out", w_out, (3, hidden)),
            ("b_out", b_out, (3,)),
        ):
            setattr(self, key, as_matrix(f"{self.name}: {key}", value, shape))
        if np.any(self.q_scale <= 0) or np.any(self.f_scale <= 0):
            raise PlanarModelError(f"{self.name}: q_scale and f_scale must be > 0")
        self._check_structure()
        super().__init__(dt)

    @classmethod
    def untrained(cls, seed: int = 0, hidden: int = 3 * HIDDEN_PER_AXIS, dt: float = PAPER_DT):
        """A network with random weights (normal, std 0.3) scaled to the n = 1 amplitudes and
        forces of Table 1: for tests and checks, deterministic given ``seed``."""
        rng = np.random.default_rng(seed)
        m1, mo = axis_masks(hidden) if cls.name == "nn-axis" else (1.0, 1.0)
        extra = {}
        if cls.name == "hybrid":
            extra = {
                "k_matrix": np.diag([379.68e3, 1518.73e3, 3.0e3]),
                "c_matrix": np.zeros((3, 3)),
            }
        return cls(
            q_offset=np.zeros(3),
            q_scale=np.array([2e-3, 2e-3, 0.05]),
            f_offset=np.zeros(3),
            f_scale=np.array([760.0, 3040.0, 150.0]),
            w1=rng.normal(0, 0.3, (hidden, N_IN)) * m1,
            b1=rng.normal(0, 0.1, hidden),
            w_out=rng.normal(0, 0.3, (3, hidden)) * mo,
            b_out=rng.normal(0, 0.1, 3),
            dt=dt,
            **extra,
        )

    def _check_structure(self) -> None:
        """The MIMO network takes any weights."""

    @property
    def n_state(self) -> int:
        return 3 * (N_PAST_Q + N_PAST_F)

    def initial_state(self, batch_size: int) -> np.ndarray:
        rest = np.concatenate(
            [np.tile(-self.q_offset / self.q_scale, N_PAST_Q), np.tile(self._rest_y(), N_PAST_F)]
        )
        return np.repeat(rest[:, None], batch_size, axis=1)

    def _rest_y(self) -> np.ndarray:
        return -self.f_offset / self.f_scale

    def nn_bound(self) -> np.ndarray:
        """(3,) the largest |network force| any input can give, N and N m."""
        return self.f_scale * (np.abs(self.w_out).sum(axis=1) + np.abs(self.b_out)) + np.abs(
            self.f_offset
        )

    def _advance(self, q: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        k, c = self._backbone_matrices()
        planar_narx_kernel(
            q, v, self.state, self.q_offset, self.q_scale, self.f_offset, self.f_scale,
            self.w1, self.b1, self.w_out, self.b_out, k, c, out,
        )  # fmt: skip

    def _backbone_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """(K, C) of the linear backbone; the pure network has none."""
        return _NO_BACKBONE, _NO_BACKBONE


_NO_BACKBONE = np.zeros((3, 3))


class PlanarNarxPerAxis(PlanarNarx):
    """Seed 000 §4.2 in three axes: three single-axis networks (a block-masked PlanarNarx)."""

    name = "nn-axis"

    def _check_structure(self) -> None:
        m1, mo = axis_masks(self.w1.shape[0])
        if np.any(self.w1[m1 == 0] != 0) or np.any(self.w_out[mo == 0] != 0):
            raise PlanarModelError(
                "nn-axis: weights across axes must be zero (hidden unit h belongs to axis "
                "h * 3 // hidden); use the MIMO 'nn' for coupled weights"
            )


class PlanarHybrid(PlanarNarx):
    """3x3 linear backbone + MIMO network on its own past residual outputs."""

    name = "hybrid"
    param_names = ("k_matrix", "c_matrix", *PlanarNarx.param_names)

    def __init__(self, k_matrix: Any, c_matrix: Any, **network: Any) -> None:  # noqa: D107
        self.k_matrix = as_matrix("hybrid: k_matrix", k_matrix)
        self.c_matrix = as_matrix("hybrid: c_matrix", c_matrix)
        super().__init__(**network)

    def _backbone_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        return self.k_matrix, self.c_matrix

    def backbone_alone(self) -> PlanarModel:
        from bushenv.models.planar_linear import PlanarLinear

        return PlanarLinear(self.k_matrix, self.c_matrix, dt=self.dt)


# the network kinds ``train.fit_mimo`` trains, by file name; here, without torch
KINDS = {"nn": PlanarNarx, "nn-axis": PlanarNarxPerAxis, "hybrid": PlanarHybrid}
