"""Certified MIMO training: a loss term that asks a MIMO network to hold like the records say.

The one-axis term (``bushenv.identify.certified``) in three coordinates. Held at a deflection
vector q, the network's own-output recurrence has fixed points y* (3,) (``fixed_points.py``);
the model holds the static force F* = K q + f_offset + f_scale (.) y* (K the hybrid's backbone,
0 for the pure network), stable when the block companion matrix of dy_t = sum_l A_l dy_{t-l}
has spectral radius rho < 1. ``MimoCertifiedHolds`` penalises, over holds spread across the
rig3 box (single coordinates, pairs and all three, ``holds_q``), every fixed point whose

- static force leaves, in any coordinate, the band of the records' static estimate
  (``static_estimate.band``: a coordinate held at rest must hold no force beyond its floor);
- spectral radius exceeds ``radius``;

and every hold whose free run after a step from rest (``step_profile``, ``SETTLE_HOLD_S``) does
not, over its last half, stay within ``SETTLE_TOLERANCE`` (scaled output) of the fixed point it
ends nearest to. All as squared hinges, zero where the model already holds right; the loss is
weight x [mean over fixed points of (sum over coordinates of ((distance outside) / scale)^2 +
((rho - radius) / (1 - radius))^2) + mean over holds, late samples and coordinates of the
settle hinge^2].

**Differentiable fixed points.** Found without gradients (``fixed_points``: interval/Krawczyk
isolation, exhaustive), each root y0 of phi(y; w) = w_out tanh(c + S y) + b_out - y enters the
graph as one Newton step y = y0 - J0^-1 phi(y0; w), J0 the 3x3 Jacobian at the current weights
held constant: its value is y0, its gradient the implicit function theorem's, dy*/dw =
-J^-1 dphi/dw. **Differentiable spectral radius.** lambda, the block companion matrix's
eigenvalue of largest modulus, with right and left eigenvectors v, u (C v = lambda v, u^T C =
lambda u^T): dlambda = u^T dC v / (u^T v), and only C's first block row [A_1 .. A_5] depends on
the weights, so rho enters as |lambda0 + sum (A - A0) (.) G|, G = u[:3] v^T / (u^T v).

``check`` judges a trained model (numpy, its own kernel) on a fixed grid of ``CHECK_LEVELS``^3
holds; ``admits`` is that check passed, and the trainer keeps the best admitted weights.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import torch

from bushenv.certify.fixed_points import fixed_points, grid
from bushenv.certify.network import NarxNet, narx_net

# the one-axis term's admission tolerance and its "reached" (per coordinate, of f_scale)
from bushenv.identify.certified import ADMIT_TOLERANCE, SETTLE_TOLERANCE
from bushenv.identify.static_estimate import COUPLING, StaticEstimate
from bushenv.models.planar_narx import N_PAST_F, N_PAST_Q, PlanarNarx

STROKE = (12.5e-3, 12.5e-3, 0.15)  # BushRig3-v0's stroke (m, m, rad): the box the search drives
RAMP_S = 0.02  # the step's rise, within the rig's rates (0.63 m/s, 7.5 rad/s at full stroke)
SETTLE_HOLD_S = 0.6  # hold after the step; its second half must sit on a fixed point
CHECK_LEVELS = 7  # the admission grid: u in linspace(-1, 1, 7) per coordinate, q = stroke u |u|
HARD_HOLDS = 12  # holds of the last check that failed it, added to every later training step
MIN_PIVOT = 1e-9  # |det J0|, |u^T v| below this are clipped (a fold: the gradient is unbounded)
# which coordinates a training hold moves, in turn: each alone, each pair, all three
SUBSETS = np.array([(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, 0, 1), (0, 1, 1), (1, 1, 1)])
_PHI3 = 1.2207440846057596  # the plastic number: R3 low-discrepancy sequence in the unit cube
R3 = 1.0 / _PHI3 ** np.arange(1, 4)


@dataclass(frozen=True)
class MimoProblem:
    """What the term needs of a training: the scaling, the backbone, the sample time and the
    records' static estimate."""

    q_offset: np.ndarray
    q_scale: np.ndarray
    f_offset: np.ndarray
    f_scale: np.ndarray
    k: np.ndarray  # (3, 3) backbone stiffness, zeros for a pure network
    dt: float
    estimate: StaticEstimate

    def model(self, arrays: dict[str, np.ndarray]) -> PlanarNarx:
        """The MIMO network of ``arrays`` (its fixed points do not depend on the backbone)."""
        return PlanarNarx(
            q_offset=self.q_offset,
            q_scale=self.q_scale,
            f_offset=self.f_offset,
            f_scale=self.f_scale,
            dt=self.dt,
            **arrays,
        )


