"""Assemble the hold-stability and passivity certificate of a NARX model of any number of
coordinates C (``bushenv certify``).

:func:`certify` asks the same questions of every network, over held deflection vectors:

- **holds**: a grid over +- the span of each coordinate (``holds`` in all; over C > 1
  coordinates ``per_coordinate`` values each, odd so that rest is a hold), every fixed point of
  the held recurrence and its stability, the folds between holds, and the free run after the
  machine's step to each hold: where it settles, whether it oscillates or departs (a departure
  is predicted from the ghosts of one coordinate's diagonal, ``ghosts``);
- **static force**: against the reference's settled force when there is one (wrong sign: a
  coordinate where the two oppose beyond the floors; off: outside the divergence criterion
  ``static``'s band), else against the deflection itself (:func:`wrong_sign`);
- **passivity** as a matrix test about holds (``passivity``: the loss matrix H_I(w) of the
  dynamic stiffness must be positive semidefinite; C = 1: Im K >= 0), the reference's measured
  by sines; for one coordinate also where the divergence judge's ``energy`` criterion fires on
  sines (``energy``).

It returns a :class:`Certificate`: the JSON document (``document``, written as
``certificate.json``, laid out by ``document``) plus the arrays the plots and a searcher use.
For a searcher, cheaper pieces stand alone: :func:`stability_margin`,
:func:`least_stable_holds`, :func:`non_passive_bands`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

import bushenv.certify.energy as en
from bushenv.certify.document import (
    WRONG_SIGN_N,
    document,
    hold_entry,
    lever_of,
    passivity_entries,
)
from bushenv.certify.fixed_points import FixedPoints, Fold, fixed_points, folds, grid
from bushenv.certify.ghosts import Ghosts, ghosts
from bushenv.certify.holds import HoldRun, free_runs, reference_static_force
from bushenv.certify.network import CertifyError, NarxNet, narx_net
from bushenv.certify.options import CertifyOptions, hold_axes, passivity_holds
from bushenv.certify.passivity import negative_bands
from bushenv.certify.stiffness import SETTLE_S, dynamic_stiffness, sine_s

SIGN_FLOOR_N = WRONG_SIGN_N  # a sign counts beyond this force (see ``document``)
K_POINTS = 512  # frequencies of the analytic K, 0 to Nyquist (0.2 Hz apart at 204.8 Hz)


@dataclass(eq=False)
class Certificate:
    """The certificate: ``document`` (JSON-able dict) and the analysis behind it; ``axes`` the
    grid's values per coordinate; ``reference_static`` (M, C) the reference's settled force
    (NaN without one)."""

    document: dict
    net: NarxNet
    fp: FixedPoints
    ghosts: Ghosts
    folds: list[Fold]
    runs: list[HoldRun]
    reference_static: np.ndarray
    axes: list[np.ndarray]
    passivity: list[dict] = field(default_factory=list)

    @property
    def reference_static_n(self) -> np.ndarray:
        """(M,) the reference's settled force of a one-coordinate certificate, N."""
        return self.reference_static[:, 0]


def wrong_sign(q, static, units=("m",), reference=None) -> np.ndarray:
    """(P,) whether each held static force ``static`` (P, C) at ``q`` (P, C) has the wrong
    sign. Against the ``reference``'s static force (P, C) where it is finite: a coordinate
    where the two oppose, both beyond ``WRONG_SIGN_N`` (N m: x ``document.LEVER_M``). Without
    one: a passive bushing stores energy in a held deflection, so its static force points away
    from rest, q . f >= 0 (for f = grad W with W convex and least at rest,
    q . grad W(q) >= W(q) - W(0)); wrong where q . f < -``WRONG_SIGN_N`` x (|q_translations| +
    LEVER_M |q_rotations|). C = 1: F x < 0 beyond 10 N, or F F_ref < 0 both beyond 10 N."""
    q = np.atleast_2d(np.asarray(q, dtype=np.float64))
    f = np.atleast_2d(np.asarray(static, dtype=np.float64))
    lever = lever_of(units)
    outward = np.sum(q * f, axis=1) < -WRONG_SIGN_N * np.sum(np.abs(q) * lever, axis=1)
    if reference is None:
        return outward
    r = np.atleast_2d(np.asarray(reference, dtype=np.float64))
    floor = WRONG_SIGN_N * lever
    opposed = np.any((f * r < 0) & (np.minimum(np.abs(f), np.abs(r)) > floor), axis=1)
    return np.where(np.all(np.isfinite(r), axis=1), opposed, outward)


