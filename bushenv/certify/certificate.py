"""Assemble the hold-stability and passivity certificate of a NARX model (``bushenv certify``).

:func:`certify` runs the analysis over the stroke, the free runs, the reference's holds and
sines, and returns a :class:`Certificate`: the JSON document (``.document``, written as
``certificate.json``) plus the arrays the plots and a searcher use. For a searcher, cheaper
pieces stand alone: :func:`stability_margin`, :func:`least_stable_holds`,
:func:`non_passive_bands`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

import bushenv.certify.energy as en
from bushenv.certify.fixed_points import FixedPoints, Fold, fixed_points, folds
from bushenv.certify.ghosts import Ghosts, ghosts
from bushenv.certify.holds import AVERAGE_S, HOLD_S, HoldRun, free_runs, reference_static_force
from bushenv.certify.network import CertifyError, NarxNet, describe, narx_net
from bushenv.certify.passivity import (
    SETTLE_S,
    SINE_S,
    dynamic_stiffness,
    negative_bands,
    sine_stiffness,
)
from bushenv.divergence import static_margin
from bushenv.scales import FORCE_FLOOR_N

# A sign is meaningful above 10 N: over 3 sigma of the reference rubber's load-cell noise
# (sigma <= 3 N, radial) and below the force of the smallest hold that matters (0.05 mm x
# 380 N/mm = 19 N, seed 000 Table 1).
SIGN_FLOOR_N = 10.0
# Off in size: outside the divergence criterion ``static``'s band (``static_margin``).
K_POINTS = 512  # frequencies of the analytic K, 0 to Nyquist (0.2 Hz apart at 204.8 Hz)


@dataclass(frozen=True)
class CertifyOptions:
    """Settings of :func:`certify` (SI units)."""

    holds: int = 201
    extra_holds_m: tuple[float, ...] = ()  # held displacements added to the grid
    stroke_m: float = 12.5e-3  # the machine's +-12.5 mm (seed 002 Table 1)
    hold_s: float = HOLD_S
    velocity: str = "central"
    passivity_holds_m: tuple[float, ...] = (-4e-3, -1e-3, 0.0, 1e-3, 4e-3)
    reference_amplitude_m: float = 0.1e-3
    reference_freq_hz: tuple[float, ...] = tuple(float(f) for f in np.arange(2.0, 101.0, 4.0))
    energy_amplitudes_m: tuple[float, ...] = (0.25e-3, 0.5e-3, 1e-3, 2e-3)
    energy_freq_hz: tuple[float, ...] = tuple(float(f) for f in np.arange(2.0, 81.0, 2.0))

    def check(self) -> None:
        if self.holds < 3:
            raise CertifyError(f"holds must be >= 3 (a grid over the stroke), got {self.holds}")
        if not (np.isfinite(self.stroke_m) and self.stroke_m > 0):
            raise CertifyError(f"stroke must be a positive length, got {self.stroke_m!r} m")
        if not (np.isfinite(self.hold_s) and self.hold_s >= 2.0):
            raise CertifyError(f"hold must last at least 2 s, got {self.hold_s!r} s")
        if not np.all(np.isfinite(self.extra_holds_m)):
            raise CertifyError(f"extra holds must be finite, got {self.extra_holds_m}")
        if not (np.isfinite(self.reference_amplitude_m) and self.reference_amplitude_m > 0):
            raise CertifyError(f"sine amplitude must be positive, got {self.reference_amplitude_m}")


@dataclass(eq=False)
class Certificate:
    """The certificate: ``document`` (JSON-able dict) and the analysis behind it."""

    document: dict
    net: NarxNet
    fp: FixedPoints
    ghosts: Ghosts
    folds: list[Fold]
    runs: list[HoldRun]
    reference_static_n: np.ndarray
    passivity: list[dict] = field(default_factory=list)


def wrong_sign(x_m: float, static_n: float | None, reference_n: float = float("nan")) -> bool:
    """Whether a held static force has the wrong sign: against the reference's static force
    when there is one (both beyond ``SIGN_FLOOR_N``); without one (``reference_n`` NaN),
    against the deflection itself -- a passive bushing's relaxed force pushes back, so it has
    the sign of x (beyond ``SIGN_FLOOR_N``; x = 0 has no sign)."""
    if static_n is None:
        return False
    if np.isfinite(reference_n):
        return bool(
            static_n * reference_n < 0 and min(abs(static_n), abs(reference_n)) > SIGN_FLOOR_N
        )
    return bool(static_n * x_m < 0 and abs(static_n) > SIGN_FLOOR_N)


# ----- cheap pieces for searchers ------------------------------------------------------------
def stability_margin(fp: FixedPoints) -> np.ndarray:
    """(M,) 1 - spectral radius of each hold's least stable attractor: the largest radius
    below 1 among its fixed points (near 0: an attractor about to be lost, as next to a
    fold); where no fixed point is stable, 1 - the smallest radius (negative)."""
    rho = fp.spectral_radius
    weakest = np.full(fp.x_m.size, -np.inf)
    np.maximum.at(weakest, fp.hold[fp.stable], rho[fp.stable])
    best = np.full(fp.x_m.size, np.inf)
    np.minimum.at(best, fp.hold, rho)
    return 1.0 - np.where(np.isfinite(weakest), weakest, best)


def least_stable_holds(model_or_net, x_m: np.ndarray, n: int = 5) -> np.ndarray:
    """The ``n`` holds of ``x_m`` with the smallest :func:`stability_margin`, least first."""
    net = model_or_net if isinstance(model_or_net, NarxNet) else narx_net(model_or_net)
    fp = fixed_points(net, np.asarray(x_m, dtype=np.float64))
    return fp.x_m[np.argsort(stability_margin(fp), kind="stable")[:n]]


def non_passive_bands(
    model_or_net, x_m: float = 0.0, velocity: str = "central"
) -> list[tuple[float, float]]:
    """Frequency bands, Hz, where Im K < 0 about the stable fixed points of the hold ``x_m``
    (the union over them)."""
    net = model_or_net if isinstance(model_or_net, NarxNet) else narx_net(model_or_net)
    fp = fixed_points(net, np.array([x_m]))
    freq = _k_grid(net)
    k = dynamic_stiffness(net, fp.point_x_m, fp.y, freq, velocity)[fp.stable]
    if k.shape[0] == 0:
        return []
    return negative_bands(freq, k.imag.min(axis=0))


def _k_grid(net: NarxNet) -> np.ndarray:
    nyquist = 0.5 / net.dt_s
    return np.linspace(nyquist / K_POINTS, nyquist, K_POINTS)


# ----- the whole certificate -----------------------------------------------------------------
def _hold_entry(net, fp, gh, run, i, ref_n, bands) -> dict:
    idx = fp.of_hold(i)
    static = None if run.reached is None else float(fp.force_n[idx[run.reached]])
    ref = float(ref_n[i])
    wrong = wrong_sign(float(fp.x_m[i]), static, ref)
    off = static is not None and float(static_margin(static, ref, FORCE_FLOOR_N)) < 0
    g = gh.hold == i
    return {
        "x_m": float(fp.x_m[i]),
        "fixed_points": [
            {
                "force_n": float(fp.force_n[p]),
                "spectral_radius": float(fp.spectral_radius[p]),
                "stable": bool(fp.stable[p]),
            }
            for p in idx
        ],
        "reached": run.reached,
        "departs": run.departs,
        "departure_s": run.departure_s,
        "departure_observed": run.observed if run.departs else None,
        "departs_from": run.departs_from,
        "linger_force_n": run.linger_force_n,
        "oscillates": run.oscillates,
        "static_force_n": static,
        "reference_static_force_n": ref if np.isfinite(ref) else None,
        "static_error_n": None if static is None or not np.isfinite(ref) else static - ref,
        "wrong_sign": bool(wrong),
        "static_off": bool(off),
        "ghosts": [
            {"force_n": float(net.force_n(fp.x_m[i], y)), "passage_s": float(s)}
            for y, s in zip(gh.y[g], gh.passage_s[g], strict=True)
        ],
        "non_passive_bands_hz": [list(b) for b in bands],
        "unresolved_cells": int(fp.unresolved[i]),
    }


def _reached_bands(net, fp, runs, velocity) -> list[list[tuple[float, float]]]:
    """Im K < 0 bands about the fixed point each hold's free run reaches."""
    pts = [(i, fp.of_hold(i)[r.reached]) for i, r in enumerate(runs) if r.reached is not None]
    out: list[list[tuple[float, float]]] = [[] for _ in runs]
    if not pts:
        return out
    hold, p = np.array(pts).T
    freq = _k_grid(net)
    imk = dynamic_stiffness(net, fp.point_x_m[p], fp.y[p], freq, velocity).imag
    for row, i in enumerate(hold):
        out[int(i)] = negative_bands(freq, imk[row])
    return out


