"""Hybrid bushing: a linear backbone plus a NARX network for everything the line misses.

    F   = k x + c v + F_nn                                   seed 000 §3, Fig. 3
    F_nn = f_offset + f_scale * net(xs_t, xs_{t-1..t-5}, rs_{t-1..t-5})

The backbone (k, c) is identified first by least squares (seed 000 §4.1); the network, of the
same NARX shape as ``narx.NarxBushing``, is fed with the displacement history and its OWN past
residual outputs rs (scaled F_nn), never with the total force.

Why it cannot run away (``nn_bound``): every hidden unit is a tanh, so lies in [-1, 1] whatever
its input; the output is linear in those units, hence for ANY excitation and any history

    |F_nn| <= f_scale * (sum |w_out| + |b_out|) + |f_offset|   = nn_bound().

So the hybrid force always stays within the linear backbone k x + c v plus or minus that bound.
A held displacement cannot make it grow without limit: the backbone is fixed by the held input,
and the network part, however it wanders or oscillates, stays inside the band. (The same bound
holds for the pure network's whole force, but there nothing ties the band to the motion.)

| parameter  | unit   | meaning                                          |
|------------|--------|--------------------------------------------------|
| k_n_per_m  | N/m    | backbone stiffness                               |
| c_ns_per_m | N s/m  | backbone damping                                 |
| the rest   |        | the network, as in narx.py (f_* scale F_nn)      |
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.models.base import PAPER_DT, ModelError
from bushenv.models.narx import N_PAST_F, N_PAST_X, NarxBushing


class HybridBushing(NarxBushing):
    """seed 000 §3 hybrid: Kelvin-Voigt backbone + bounded NARX residual network."""

    name = "hybrid"
    param_names = ("k_n_per_m", "c_ns_per_m") + NarxBushing.param_names

    def __init__(
        self,
        k_n_per_m: float,
        c_ns_per_m: float,
        x_offset_m: float,
        x_scale_m: float,
        f_offset_n: float,
        f_scale_n: float,
        w1: np.ndarray,
        b1: np.ndarray,
        w2: np.ndarray,
        b2: np.ndarray,
        w_out: np.ndarray,
        b_out: float,
        n_past_x: int = N_PAST_X,
        n_past_f: int = N_PAST_F,
        dt: float = PAPER_DT,
    ) -> None:
        self.k_n_per_m = float(np.asarray(k_n_per_m, dtype=np.float64))
        self.c_ns_per_m = float(np.asarray(c_ns_per_m, dtype=np.float64))
        if not (np.isfinite(self.k_n_per_m) and np.isfinite(self.c_ns_per_m)):
            raise ModelError(f"hybrid: k and c must be finite, got {k_n_per_m!r}, {c_ns_per_m!r}")
        super().__init__(
            x_offset_m=x_offset_m,
            x_scale_m=x_scale_m,
            f_offset_n=f_offset_n,
            f_scale_n=f_scale_n,
            w1=w1,
            b1=b1,
            w2=w2,
            b2=b2,
            w_out=w_out,
            b_out=b_out,
            n_past_x=n_past_x,
            n_past_f=n_past_f,
            dt=dt,
        )

    def _backbone(self) -> tuple[float, float]:
        return self.k_n_per_m, self.c_ns_per_m

    def backbone_force(self, x: Any, v: Any) -> Any:
        """k x + c v, N (the linear part alone)."""
        return self.k_n_per_m * np.asarray(x) + self.c_ns_per_m * np.asarray(v)

    def __repr__(self) -> str:
        return (
            f"HybridBushing(k={self.k_n_per_m:.6g} N/m, c={self.c_ns_per_m:.6g} N s/m, "
            f"hidden={self.hidden}, dt={self.dt:.6g})"
        )
