"""Is there a delay? What only a delay does: a phase lag growing linearly with frequency at
unchanged gain, on every record.

A least-squares fit in time cannot tell a delay from its look-alikes: over a band, a lag of
``d`` on ``k + i w c`` is a smaller damper and a negative mass, which short relaxation times,
a misfitted heating law or friction also give. The frequency response can: every passive
linear bushing -- spring, damper, mass, any non-negative relaxation spectrum, a constant
hysteretic loss (friction's describing function) -- is a *minimum-phase* response whose phase
follows from its gain; a delay is the one factor ``exp(-i w d)`` that adds phase and leaves
the gain alone.

Per record, the response ``H(f) = S_xF / S_xx`` on the bins where the force is coherent with
the displacement is fitted by that passive family (non-negative weights, its own per record:
a non-linear bushing's best linear approximation depends on the amplitude) with and without a
shared lag ``d``. The lag is **seen** when it removes at least ``LAG_SHARE`` of the family's
weighted misfit and the drop is significant (an F test at ``LAG_P``) on records that cover a
frequency ratio of at least ``MIN_SPAN``; seen **in part** when significant and removing at
least ``PARTIAL_SHARE`` (then a delay is neither named nor ruled out).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize, signal, stats

RESOLUTION_HZ = 0.25  # the frequency step aimed at
COHERENCE_MIN = 0.8
MIN_BINS = 12
MIN_SPAN = 3.0  # highest / lowest coherent frequency of a record that counts
LAG_SHARE = 0.3  # the lag must remove at least this share of the passive family's misfit
LAG_P = 1e-3  # ... and the drop must be significant at this level
PARTIAL_SHARE = 0.15  # a significant lag removing this much is seen in part: no answer
LAG_GRID_S = np.concatenate([[0.0], 1e-3 * np.geomspace(0.05, 60.0, 120)])


@dataclass
class LagEvidence:
    seen: bool
    partial: bool  # significant but below LAG_SHARE: neither a delay nor its absence
    delay_s: float
    misfit_share_removed: float  # 1 - SSE(d) / SSE(0)
    p_value: float
    records_used: list[str]
    text: str

    def as_dict(self) -> dict:
        return {
            "seen": self.seen,
            "partial": self.partial,
            "delay_s": self.delay_s,
            "misfit_share_removed": self.misfit_share_removed,
            "p_value": self.p_value,
            "records_used": self.records_used,
            "text": self.text,
        }


def _spectra(x: np.ndarray, y: np.ndarray, dt: float):
    """(f, S_xx, S_xy, S_yy, segments) from Hann segments spread over the whole record."""
    nper = 2 ** int(np.ceil(np.log2(1.0 / (dt * RESOLUTION_HZ))))
    nper = int(min(nper, 2 ** int(np.log2(max(x.size // 4, 64)))))
    count = max(int(np.ceil(2 * x.size / nper)) - 1, 1)
    starts = np.unique(np.round(np.linspace(0, x.size - nper, count)).astype(int))
    win = signal.get_window("hann", nper)

    def fft(a):
        segs = np.stack([a[s : s + nper] for s in starts])
        return np.fft.rfft((segs - segs.mean(axis=1, keepdims=True)) * win, axis=1)

    fx, fy = fft(x), fft(y)
    sxx = np.mean(np.abs(fx) ** 2, axis=0)
    syy = np.mean(np.abs(fy) ** 2, axis=0)
    sxy = np.mean(np.conj(fx) * fy, axis=0)
    return np.fft.rfftfreq(nper, dt), sxx, sxy, syy, starts.size


def _passive_columns(w: np.ndarray, dt: float) -> np.ndarray:
    """(n_bins, p) complex responses of the passive family: spring, damper, mass, hysteretic
    loss, Maxwell branches 3 per decade from 2 dt to 100 s."""
    taus = 2 * dt * 10.0 ** (np.arange(int(np.log10(50.0 / dt) * 3) + 1) / 3.0)
    cols = [np.ones_like(w), 1j * w, -(w**2) + 0j, 1j * np.ones_like(w)]
    cols += [1j * w * t / (1 + 1j * w * t) for t in taus]
    return np.stack(cols, axis=1)


@dataclass
class _RecordResponse:
    name: str
    w: np.ndarray  # rad/s
    h: np.ndarray  # complex response, N/m
    weight: np.ndarray  # 1 / variance of h (relative)
    cols: np.ndarray

    def misfit(self, delay_s: float) -> float:
        """Weighted SSE of the passive family fitted (weights >= 0) to H exp(+i w d)."""
        h = self.h * np.exp(1j * self.w * delay_s)
        sw = np.sqrt(self.weight)
        a = self.cols * sw[:, None]
        a = np.concatenate([a.real, a.imag])
        b = np.concatenate([(h * sw).real, (h * sw).imag])
        scale = np.sqrt(np.sum(a * a, axis=0)) + 1e-300
        _, res = optimize.nnls(a / scale, b, maxiter=50 * a.shape[1])
        return float(res**2)


def _response(name: str, x: np.ndarray, force: np.ndarray, dt: float) -> _RecordResponse | None:
    if x.size < 256:
        return None
    f, sxx, sxy, syy, nseg = _spectra(x, force, dt)
    coh = np.abs(sxy) ** 2 / np.maximum(sxx * syy, 1e-300)
    keep = (f > 0) & (coh >= COHERENCE_MIN) & (sxx >= 1e-4 * sxx.max())
    if keep.sum() < MIN_BINS:
        return None
    fk = f[keep]
    if fk.max() < MIN_SPAN * fk.min():
        return None
    h = sxy[keep] / sxx[keep]
    c = np.minimum(coh[keep], 0.999)
    var = (1 - c) / (2 * nseg * c) * np.abs(h) ** 2  # of the H1 estimate (Bendat & Piersol)
    w = 2 * np.pi * fk
    return _RecordResponse(name, w, h, 1.0 / var, _passive_columns(w, dt))


def lag_evidence(records: list[tuple[str, np.ndarray, np.ndarray, float]]) -> LagEvidence:
    """Whether the force lags the displacement by a delay (see the module docstring).

    ``records``: (name, displacement m, force N, dt s) of every record.
    """
    resp = [r for r in (_response(*rec) for rec in records) if r is not None]
    if not resp:
        return LagEvidence(False, False, 0.0, 0.0, 1.0, [], "no record has a broad coherent band")

    def total(d: float) -> float:
        return sum(r.misfit(d) for r in resp)

    sse = np.array([total(d) for d in LAG_GRID_S])
    i = int(np.argmin(sse))
    d_best, sse_best = float(LAG_GRID_S[i]), float(sse[i])
    if 0 < i < LAG_GRID_S.size - 1:
        res = optimize.minimize_scalar(
            total, bounds=(LAG_GRID_S[i - 1], LAG_GRID_S[i + 1]), method="bounded"
        )
        if res.fun < sse_best:
            d_best, sse_best = float(res.x), float(res.fun)
    sse0 = float(sse[0])
    removed = 1.0 - sse_best / sse0 if sse0 > 0 else 0.0
    n_eq = sum(2 * r.w.size for r in resp)
    dof = max(n_eq - sum(r.cols.shape[1] for r in resp) - 1, 1)
    fstat = (sse0 - sse_best) / max(sse_best / dof, 1e-300)
    p = float(stats.f.sf(fstat, 1, dof)) if d_best > 0 else 1.0
    seen = bool(d_best > 0 and removed >= LAG_SHARE and p <= LAG_P)
    partial = bool(not seen and d_best > 0 and removed >= PARTIAL_SHARE and p <= LAG_P)
    names = [r.name for r in resp]
    text = (
        f"phase lag linear in frequency at unchanged gain: a delay of {1e3 * d_best:.3g} ms "
        f"removes {100 * removed:.0f} % of what the best passive (minimum-phase) response "
        f"leaves on {', '.join(names)} (p = {p:.2g})"
    )
    if not seen:
        text = (
            f"no delay: a lag removes {100 * removed:.0f} % of what the best passive "
            f"(minimum-phase) response leaves on {', '.join(names)} (needs "
            f"{100 * LAG_SHARE:.0f} % at p <= {LAG_P:g})"
        )
    if partial:
        text = text.replace("no delay:", "a delay in part:")
    return LagEvidence(seen, partial, d_best, removed, p, names, text)