def _passivity(model, reference, net, opts: CertifyOptions) -> list[dict]:
    freq = _k_grid(net)
    ref_freq = np.array(opts.reference_freq_hz)
    entries = []
    fp = fixed_points(net, np.array(opts.passivity_holds_m, dtype=np.float64))
    for i, x0 in enumerate(fp.x_m):
        idx = [p for p in fp.of_hold(i) if fp.stable[p]]
        k = dynamic_stiffness(net, fp.point_x_m[idx], fp.y[idx], freq, opts.velocity)
        k_ref = (
            np.full(ref_freq.size, np.nan + 0j)
            if reference is None
            else sine_stiffness(reference, float(x0), ref_freq, opts.reference_amplitude_m)
        )
        entries.append(
            {
                "x_m": float(x0),
                "fixed_points": [
                    {
                        "force_n": float(fp.force_n[p]),
                        "non_passive_bands_hz": [list(b) for b in negative_bands(freq, kk.imag)],
                    }
                    for p, kk in zip(idx, k, strict=True)
                ],
                "frequency_hz": freq,
                "im_k_n_per_m": k.imag,
                "re_k_n_per_m": k.real,
                "reference_frequency_hz": ref_freq,
                "reference_im_k_n_per_m": k_ref.imag,
                "reference_re_k_n_per_m": k_ref.real,
                "reference_negative_bands_hz": [
                    list(b) for b in negative_bands(ref_freq, k_ref.imag)
                ],
            }
        )
    return entries