# ----- cheap pieces for searchers ------------------------------------------------------------
def stability_margin(fp: FixedPoints) -> np.ndarray:
    """(M,) 1 - spectral radius of each hold's least stable attractor: the largest radius
    below 1 among its fixed points (near 0: an attractor about to be lost, as next to a
    fold); where no fixed point is stable, 1 - the smallest radius (negative)."""
    rho = fp.spectral_radius
    weakest = np.full(len(fp.q), -np.inf)
    np.maximum.at(weakest, fp.hold[fp.stable], rho[fp.stable])
    best = np.full(len(fp.q), np.inf)
    np.minimum.at(best, fp.hold, rho)
    return 1.0 - np.where(np.isfinite(weakest), weakest, best)


def least_stable_holds(model_or_net, q: np.ndarray, n: int = 5) -> np.ndarray:
    """The ``n`` holds of ``q`` (M,) or (M, C) with the smallest :func:`stability_margin`,
    least first (the shape of ``q``'s rows)."""
    net = model_or_net if isinstance(model_or_net, NarxNet) else narx_net(model_or_net)
    q = np.asarray(q, dtype=np.float64)
    fp = fixed_points(net, q)
    return q[np.argsort(stability_margin(fp), kind="stable")[:n]]


def k_grid(net: NarxNet) -> np.ndarray:
    """(K_POINTS,) the frequencies of the analytic K, 0 to Nyquist, Hz."""
    nyquist = 0.5 / net.dt_s
    return np.linspace(nyquist / K_POINTS, nyquist, K_POINTS)


def non_passive_bands(model_or_net, q=0.0, velocity: str = "central") -> list[tuple[float, float]]:
    """Frequency bands, Hz, where the least loss eigenvalue (C = 1: Im K) is negative about
    the stable fixed points of the hold ``q`` (a number for one coordinate, else (C,)); the
    union over them."""
    from bushenv.certify.passivity import amplitudes, loss_eigenvalues

    net = model_or_net if isinstance(model_or_net, NarxNet) else narx_net(model_or_net)
    fp = fixed_points(net, np.asarray(q, dtype=np.float64).reshape(1, -1))
    freq = k_grid(net)
    k = dynamic_stiffness(net, fp.q[fp.hold], fp.y, freq, velocity)[fp.stable]
    if k.shape[0] == 0:
        return []
    least = loss_eigenvalues(k, amplitudes(net.units))[..., 0]
    return negative_bands(freq, least.min(axis=0))


# ----- the whole certificate -----------------------------------------------------------------
def _reached_bands(net, fp, runs, velocity) -> list[list[tuple[float, float]]]:
    """Bands of a negative least loss eigenvalue about the fixed point each hold's run reaches."""
    from bushenv.certify.passivity import amplitudes, loss_eigenvalues

    pts = [(i, fp.of_hold(i)[r.reached]) for i, r in enumerate(runs) if r.reached is not None]
    out: list[list[tuple[float, float]]] = [[] for _ in runs]
    if not pts:
        return out
    hold, p = np.array(pts).T
    freq = k_grid(net)
    k = dynamic_stiffness(net, fp.q[fp.hold[p]], fp.y[p], freq, velocity)
    least = loss_eigenvalues(k, amplitudes(net.units))[..., 0]
    for row, i in enumerate(hold):
        out[int(i)] = negative_bands(freq, least[row])
    return out


def _energy(model, reference, opts: CertifyOptions) -> dict | None:
    """The energy criterion on sines (one coordinate: the judge's sines are of one axis)."""
    if model.n_coords != 1:
        return None
    freq = np.array(opts.energy_freq_hz)
    fires = en.energy_fires(model, reference, freq, np.array(opts.energy_amplitudes_m))
    return {
        "frequency_hz": freq,
        "amplitudes_m": list(opts.energy_amplitudes_m),
        "fires": fires,
        "bands_hz": [[list(b) for b in en.firing_bands(freq, row)] for row in fires],
    }


