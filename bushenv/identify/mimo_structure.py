"""Structured MIMO networks: the MIMO NARX network with weights tied so that its holds are
right by construction, not by a loss term.

Every structure is still the seeds' NARX network (``bushenv.models.planar_narx``: 33 inputs,
displacement lags 0..5 and own-output lags 1..5, one tanh hidden layer, linear output; the
hybrid adds its linear backbone), so a trained one is a plain ``PlanarNarx``/``PlanarHybrid``
array set: the kernel, the files, ``fixed_points`` and the hold check
(``mimo_certified.check``) see no difference. Only
the training parametrises the arrays (``structured_net``):

- ``mirror``: the network is equivariant under the mirror of each coordinate, N(M_s z) = M_s
  N(z) for the 8 sign flips M_s of (axial, radial, rotation) acting on every lag of a
  coordinate's displacement and own output. Hidden units come in orbits of 8: unit (s, h) has
  the input weights of base unit h with the inputs of the flipped coordinates negated, the same
  bias, and output weights s (.) v_h; b_out = 0. Scaling is about zero (q_offset = f_offset =
  0) and the hybrid's backbone diagonal, so the whole model is mirror-symmetric like the
  bushings the band assumes (``static_estimate``): a coordinate kept at rest while the others
  move carries no network force at all, held or moving (by induction over the run: its input
  and state are mirror-invariant, its output odd), and every held fixed point that is unique
  has zero force in each coordinate held at rest.
- ``rate``: the displacement enters as increments only (the lag weights of each coordinate sum
  to zero: w_q,l = D_l - D_{l-1}), so at every hold the network sees what it sees at rest and
  its held recurrence is the same everywhere: one fixed point for the whole box, the held force
  the backbone's K q plus one constant. The network keeps its dynamic content (relaxation,
  hysteresis through its own past force) and gives up static nonlinearity.
- ``mirror-rate``: both; the one held fixed point is then y = 0 when unique, and the model
  holds exactly its diagonal backbone K q everywhere.
"""

from __future__ import annotations

import numpy as np
import torch

from bushenv.models.base import velocity_of
from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_linear import PlanarLinear
from bushenv.models.planar_narx import N_PAST_F, N_PAST_Q, STRUCTURES, input_axes

SIGNS = np.array([[a, b, c] for a in (1, -1) for b in (1, -1) for c in (1, -1)], dtype=float)
NQ = 3 * (N_PAST_Q + 1)


def check_structure(structure: str) -> None:
    if structure not in STRUCTURES:
        raise PlanarModelError(
            f"network structure {structure!r} unknown; known: {', '.join(STRUCTURES)}"
        )


def is_mirror(structure: str) -> bool:
    return structure.startswith("mirror")


def mirror_hidden(hidden: int) -> int:
    """Hidden units of a mirror network asked for ``hidden``: whole orbits of 8, at least one."""
    return 8 * max(1, int(np.ceil(hidden / 8)))


