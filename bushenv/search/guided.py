"""The certificate searcher: excitations a model's certificates say are its weakest.

For a NARX model (nn, hybrid) the hold certificate (``bushenv.certify``) gives, for every held
displacement, the model's static force and how stable it is there; the passivity certificate
the frequency bands where the model generates energy at small amplitude. The searcher turns
them into profiles of the target's own families, most promising first:

1. steps to the holds whose static force lies furthest outside the static criterion's band
   about the reference's static curve, or whose attractor is least stable (near a fold the
   free run lingers, then departs, as the papers' NN did 7.3 s after its step);
2. sines in the non-passive bands, about rest and about held offsets, from small to large
   amplitudes (the energy criterion needs cycles, and large amplitudes saturate the tanh units);
3. then, with the budget left, jittered copies of the best profiles so far.

For a model the certificates cannot read (not a NARX network) the same families are swept
systematically: steps over the stroke, sines over frequency and amplitude.
"""

from __future__ import annotations

import math

import numpy as np

from bushenv import excitation as ex
from bushenv.certify import CertifyError, narx_net
from bushenv.certify.certificate import non_passive_bands, stability_margin
from bushenv.certify.fixed_points import fixed_points
from bushenv.divergence import static_curve, static_margin
from bushenv.search.base import SearchContext, Searcher, SearchError

HOLD_GRID = 81  # held displacements the certificate reads over the stroke
SINE_AMPLITUDES_M = (0.25e-3, 0.5e-3, 1e-3, 2e-3)
SINE_OFFSETS = (0.0, -0.3, 0.3)  # fractions of the stroke
FREQS_PER_BAND = 4
SWEEP_FREQS_HZ = (1.0, 3.0, 10.0, 20.0, 35.0, 45.0, 55.0, 70.0, 80.0)
JITTER = 0.05  # unit-cube std of the copies made once the proposals are spent


def _unit(value: float, lo: float, hi: float) -> float:
    return float(np.clip((value - lo) / (hi - lo), 0.0, 1.0)) if hi > lo else 0.0


def step_coordinates(x_m: float, stroke_m: float) -> np.ndarray:
    """The ``step`` family's unit-cube point of a step to ``x_m`` held as long as it can be."""
    return np.array([_unit(x_m, -stroke_m, stroke_m), 0.0, 0.0, 1.0])


def sine_coordinates(freq_hz: float, amp_m: float, offset_m: float, lim) -> np.ndarray:
    """The ``sine`` family's unit-cube point of a sine (longest duration, 2 s hold after)."""
    vmax = lim.velocity_m_per_s * 0.98
    cap = min(lim.stroke_m, vmax / (2 * math.pi * freq_hz))
    amp = min(amp_m, cap)
    lo = min(0.1e-3, cap)
    span = lim.stroke_m - amp
    u_freq = math.log(freq_hz / ex.MIN_FREQUENCY_HZ) / math.log(
        ex.MAX_FREQUENCY_HZ / ex.MIN_FREQUENCY_HZ
    )
    u_off = 0.5 + 0.5 * offset_m / span if span > 0 else 0.5
    return np.array([u_freq, _unit(amp, lo, cap), np.clip(u_off, 0, 1), 1.0, 3 / 7])