def _work_units(opts: CertifyOptions, dt: float, holds: int, coords: int) -> dict[str, float]:
    """Relative cost of each stage, in simulated samples (for the time-left estimate)."""
    hold = holds * (opts.hold_s + 1.0) / dt
    n_pas = len(passivity_holds(opts, coords)) * coords
    sine_len = SETTLE_S + sine_s(np.array(opts.reference_freq_hz)) + 1
    sine = n_pas * len(opts.reference_freq_hz) * sine_len / dt
    scan = 2 * len(opts.energy_amplitudes_m) * len(opts.energy_freq_hz) * (en.DURATION_S + 1) / dt
    return {
        "fixed points": holds * 2000.0 * coords**3,
        "free runs": hold * coords,
        "reference holds": 1.5 * hold * coords,
        "passivity": 1.5 * sine,
        "energy scan": 1.2 * scan if coords == 1 else 0.0,
    }


def certify(
    model,
    reference,
    options: CertifyOptions | None = None,
    progress: Callable[[str, float], None] | None = None,
) -> Certificate:
    """The certificate of ``model`` (a NARX network of C coordinates) against ``reference``
    (a model of as many coordinates) over the holds' span; ``reference`` None: the
    reference-free parts only (no static comparison, no reference K; wrong sign against the
    deflection). ``progress(stage, fraction_done)`` is called before each stage.
    """
    opts = options or CertifyOptions()
    net = narx_net(model)
    dim = net.n_coords
    opts.check(dim)
    if reference is not None:
        if reference.n_coords != dim:
            raise CertifyError(
                f"the reference has {reference.n_coords} coordinate(s), the model {dim}: give a "
                f"reference of the model's coordinates ({', '.join(model.coords)})"
            )
        if abs(reference.dt - net.dt_s) > 1e-9 * net.dt_s:
            raise CertifyError(
                f"model runs at {1 / net.dt_s:.6g} Hz, reference at {1 / reference.dt:.6g} Hz; "
                "give a reference sampled at the model's rate"
            )
    axes = hold_axes(opts, dim)
    q = grid(*axes)
    units = _work_units(opts, net.dt_s, len(q), dim)
    total, done, timing = sum(units.values()), 0.0, {}

    def stage(name: str) -> float:
        if progress is not None:
            progress(name, done / total)
        return time.perf_counter()

    t = stage("fixed points")
    fp = fixed_points(net, q)
    gh = ghosts(net, q)
    fo = folds(net, fp, axes)
    timing["fixed_points_s"], done = time.perf_counter() - t, done + units["fixed points"]
    t = stage("free runs")
    runs, _, _ = free_runs(model, net, fp, gh, opts.hold_s)
    bands = _reached_bands(net, fp, runs, opts.velocity)
    timing["free_runs_s"], done = time.perf_counter() - t, done + units["free runs"]
    t = stage("reference holds")
    ref_static = (  # no reference: no comparison (off band); wrong sign against q itself
        np.full(q.shape, np.nan)
        if reference is None
        else reference_static_force(reference, q if dim > 1 else q[:, 0], opts.hold_s).reshape(
            q.shape
        )
    )
    timing["reference_holds_s"], done = time.perf_counter() - t, done + units["reference holds"]
    t = stage("passivity")
    pas = passivity_entries(
        net, fixed_points(net, passivity_holds(opts, dim)), reference, k_grid(net), opts
    )
    timing["passivity_s"], done = time.perf_counter() - t, done + units["passivity"]
    t = stage("energy scan")
    scan = _energy(model, reference, opts)
    timing["energy_scan_s"] = time.perf_counter() - t
    holds = [
        hold_entry(net, fp, gh, r, i, ref_static[i], bands[i], wrong_sign)
        for i, r in enumerate(runs)
    ]
    doc = document(net, opts, holds, fo, pas, scan, timing, reference is not None)
    return Certificate(doc, net, fp, gh, fo, runs, ref_static, axes, pas)