def symmetric_scale(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(offset 0, scale max |a|) per column: scaling that keeps the mirror of a coordinate."""
    return np.zeros(a.shape[1]), np.maximum(np.abs(a).max(axis=0), 1e-12)


def fit_diagonal_linear(q: np.ndarray, f: np.ndarray, dt: float) -> PlanarLinear:
    """Per coordinate least squares f_i ~ k_i q_i + c_i v_i: the backbone a mirror-symmetric
    bushing allows (a cross term K_ij q_j would hold force in a coordinate at rest)."""
    v = velocity_of(q, dt)
    k, c = np.zeros(3), np.zeros(3)
    for i in range(3):
        a = np.c_[q[:, i], v[:, i]]
        s = np.maximum(np.abs(a).max(axis=0), 1e-300)
        sol = np.linalg.lstsq(a / s, f[:, i], rcond=None)[0] / s
        k[i], c[i] = sol
    return PlanarLinear(np.diag(k), np.diag(c), dt=dt)


class StructuredNet(torch.nn.Module):
    """The training's network (``mimo_train._Net``'s interface: ``forward``, ``unroll``, ``arrays``
    and the attributes ``w1``, ``m1``, ``b1``, ``w_out``, ``mo``, ``b_out`` the certified term
    reads) with the arrays built from free parameters by ``structure``. ``gain`` multiplies the
    increment weights of ``rate`` (the scaled increments are small; without it Adam's steps are
    too short for them)."""

    def __init__(self, structure: str, hidden: int, gen: torch.Generator, gain: float = 1.0):
        super().__init__()
        check_structure(structure)
        self.mirror, self.rate = is_mirror(structure), structure.endswith("rate")
        base = mirror_hidden(hidden) // 8 if self.mirror else hidden
        units = 8 * base if self.mirror else hidden
        n_in = 3 * (N_PAST_Q + 1 + N_PAST_F)
        bound = 1.0 / np.sqrt(n_in)

        def uniform(*shape, scale=1.0):
            r = torch.rand(*shape, generator=gen, dtype=torch.float64) * 2 - 1
            return torch.nn.Parameter(r * scale)

        nd = 3 * N_PAST_Q if self.rate else NQ
        self.gain = gain if self.rate else 1.0
        self.wd = uniform(base, nd, scale=bound)  # displacement (or increment) part
        self.wy = uniform(base, 3 * N_PAST_F, scale=bound)
        self.bh = torch.nn.Parameter(torch.zeros(base, dtype=torch.float64))
        self.v = uniform(3, base, scale=1.0 / np.sqrt(units))
        zero3 = torch.zeros(3, dtype=torch.float64)
        self.bo = torch.nn.Parameter(zero3, requires_grad=not self.mirror)  # mirror: b_out = 0
        if self.mirror:
            sig_in = SIGNS[:, input_axes()]  # (8, 33)
            self.sig_in = torch.tensor(np.repeat(sig_in, base, axis=0))  # (8 base, 33)
            self.sig_out = torch.tensor(np.repeat(SIGNS, base, axis=0).T)  # (3, 8 base)
            self.copies = 8
        else:
            self.copies = 1
        self.m1 = torch.ones(units, n_in, dtype=torch.float64)
        self.mo = torch.ones(3, units, dtype=torch.float64)

    def _base_w1(self) -> torch.Tensor:
        if not self.rate:
            wq = self.wd
        else:  # w_q,l = D_l - D_{l-1}, D_{-1} = D_5 = 0: the lags' weights sum to zero
            d = self.gain * self.wd.reshape(-1, N_PAST_Q, 3)
            zero = torch.zeros_like(d[:, :1])
            wq = (torch.cat([d, zero], 1) - torch.cat([zero, d], 1)).reshape(-1, NQ)
        return torch.cat([wq, self.wy], dim=1)

    @property
    def w1(self) -> torch.Tensor:
        w = self._base_w1()
        return w.repeat(self.copies, 1) * self.sig_in if self.mirror else w

    @property
    def b1(self) -> torch.Tensor:
        return self.bh.repeat(self.copies)

    @property
    def w_out(self) -> torch.Tensor:
        return self.v.repeat(1, self.copies) * self.sig_out if self.mirror else self.v

    @property
    def b_out(self) -> torch.Tensor:
        return self.bo * 0.0 if self.mirror else self.bo

    def forward(self, z: torch.Tensor) -> torch.Tensor:
        return torch.tanh(z @ self.w1.T + self.b1) @ self.w_out.T + self.b_out

    def unroll(self, qz: torch.Tensor, y0: torch.Tensor) -> torch.Tensor:
        """Free run (``train._Net.unroll``), the arrays built once for the whole window."""
        w1, b1, wo, bo = self.w1, self.b1, self.w_out, self.b_out
        ys, hist = [], y0
        for j in range(qz.shape[1]):
            y = torch.tanh(torch.cat([qz[:, j], hist], dim=1) @ w1.T + b1) @ wo.T + bo
            ys.append(y)
            hist = torch.cat([y, hist[:, :-3]], dim=1)
        return torch.stack(ys, dim=1)

    def arrays(self) -> dict[str, np.ndarray]:
        with torch.no_grad():
            return {
                "w1": self.w1.numpy().copy(),
                "b1": self.b1.numpy().copy(),
                "w_out": self.w_out.numpy().copy(),
                "b_out": self.b_out.numpy().copy(),
            }


def increment_gain(qs: np.ndarray) -> float:
    """1 / RMS of the scaled displacement's increments (``StructuredNet``'s ``gain``)."""
    return float(1.0 / max(np.sqrt(np.mean(np.diff(qs, axis=0) ** 2)), 1e-6))
