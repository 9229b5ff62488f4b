"""Certified training: a loss term that asks the NARX network to hold like the records say.

With the displacement held at x, the network's own-output recurrence has fixed points y*
(``bushenv.certify``); the model holds the static force F* = k x + f_offset + f_scale y* (k = 0
for the pure NN, the backbone's for the hybrid) and the fixed point is stable when the spectral
radius rho of the companion matrix of dy_t = sum_j a_j dy_{t-j}, a_j = dN/dy_{t-j}, is below 1.
``CertifiedHolds`` penalises, over holds spread across the whole stroke, every fixed point whose

- static force leaves the band [low, high] x F_s(x) along the sign of F_s (widened by a floor of
  ``FLOOR_FRACTION`` of the records' RMS force), where F_s is the records' own static estimate
  (``static_estimate.py``): the wrong sign and a saturating force are both outside;
- spectral radius exceeds ``radius`` (a stable fixed point losing its stability is where a
  fold, and a delayed departure from a hold, begins);

and every hold whose free run, after the test machine's step from rest (``certify.holds``),
does not end at a fixed point: a stable fixed point is only a local attractor, and a network
can also have a limit cycle the step kicks it into (docs/fit.md has one). The run is short
(``SETTLE_HOLD_S``) and differentiable (the training's own free-run unroll); its last half must
stay within ``SETTLE_TOLERANCE`` of the fixed point it is nearest to at its end.

All three as squared hinges: zero inside the band, below the radius and once settled, so the
data fit is not traded away where the model already holds right. The loss is the weight times
[the mean over the fixed points of ((distance outside the band) / max(|F_s|, floor))^2 +
((rho - radius) / (1 - radius))^2] plus the weight times the mean over the holds and the late
samples of ((|y_t - y*| - tolerance)^+)^2 (y in the network's scaled output, in units of
f_scale, as the free-run data loss is).

**Differentiable fixed points.** The fixed points are found without gradients by the
certificate's exhaustive search (``certify.fixed_points``, few cells: a training term needs
no proof, the certificate gives it afterwards). Each root y0 of phi(y; w) = N(xs, y, .., y; w)
- y then enters the graph as one Newton step, y = y0 - phi(y0; w) / phi'(y0), with phi'
constant: its value is y0 and its gradient the implicit function theorem's, dy*/dw = -(dphi/dw)
/ phi'. **Differentiable spectral radius.** The eigenvalue lambda of largest modulus of the
companion matrix is a root of p(z) = z^n - sum_j a_j z^(n-j); by the same theorem dlambda/da_j =
lambda^(n-j) / p'(lambda), so rho enters as |lambda0 + sum_j dlambda/da_j (a_j - a_j0)|. The
sufficient bound sum |a_j| < 1 is not used: networks that fit have lags of alternating sign
(damping) with sum |a_j| well above 1 at stable fixed points (docs/fit.md), so the bound would
forbid them.

Holds: ``holds`` per call, one in each of as many equal strata of u in [-1, 1], mapped to
x = stroke u |u| (denser near rest, where small forces change sign), the strata shifted by the
golden ratio from call to call so the whole stroke is covered. ``admits`` checks a fixed grid
of ``CHECK_HOLDS`` holds the same way; the trainer keeps the best weights among those it admits.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import torch

from bushenv.certify.fixed_points import fixed_points
from bushenv.certify.holds import step_profiles
from bushenv.certify.network import NarxNet, diagonal
from bushenv.identify.narx_data import NarxProblem
from bushenv.identify.narx_torch import TorchNarx
from bushenv.identify.static_estimate import StaticEstimate, static_estimate

SETTLE_HOLD_S = 1.0  # hold after the step whose second half must sit on a fixed point
SETTLE_TOLERANCE = 0.01  # of f_scale: the certificate's "reached" tolerance (holds.REACH_TOL)
SEARCH_CELLS = 32  # initial cells of the fixed-point search per hold (it refines itself)
CHECK_HOLDS = 101  # holds of the admission check, x = stroke u |u| on a uniform u grid
ADMIT_TOLERANCE = 0.02  # relative distance outside the band still admitted (a hinge's rest)
GOLDEN = 0.5 * (np.sqrt(5.0) - 1.0)
MIN_SLOPE = 1e-9  # |phi'| and |p'| below this are clipped (a fold: the gradient is unbounded)


@dataclass
class CertifiedHolds:
    """The certified-hold loss term (module docstring). ``weight`` scales it; ``low``,
    ``high`` bound the held force as fractions of the static estimate; ``radius`` is the
    largest spectral radius left alone; ``stroke_m`` and ``holds`` place the holds."""

    weight: float
    low: float = 0.8
    high: float = 1.9
    radius: float = 0.98
    stroke_m: float = 12.5e-3
    holds: int = 24
    name: ClassVar[str] = "certified_holds"
    stages: ClassVar[tuple[str, ...]] = ("teacher", "free-run")
    calls: int = field(default=0, init=False)
    _estimate: tuple[int, StaticEstimate] | None = field(default=None, init=False, repr=False)

    # ----- what the term judges against ---------------------------------------------------------
    def estimate(self, problem: NarxProblem) -> StaticEstimate:
        """The records' static estimate (their training parts), computed once per problem."""
        if self._estimate is None or self._estimate[0] != id(problem):
            lengths = [hi - lo for lo, hi in problem.train]
            segs = problem.data.segments
            parts = [(s.x[:n], s.f[:n]) for s, n in zip(segs, lengths, strict=True)]
            est = static_estimate(parts, problem.dt)
            self._estimate = (id(problem), est)
        return self._estimate[1]

    def holds_m(self, call: int) -> np.ndarray:
        """(holds,) held displacements of call number ``call``, m (stratified, shifted)."""
        shift = (call * GOLDEN) % 1.0
        u = 2.0 * (np.arange(self.holds) + shift) / self.holds - 1.0
        return self.stroke_m * u * np.abs(u)

    def check_holds_m(self) -> np.ndarray:
        u = np.linspace(-1.0, 1.0, CHECK_HOLDS)
        return self.stroke_m * u * np.abs(u)

    # ----- the loss ----------------------------------------------------------------------------
    def __call__(self, net: TorchNarx, problem: NarxProblem) -> torch.Tensor:
        x = self.holds_m(self.calls)
        self.calls += 1
        parts = self.penalties(net, problem, x)
        held = torch.mean(parts["static"] ** 2 + parts["radius"] ** 2)
        return self.weight * (held + torch.mean(parts["settle"] ** 2))

    def penalties(self, net: TorchNarx, problem: NarxProblem, x_m: np.ndarray) -> dict[str, Any]:
        """Per fixed point at the holds ``x_m``: the static force (N, differentiable), its
        relative distance outside the band and the spectral radius's excess (both >= 0,
        differentiable), the spectral radius, the hold index, and the fixed points per hold."""
        est = self.estimate(problem)
        cnet = narx_net_of(net, problem)
        fp = fixed_points(cnet, x_m, n_cells=SEARCH_CELLS)
        y0 = fp.y[:, 0]  # one coordinate: the scaled outputs as scalars
        y = held_output(net, problem, x_m[fp.hold], y0)
        force = problem.k * torch.from_numpy(x_m[fp.hold]) + problem.f_off + problem.f_sc * y
        sign, lo, hi, scale = (
            torch.from_numpy(a) for a in est.band(x_m[fp.hold], self.low, self.high)
        )
        along = sign * force
        static = (torch.relu(lo - along) + torch.relu(along - hi)) / scale
        rho = spectral_radius_of(net, problem, x_m[fp.hold], y)
        excess = torch.relu(rho - self.radius) / (1.0 - self.radius)
        late = step_run(net, problem, x_m)
        with torch.no_grad():  # the fixed point of its own hold each run ends nearest to
            gap = np.abs(late[fp.hold, -1].numpy() - y0)
        nearest = np.array([fp.of_hold(i)[np.argmin(gap[fp.hold == i])] for i in range(x_m.size)])
        off = torch.relu(torch.abs(late - y[nearest][:, None]) - SETTLE_TOLERANCE)
        return {
            "force_n": force,
            "static": static,
            "radius": excess,
            "spectral_radius": rho,
            "settle": off,
            "hold": fp.hold,
            "count": fp.count,
        }

    # ----- which weights the trainer may keep --------------------------------------------------
    def report(self, net: TorchNarx, problem: NarxProblem) -> dict[str, Any]:
        """The check grid's verdict: worst relative distance outside the band, largest spectral
        radius, most fixed points at one hold, and whether the weights are admitted."""
        with torch.no_grad():
            p = self.penalties(net, problem, self.check_holds_m())
        worst = float(p["static"].max())
        rho = float(p["spectral_radius"].max())
        unsettled = float(p["settle"].max())
        most = int(p["count"].max())
        ok = (
            worst <= ADMIT_TOLERANCE
            and rho < 0.5 * (1.0 + self.radius)
            and unsettled <= SETTLE_TOLERANCE
            and most == 1
        )
        return {
            "admitted": bool(ok),
            "worst_static_outside": worst,
            "max_spectral_radius": rho,
            "worst_unsettled_scaled": unsettled,
            "max_fixed_points_per_hold": most,
            "static_estimate": self.estimate(problem).as_dict(),
        }

    def admits(self, net: TorchNarx, problem: NarxProblem) -> bool:
        """Whether the weights hold within the band (up to ``ADMIT_TOLERANCE``), below the
        midpoint of ``radius`` and 1, settle after the step to within twice the tolerance, with
        one fixed point at every hold of the check grid."""
        return self.report(net, problem)["admitted"]