def step_profile(q: np.ndarray, dt: float, hold_s: float = SETTLE_HOLD_S) -> np.ndarray:
    """(T, M, 3) from rest, a ``RAMP_S`` linear rise to each hold of ``q`` (M, 3), then held."""
    ramp = max(1, int(round(RAMP_S / dt)))
    rise = np.arange(1, ramp + 1) / ramp
    hold = max(2, int(round(hold_s / dt)))
    frac = np.concatenate([np.zeros(1), rise, np.ones(hold)])
    return frac[:, None, None] * np.asarray(q, dtype=np.float64)[None]


def late_samples(hold_s: float, dt: float) -> int:
    return max(1, int(round(0.5 * hold_s / dt)))


@dataclass
class MimoCertifiedHolds:
    """The certified-hold loss term of the MIMO networks (module docstring)."""

    weight: float
    low: float = 0.8
    high: float = 1.9
    radius: float = 0.98
    stroke: tuple[float, float, float] = STROKE
    holds: int = 24
    coupling: float = COUPLING
    name: ClassVar[str] = "certified_holds"
    stages: ClassVar[tuple[str, ...]] = ("teacher", "free-run")
    calls: int = field(default=0, init=False)
    hard: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)), init=False, repr=False)

    def holds_q(self, call: int) -> np.ndarray:
        """(holds, 3) the held vectors of call ``call``: new points of the R3 sequence each call,
        q = stroke u |u| (denser near rest), each hold moving the coordinates of ``SUBSETS`` in
        turn (the others at rest, where cross-force shows)."""
        k = np.arange(self.holds) + call * self.holds + 1
        u = 2.0 * ((0.5 + np.outer(k, R3)) % 1.0) - 1.0
        mask = SUBSETS[(np.arange(self.holds) + call) % len(SUBSETS)]
        return np.asarray(self.stroke) * u * np.abs(u) * mask

    def check_holds_q(self) -> np.ndarray:
        u = np.linspace(-1.0, 1.0, CHECK_LEVELS)
        s = np.asarray(self.stroke)
        return grid(*(s[i] * u * np.abs(u) for i in range(3)))

    def __call__(self, net: Any, problem: MimoProblem) -> torch.Tensor:
        q = np.vstack([self.holds_q(self.calls), self.hard])
        self.calls += 1
        parts = self.penalties(net, problem, q)
        held = torch.sum(parts["static"] ** 2, dim=1) + parts["radius"] ** 2
        settle = parts["settle"]
        return self.weight * (
            (torch.mean(held) if held.numel() else held.sum())
            + (torch.mean(settle**2) if settle.numel() else settle.sum())
        )

    def penalties(self, net: Any, problem: MimoProblem, q: np.ndarray) -> dict[str, Any]:
        """At the holds ``q`` (M, 3): per fixed point the static force (P, 3), its relative
        distance outside the band (P, 3) and the spectral radius's excess (P,) (differentiable,
        >= 0), the spectral radius; per hold the settle hinge (M', L, 3)."""
        with torch.no_grad():
            arrays = net.arrays()
        held = narx_net(problem.model(arrays))
        fp = fixed_points(problem.model(arrays), q)
        c_np = held.held(q)[fp.hold]
        w = _weights(net)
        c = (
            w["b1"]
            + torch.from_numpy((q[fp.hold] - problem.q_offset) / problem.q_scale) @ w["wq_sum"].T
        )
        y = newton_step(w, c, c_np, held, fp.y)
        force = (
            torch.from_numpy(q[fp.hold] @ problem.k.T + problem.f_offset)
            + torch.from_numpy(problem.f_scale) * y
        )
        sign, lo, hi, scale = problem.estimate.band(q[fp.hold], self.low, self.high, self.coupling)
        along = torch.from_numpy(sign) * force
        lo_t, hi_t = torch.from_numpy(lo), torch.from_numpy(hi)
        outside = torch.relu(lo_t - along) + torch.relu(along - hi_t)
        rho = spectral_radius_of(w, c, y)
        late = step_run(net, problem, q)
        with torch.no_grad():
            end = late[:, -1].numpy()
        has = np.flatnonzero(fp.count > 0)
        nearest = []
        for m in has:
            idx = np.flatnonzero(fp.hold == m)
            nearest.append(idx[np.argmin(np.linalg.norm(fp.y[idx] - end[m], axis=1))])
        target = y[np.array(nearest, dtype=np.int64)]
        off = torch.relu(torch.abs(late[has] - target[:, None, :]) - SETTLE_TOLERANCE)
        return {
            "force": force,
            "static": outside / torch.from_numpy(scale),
            "radius": torch.relu(rho - self.radius) / (1.0 - self.radius),
            "spectral_radius": rho,
            "settle": off,
            "fixed_points": fp,
        }

    def check(self, model: PlanarNarx, estimate: StaticEstimate) -> dict[str, Any]:
        """``check`` with this term's band, radius and stroke; the holds that fail it (the
        worst ``HARD_HOLDS``) join every later training step, so the grid's own failures are
        trained on until a check passes them."""
        q = self.check_holds_q()
        out = check(model, estimate, q, self.low, self.high, self.radius, self.coupling)
        self.hard = q[np.array(out["failing_holds"][:HARD_HOLDS], dtype=np.int64)]
        return out

    def admits(self, model: PlanarNarx, estimate: StaticEstimate) -> bool:
        return self.check(model, estimate)["admitted"]