class CertificateSearch(Searcher):
    """Profiles the model's certificates point at first (module docstring); rig only."""

    name = "certificate"

    def __init__(self, batch_size: int = 32) -> None:
        self.batch_size = int(batch_size)

    def search(self, ctx: SearchContext) -> None:
        evaluator, budget, rng, recorder = ctx.evaluator, ctx.budget, ctx.rng, ctx.recorder
        target = evaluator.target
        if not {"step", "sine"} <= set(target.family_names()):
            raise SearchError(
                f"the certificate searcher proposes bushing displacements (steps and sines); "
                f"the {target.name} target has none"
            )
        proposals = self.proposals(evaluator)
        done, best = 0, []
        while done < budget:
            n = min(self.batch_size, budget - done)
            batch = proposals[:n]
            proposals = proposals[n:]
            if len(batch) < n:  # spent: jitter the best so far
                batch += _jittered(best, n - len(batch), rng)
            if not batch:
                break
            fams = [target.family(name) for name, _ in batch]
            profiles = [
                f.profile(u, evaluator.dt, limits=evaluator.scales)
                for f, (_, u) in zip(fams, batch, strict=True)
            ]
            result = evaluator.evaluate(profiles)
            recorder.record(result, [name for name, _ in batch], [u.tolist() for _, u in batch])
            rob = result.verdict.robustness
            best = sorted(best + list(zip(rob.tolist(), batch, strict=True)), key=lambda t: t[0])
            best = best[: self.batch_size]
            done += n
            ctx.progress(f"certificate {done}/{budget} evals, best robustness {recorder.best:.3g}")

    def proposals(self, evaluator) -> list[tuple[str, np.ndarray]]:
        """(family, unit-cube point) in the order they are tried."""
        lim = evaluator.scales
        try:
            net = narx_net(evaluator.model)
        except CertifyError:
            return _sweep(lim)
        return _hold_proposals(net, evaluator) + _sine_proposals(net, lim)


def _hold_proposals(net, evaluator) -> list[tuple[str, np.ndarray]]:
    """Steps to every hold of the grid, the worst by the certificate first."""
    lim = evaluator.scales
    xs = np.linspace(-lim.stroke_m, lim.stroke_m, HOLD_GRID)
    fp = fixed_points(net, xs)
    score = stability_margin(fp)
    if evaluator.reference is not None:
        ref_x, ref_f = static_curve(evaluator.reference.copy(), lim.stroke_m)
        f_ref = np.interp(xs, ref_x, ref_f)
        worst = np.full(xs.size, np.inf)  # the held force the certificate finds least right
        for p in np.flatnonzero(fp.stable):
            i = fp.hold[p]
            margin = float(static_margin(fp.force_n[p], f_ref[i], lim.force_floor_n))
            worst[i] = min(worst[i], margin / max(abs(f_ref[i]), lim.force_floor_n))
        score = np.minimum(score, worst)
    order = np.argsort(score, kind="stable")
    return [("step", step_coordinates(float(xs[i]), lim.stroke_m)) for i in order]


def _sine_proposals(net, lim) -> list[tuple[str, np.ndarray]]:
    out = []
    for frac in SINE_OFFSETS:
        offset = frac * lim.stroke_m
        for lo, hi in non_passive_bands(net, offset):
            lo, hi = max(lo, ex.MIN_FREQUENCY_HZ), min(hi, ex.MAX_FREQUENCY_HZ)
            if hi <= lo:
                continue
            for f in np.linspace(lo, hi, FREQS_PER_BAND + 2)[1:-1]:
                out += [
                    ("sine", sine_coordinates(float(f), a, offset, lim)) for a in SINE_AMPLITUDES_M
                ]
    return out


def _sweep(lim) -> list[tuple[str, np.ndarray]]:
    """Steps over the stroke and sines over frequency and amplitude, for any model."""
    steps = [
        ("step", step_coordinates(float(x), lim.stroke_m))
        for x in np.linspace(-lim.stroke_m, lim.stroke_m, 21)
    ]
    sines = [
        ("sine", sine_coordinates(f, a, 0.0, lim))
        for f in SWEEP_FREQS_HZ
        for a in SINE_AMPLITUDES_M
    ]
    return steps + sines


def _jittered(best, n: int, rng) -> list[tuple[str, np.ndarray]]:
    if not best:
        return []
    picks = rng.integers(0, len(best), size=n)
    out = []
    for i in picks:
        name, u = best[i][1]
        out.append((name, np.clip(u + rng.normal(0.0, JITTER, u.size), 0.0, 1.0)))
    return out