def step_run(
    net: TorchNarx, problem: NarxProblem, x_m: np.ndarray, hold_s: float = SETTLE_HOLD_S
) -> torch.Tensor:
    """(M, L) the network's scaled output over the last half of a ``hold_s`` hold, after the
    test machine's step from rest to each of ``x_m`` (``certify.holds.step_profiles``: the
    certificate's own profiles), run free from the rest state (differentiable)."""
    prof, _ = step_profiles(x_m, hold_s, problem.dt)
    nx = problem.n_past_x
    xs = (prof - problem.x_off) / problem.x_sc
    rest_x = (0.0 - problem.x_off) / problem.x_sc
    xs = np.concatenate([np.full((nx, xs.shape[1]), rest_x), xs])
    lag = np.arange(prof.shape[0])[:, None] + nx - np.arange(nx + 1)[None, :]
    x_in = np.ascontiguousarray(np.transpose(xs[lag], (2, 0, 1)))  # (M, T, 1 + nx)
    rest_y = (0.0 - problem.f_off) / problem.f_sc
    y_hist = np.full((x_m.size, problem.n_past_f), rest_y)
    ys = net.unroll(torch.from_numpy(x_in), torch.from_numpy(y_hist), nx, "numba")
    return ys[:, -max(1, int(round(0.5 * hold_s / problem.dt))) :]