def _weights(net: Any) -> dict[str, torch.Tensor]:
    """The network's weights as the held recurrence uses them (masked, differentiable)."""
    w1 = net.w1 * net.m1
    nq = 3 * (N_PAST_Q + 1)
    wq = w1[:, :nq].reshape(-1, N_PAST_Q + 1, 3)
    wy = w1[:, nq:].reshape(-1, N_PAST_F, 3).permute(1, 0, 2)  # (5, H, 3)
    return {
        "b1": net.b1,
        "wq_sum": wq.sum(dim=1),
        "wy": wy,
        "s": wy.sum(dim=0),
        "w_out": net.w_out * net.mo,
        "b_out": net.b_out,
    }


def newton_step(w, c: torch.Tensor, c_np: np.ndarray, held: NarxNet, y0: np.ndarray):
    """(P, 3) the fixed points ``y0`` as functions of the weights: y0 - J0^-1 phi(y0; w)."""
    y0_t = torch.from_numpy(y0)
    phi = torch.tanh(c + y0_t @ w["s"].T) @ w["w_out"].T + w["b_out"] - y0_t
    _, jac = held.phi(c_np, y0)
    det = np.linalg.det(jac) if len(jac) else np.zeros(0)
    jac = jac + (np.abs(det) < MIN_PIVOT)[:, None, None] * MIN_PIVOT * np.eye(3)
    inv = torch.from_numpy(np.linalg.inv(jac)) if len(jac) else torch.zeros(0, 3, 3)
    return y0_t - torch.einsum("pij,pj->pi", inv, phi)


