"""Ghosts of vanished fixed points, and how long the held free run lingers near them.

Just past a fold the stable fixed point is gone, but phi(y) = N(.., y, ..) - y keeps a small
non-zero extremum where the two roots met: a *ghost*. The free run slows down there, looks
settled, then leaves (seed 000 §5.2: the NN "diverges after 7.3 s" of a held step).

Slow motion along the diagonal: if the outputs drift slowly, y_{t-j} = u - j e with
u = y_{t+1} and e the change per sample, the recurrence y_{t+1} = N(.., y_{t-j}, ..) gives to
first order u = N_diag(u) - e sum_j j a_j, i.e.

    e = dy/dt [per sample] = phi(y) / tau(y),      tau = sum_j j a_j   (the lag-weighted gain)

with a_j = dN/dy_{t-j} (``network.lag_gradients``). Through a ghost where
phi ~ phi_g + phi''_g (y - y_g)^2 / 2 the passage takes pi tau / sqrt(|phi_g phi''_g| / 2)
samples (the integral of dy / (A + B y^2) over the line is pi / sqrt(A B)); in general the time
to move from y0 by a distance d is dt * integral tau / |phi| dy (:func:`slow_flow_time`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.certify.network import NarxNet, diagonal, lag_gradients

GHOST_CELLS = 512  # grid on which phi's extrema are located (then refined)
MIN_PASSAGE_S = 0.05  # ghosts passed faster than this (10 samples at 204.8 Hz) are not kept
FLOW_POINTS = 2001  # quadrature points of slow_flow_time


@dataclass(frozen=True, eq=False)
class Ghosts:
    """Ghosts at M holds, flattened: ``hold`` (G,), ``y`` (G,) scaled output at the extremum,
    ``phi`` (G,) its value there (non-zero), ``passage_s`` (G,) the passage time, s."""

    hold: np.ndarray
    y: np.ndarray
    phi: np.ndarray
    passage_s: np.ndarray


def _tau(net: NarxNet, c: np.ndarray, y: np.ndarray) -> np.ndarray:
    a, _ = lag_gradients(net, c, y)
    return a @ np.arange(1, net.n_past_f + 1, dtype=np.float64)


def ghosts(net: NarxNet, x_m: np.ndarray, min_passage_s: float = MIN_PASSAGE_S) -> Ghosts:
    """Extrema of phi at each hold of ``x_m`` (M,) where |phi| has a non-zero local minimum
    and the free run would take at least ``min_passage_s`` to pass (see the module doc).
    The slow flow along the diagonal is one coordinate's: over several coordinates (``x_m``
    (M, C)) none are computed.

    Extrema are located where phi' changes sign on a ``GHOST_CELLS`` grid and refined by
    bisection; two extrema closer than one grid cell are not separated (ghosts that matter
    are broad: their passage time grows as the extremum flattens).
    """
    if net.n_coords > 1:
        empty = np.zeros(0)
        return Ghosts(hold=np.zeros(0, dtype=np.int64), y=empty, phi=empty, passage_s=empty)
    x_m = np.asarray(x_m, dtype=np.float64).reshape(-1)
    c = net.held_preactivation(x_m)
    lo, hi = net.y_range
    grid = np.linspace(lo, hi, GHOST_CELLS + 1)
    _, d = diagonal(net, c[:, None, :], grid[None, :])
    hold, k = np.nonzero(d[:, :-1] * d[:, 1:] < 0)
    a, b = grid[k], grid[k + 1]
    da = d[hold, k]
    ch = c[hold]
    for _ in range(50):
        mid = 0.5 * (a + b)
        _, dm = diagonal(net, ch, mid)
        left = np.sign(dm) == np.sign(da)
        a, b = np.where(left, mid, a), np.where(left, b, mid)
    y = 0.5 * (a + b)
    phi, _ = diagonal(net, ch, y)
    h = 1e-5 * (hi - lo)
    _, dp = diagonal(net, ch, y + h)
    _, dm = diagonal(net, ch, y - h)
    curv = (dp - dm) / (2 * h)
    tau = _tau(net, ch, y)
    bottleneck = (np.sign(phi) * curv > 0) & (phi != 0) & (tau > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        passage = np.pi * tau / np.sqrt(np.abs(phi * curv) / 2) * net.dt_s
    keep = bottleneck & (passage >= min_passage_s)
    return Ghosts(hold=hold[keep], y=y[keep], phi=phi[keep], passage_s=passage[keep])


def slow_flow_time(net: NarxNet, x_m: float, y0: float, distance: float) -> tuple[float, bool]:
    """Time, s, for the held free run at ``x_m`` to move ``distance`` (scaled) from ``y0``
    along the diagonal in the direction phi(y0) points to: dt * integral tau / |phi| dy.

    Returns (time, reaches): ``reaches`` is False when a root of phi (a fixed point) lies
    within ``distance`` on that side, or the lag-weighted gain tau is not positive on the way
    (the slow-flow reduction does not apply); the time is then ``inf``.
    """
    c = net.held_preactivation(np.array([x_m]))
    phi0, _ = diagonal(net, c, np.array([y0]))
    direction = np.sign(phi0[0])
    if direction == 0:
        return float("inf"), False
    ys = y0 + direction * np.linspace(0.0, distance, FLOW_POINTS)
    phi, _ = diagonal(net, c, ys)
    tau = _tau(net, np.broadcast_to(c, (ys.size, c.shape[1])), ys)
    if np.any(np.sign(phi) != direction) or np.any(tau <= 0):
        return float("inf"), False
    steps = np.trapezoid(tau / np.abs(phi), dx=distance / (FLOW_POINTS - 1))
    return float(steps * net.dt_s), True