def narx_net_of(net: TorchNarx, problem: NarxProblem) -> NarxNet:
    """The certificate's view of the network being trained (its current weights)."""
    a, one = net.arrays(), np.ones(1)
    return NarxNet(
        n_past_x=problem.n_past_x,
        n_past_f=problem.n_past_f,
        q_offset=problem.x_off * one,
        q_scale=problem.x_sc * one,
        f_offset=problem.f_off * one,
        f_scale=problem.f_sc * one,
        w1=a["w1"],
        b1=a["b1"],
        w2=a["w2"],
        b2=a["b2"],
        w_out=a["w_out"].reshape(1, -1),
        b_out=float(a["b_out"]) * one,
        k=np.array([[problem.k]]),
        c=np.array([[problem.c]]),
        dt_s=problem.dt,
        model_name=problem.kind,
    )


def _held_preactivation(net: TorchNarx, problem: NarxProblem, x_m: np.ndarray):
    """(P, H1) first-layer pre-activation of the held displacement, and (H1,) the row sums of
    the past-output columns (both differentiable in the weights)."""
    w1 = net.w1_eff()
    nx1 = 1 + problem.n_past_x
    xs = torch.from_numpy((x_m - problem.x_off) / problem.x_sc)
    c = net.b1 + xs[:, None] * w1[:, :nx1].sum(dim=1)
    return c, w1[:, nx1:].sum(dim=1)