def _energy(model, reference, opts: CertifyOptions) -> dict:
    freq = np.array(opts.energy_freq_hz)
    fires = en.energy_fires(model, reference, freq, np.array(opts.energy_amplitudes_m))
    return {
        "frequency_hz": freq,
        "amplitudes_m": list(opts.energy_amplitudes_m),
        "fires": fires,
        "bands_hz": [[list(b) for b in en.firing_bands(freq, row)] for row in fires],
    }


def _work_units(opts: CertifyOptions, dt: float) -> dict[str, float]:
    """Relative cost of each stage, in simulated samples (for the time-left estimate)."""
    hold = opts.holds * (opts.hold_s + 1.0) / dt
    sine = len(opts.passivity_holds_m) * len(opts.reference_freq_hz) * (SETTLE_S + SINE_S + 1) / dt
    scan = 2 * len(opts.energy_amplitudes_m) * len(opts.energy_freq_hz) * (en.DURATION_S + 1) / dt
    return {
        "fixed points": opts.holds * 2000.0,
        "free runs": hold,
        "reference holds": 1.5 * hold,
        "passivity": 1.5 * sine,
        "energy scan": 1.2 * scan,
    }


def certify(
    model,
    reference,
    options: CertifyOptions | None = None,
    progress: Callable[[str, float], None] | None = None,
) -> Certificate:
    """The certificate of ``model`` (nn or hybrid) against ``reference`` over the stroke;
    ``reference`` None: the reference-free parts only (no static comparison, no reference K).

    ``progress(stage, fraction_done)`` is called before each stage.
    """
    opts = options or CertifyOptions()
    opts.check()
    net = narx_net(model)
    if reference is not None and abs(reference.dt - net.dt_s) > 1e-9 * net.dt_s:
        raise CertifyError(
            f"model runs at {1 / net.dt_s:.6g} Hz, reference at {1 / reference.dt:.6g} Hz; "
            "give a reference sampled at the model's rate"
        )
    units = _work_units(opts, net.dt_s)
    total, done, timing = sum(units.values()), 0.0, {}

    def stage(name: str) -> float:
        if progress is not None:
            progress(name, done / total)
        return time.perf_counter()

    t = stage("fixed points")
    x = np.unique(np.r_[np.linspace(-opts.stroke_m, opts.stroke_m, opts.holds), opts.extra_holds_m])
    fp = fixed_points(net, x)
    gh = ghosts(net, x)
    fo = folds(net, fp)
    timing["fixed_points_s"], done = time.perf_counter() - t, done + units["fixed points"]
    t = stage("free runs")
    runs, _, _ = free_runs(model, net, fp, gh, opts.hold_s)
    bands = _reached_bands(net, fp, runs, opts.velocity)
    timing["free_runs_s"], done = time.perf_counter() - t, done + units["free runs"]
    t = stage("reference holds")
    ref_static = (  # no reference: no comparison (off band); wrong sign against x itself
        np.full(x.size, np.nan)
        if reference is None
        else reference_static_force(reference, x, opts.hold_s)
    )
    timing["reference_holds_s"], done = time.perf_counter() - t, done + units["reference holds"]
    t = stage("passivity")
    pas = _passivity(model, reference, net, opts)
    timing["passivity_s"], done = time.perf_counter() - t, done + units["passivity"]
    t = stage("energy scan")
    scan = _energy(model, reference, opts)
    timing["energy_scan_s"] = time.perf_counter() - t
    holds = [_hold_entry(net, fp, gh, r, i, ref_static, bands[i]) for i, r in enumerate(runs)]
    doc = _document(net, opts, holds, fo, pas, scan, timing)
    doc["settings"]["wrong_sign_against"] = (
        "the deflection (no reference: a passive bushing's static force has the sign of x)"
        if reference is None
        else "the reference's static force"
    )
    return Certificate(doc, net, fp, gh, fo, runs, ref_static, pas)