def spectral_radius_of(w, c: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
    """(P,) spectral radius of the block companion matrix at the held points (c, y),
    differentiable through the largest-modulus eigenvalue's left and right eigenvectors."""
    t = torch.tanh(c + y @ w["s"].T)
    d = 1.0 - t * t
    a = torch.einsum("ih,ph,lhj->plij", w["w_out"], d, w["wy"])  # (P, 5, 3, 3)
    P, lags = a.shape[:2]
    row = a.permute(0, 2, 1, 3).reshape(P, 3, 3 * lags)  # C's first block row
    if P == 0:
        return row.sum(dim=(1, 2))
    row0 = row.detach().numpy()
    comp = np.zeros((P, 3 * lags, 3 * lags))
    comp[:, :3, :] = row0
    comp[:, 3:, :-3] = np.eye(3 * (lags - 1))
    lam_all, right = np.linalg.eig(comp)
    pick = np.argmax(np.abs(lam_all), axis=1)
    lam = lam_all[np.arange(P), pick]
    v = right[np.arange(P), :, pick]
    lam_t, left = np.linalg.eig(np.transpose(comp, (0, 2, 1)))
    u = left[np.arange(P), :, np.argmin(np.abs(lam_t - lam[:, None]), axis=1)]
    norm = np.einsum("pi,pi->p", u, v)
    norm = np.where(np.abs(norm) < MIN_PIVOT, MIN_PIVOT, norm)
    g = u[:, :3, None] * v[:, None, :] / norm[:, None, None]  # dlambda / dC[:3, :]
    delta = row - torch.from_numpy(row0)
    re = torch.from_numpy(lam.real) + torch.sum(delta * torch.from_numpy(g.real), dim=(1, 2))
    im = torch.from_numpy(lam.imag) + torch.sum(delta * torch.from_numpy(g.imag), dim=(1, 2))
    return torch.sqrt(torch.clamp(re * re + im * im, min=1e-300))


def step_run(net: Any, problem: MimoProblem, q: np.ndarray) -> torch.Tensor:
    """(M, L, 3) the network's scaled output over the last half of the hold after
    ``step_profile`` to each hold, run free from rest (differentiable)."""
    prof = step_profile(q, problem.dt)  # (T, M, 3)
    qs = (np.transpose(prof, (1, 0, 2)) - problem.q_offset) / problem.q_scale
    rest = (0.0 - problem.q_offset) / problem.q_scale
    pad = np.concatenate([np.broadcast_to(rest, (len(q), N_PAST_Q, 3)), qs], axis=1)
    T = prof.shape[0]
    qz = np.concatenate([pad[:, N_PAST_Q - l : N_PAST_Q - l + T] for l in range(N_PAST_Q + 1)], 2)
    y0 = np.tile((0.0 - problem.f_offset) / problem.f_scale, N_PAST_F)
    ys = net.unroll(torch.from_numpy(qz), torch.from_numpy(np.tile(y0, (len(q), 1))))
    return ys[:, -late_samples(SETTLE_HOLD_S, problem.dt) :]


def check(
    model: PlanarNarx,
    estimate: StaticEstimate,
    q: np.ndarray,
    low: float = 0.8,
    high: float = 1.9,
    radius: float = 0.98,
    coupling: float = COUPLING,
) -> dict[str, Any]:
    """A MIMO network's holds judged at ``q`` (M, 3) (numpy, the model's own kernel): its
    fixed points (``fixed_points``), their static force against the band, their spectral
    radius, the free run after the step settling; admitted when every fixed point is within
    ``ADMIT_TOLERANCE`` of the band, rho below halfway from ``radius`` to 1, every hold settled
    within twice ``SETTLE_TOLERANCE``, exactly one fixed point at every hold, none unresolved.
    ``failing_holds``: the indices into ``q`` of the holds that fail, worst first."""
    fp = fixed_points(model, q)
    sign, lo, hi, scale = estimate.band(q[fp.hold], low, high, coupling)
    along = sign * fp.force
    static = (np.maximum(lo - along, 0.0) + np.maximum(along - hi, 0.0)) / scale
    f_run = model.simulate(step_profile(q, model.dt))[-late_samples(SETTLE_HOLD_S, model.dt) :]
    unsettled = np.zeros(len(q))
    for m in np.flatnonzero(fp.count > 0):
        gap = np.abs(f_run[:, m, None, :] - fp.force[fp.hold == m][None]) / model.f_scale
        unsettled[m] = np.min(np.max(gap, axis=(0, 2)))  # to the nearest fixed point
    unsettled[fp.count == 0] = np.inf
    outside = np.max(static, axis=1) if len(static) else np.zeros(0)
    rho = fp.spectral_radius
    out = {
        "holds": len(q),
        "fixed_points": int(len(fp.hold)),
        "max_fixed_points_per_hold": int(fp.count.max()) if len(q) else 0,
        "holds_without_one_fixed_point": int(np.sum(fp.count != 1)),
        "unresolved_boxes": int(fp.unresolved.sum()),
        "unstable": int(np.sum(rho >= 1.0)),
        "max_spectral_radius": float(rho.max()) if rho.size else 0.0,
        "out_of_band": int(np.sum(outside > ADMIT_TOLERANCE)),
        "worst_static_outside": float(outside.max()) if outside.size else 0.0,
        "unsettled_holds": int(np.sum(unsettled > 2 * SETTLE_TOLERANCE)),
        "worst_unsettled_scaled": float(unsettled.max()) if len(q) else 0.0,
    }
    # per hold, how badly it fails (0: passes), worst first: the holds a training adds
    bad = np.zeros(len(q))
    np.maximum.at(bad, fp.hold, np.maximum(outside - ADMIT_TOLERANCE, 0.0) / ADMIT_TOLERANCE)
    np.maximum.at(bad, fp.hold, np.maximum(rho - 0.5 * (1.0 + radius), 0.0) / (1.0 - radius))
    bad = np.maximum(bad, np.maximum(unsettled - 2 * SETTLE_TOLERANCE, 0.0) / SETTLE_TOLERANCE)
    bad[fp.count != 1] = np.inf
    order = np.argsort(-bad, kind="stable")
    out["failing_holds"] = [int(i) for i in order[bad[order] > 0]]
    out["admitted"] = bool(
        out["worst_static_outside"] <= ADMIT_TOLERANCE
        and out["max_spectral_radius"] < 0.5 * (1.0 + radius)
        and out["worst_unsettled_scaled"] <= 2 * SETTLE_TOLERANCE
        and out["holds_without_one_fixed_point"] == 0
        and out["unresolved_boxes"] == 0
    )
    return out