def held_output(
    net: TorchNarx, problem: NarxProblem, x_m: np.ndarray, y0: np.ndarray
) -> torch.Tensor:
    """(P,) fixed points ``y0`` (found at the current weights) as a differentiable function of
    the weights: one Newton step with phi' held constant (value y0, implicit-function
    gradient)."""
    c, s = _held_preactivation(net, problem, x_m)
    y0_t = torch.from_numpy(y0)
    phi = net.head(c + y0_t[:, None] * s) - y0_t
    cnet = narx_net_of(net, problem)
    _, dphi = diagonal(cnet, cnet.held_preactivation(x_m), y0)
    dphi = np.where(np.abs(dphi) < MIN_SLOPE, -MIN_SLOPE, dphi)
    return y0_t - phi / torch.from_numpy(dphi)


def lag_gradients_of(
    net: TorchNarx, problem: NarxProblem, x_m: np.ndarray, y: torch.Tensor
) -> torch.Tensor:
    """(P, n_past_f) a_j = dN/dy_{t-j} at the held points (x, y), differentiable
    (``certify.network.lag_gradients``)."""
    c, s = _held_preactivation(net, problem, x_m)
    h1 = torch.tanh(c + y[:, None] * s)
    g = 1.0 - h1 * h1
    if net.w2.shape[0]:
        h2 = torch.tanh(h1 @ net.w2.T + net.b2)
        g = ((net.w_out * (1.0 - h2 * h2)) @ net.w2) * g
    else:
        g = net.w_out * g
    return g @ net.w1_eff()[:, 1 + problem.n_past_x :]


def spectral_radius_of(
    net: TorchNarx, problem: NarxProblem, x_m: np.ndarray, y: torch.Tensor
) -> torch.Tensor:
    """(P,) spectral radius of the companion matrix at each held point, differentiable
    (largest-modulus root of p(z) = z^n - sum a_j z^(n-j), implicit-function gradient)."""
    a = lag_gradients_of(net, problem, x_m, y)
    a0 = a.detach().numpy()
    P, n = a0.shape
    if P == 0:
        return a.sum(dim=1)
    comp = np.zeros((P, n, n))
    comp[:, 0, :] = a0
    comp[:, np.arange(1, n), np.arange(n - 1)] = 1.0
    eig = np.linalg.eigvals(comp)
    lam = eig[np.arange(P), np.argmax(np.abs(eig), axis=1)]
    powers = lam[:, None] ** np.arange(n - 1, -1, -1)[None, :]  # lambda^(n-j), j = 1..n
    dp = n * lam ** (n - 1) - np.sum(
        np.arange(n - 1, 0, -1)[None, :] * a0[:, : n - 1] * powers[:, 1:], axis=1
    )
    dp = np.where(np.abs(dp) < MIN_SLOPE, MIN_SLOPE, dp)
    d = powers / dp[:, None]  # dlambda / da_j
    delta = a - torch.from_numpy(a0)
    re = torch.tensor(lam.real) + torch.sum(delta * torch.tensor(d.real), dim=1)
    im = torch.tensor(lam.imag) + torch.sum(delta * torch.tensor(d.imag), dim=1)
    # clamped: |lambda| = 0 (a silent network) has no gradient direction, not a NaN one
    return torch.sqrt(torch.clamp(re * re + im * im, min=1e-300))