def _ranges(x: np.ndarray, mask: np.ndarray) -> list[list[float]]:
    """[[first x, last x], ...] of the runs of consecutive True in ``mask``."""
    out, start = [], None
    for k, m in enumerate(list(mask) + [False]):
        if m and start is None:
            start = k
        if not m and start is not None:
            out.append([float(x[start]), float(x[k - 1])])
            start = None
    return out


def _document(net, opts, holds, fo, pas, scan, timing) -> dict:
    x = np.array([h["x_m"] for h in holds])
    wrong = np.array([h["wrong_sign"] for h in holds])
    departs = np.array([h["departs"] for h in holds])
    stable_end = np.array(
        [
            h["reached"] is not None
            and h["fixed_points"][h["reached"]]["stable"]
            and not h["departs"]
            for h in holds
        ]
    )
    rho = [
        h["fixed_points"][h["reached"]]["spectral_radius"]
        for h in holds
        if h["reached"] is not None
    ]
    at_zero = [p for e in pas if e["x_m"] == 0.0 for p in e["fixed_points"]]
    non_passive = any(p["non_passive_bands_hz"] for e in pas for p in e["fixed_points"])
    summary = {
        "holds": len(holds),
        "holds_settling_stably": int(stable_end.sum()),
        "departing_holds": int(departs.sum()),
        "departing_unexplained": int(
            sum(h["departs"] and h["departs_from"] is None for h in holds)
        ),
        "oscillating_holds": int(sum(h["oscillates"] for h in holds)),
        "wrong_sign_holds": int(wrong.sum()),
        "wrong_sign_ranges_m": _ranges(x, wrong),
        "static_off_holds": int(sum(h["static_off"] for h in holds)),
        "static_off_ranges_m": _ranges(x, np.array([h["static_off"] for h in holds])),
        "folds": len(fo),
        "max_reached_spectral_radius": max(rho) if rho else None,
        "unresolved_cells": int(sum(h["unresolved_cells"] for h in holds)),
        "non_passive_bands_hz_at_rest": [b for p in at_zero for b in p["non_passive_bands_hz"]],
        "passes_holds": bool(not fo and stable_end.all() and not wrong.any()),
        "passes_passivity": not non_passive,
    }
    return {
        "model": describe(net),
        "settings": {
            "holds": opts.holds,
            "stroke_m": opts.stroke_m,
            "hold_s": opts.hold_s,
            "reference_average_s": AVERAGE_S,
            "velocity": opts.velocity,
            "sign_floor_n": SIGN_FLOOR_N,
            "static_off": "outside the divergence criterion static's band about F_ref "
            f"(bushenv.divergence.static_margin, floor {FORCE_FLOOR_N} N)",
            "reference_sine_amplitude_m": opts.reference_amplitude_m,
        },
        "summary": summary,
        "holds": holds,
        "folds": [
            {
                "x_m": f.x_m,
                "force_n": f.force_n,
                "pair_exists": "above" if f.exists_above else "below",
                "spectral_radii": list(f.radii),
            }
            for f in fo
        ],
        "passivity": {"holds": pas, "energy_scan": scan},
        "timing_s": timing,
    }
