"""Regimes a judged record holds that the identification records lack (a shift warning).

Compared per TEST against the identification records together: holds after a step (total
held time), peak deflection on each side, the 95th percentile of speed while moving, and the
displacement's frequency band (1 % .. 99 % of its spectral energy, Welch).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import signal

from bushenv.diagnose.regimes import held_after_step_mask
from bushenv.models.base import velocity_of

AMPLITUDE_MARGIN = 1.15
RATE_MARGIN = 1.5
BAND_MARGIN = 1.3
HOLD_MIN_S = 1.0
SIDE_FLOOR = 0.05  # a side reached by less than this fraction of TRAIN's peak is not a regime


def record_regimes(x: np.ndarray, dt: float) -> dict[str, float]:
    """Held time (s), peaks (m), moving speed (m/s) and band edges (Hz) of one record."""
    v = np.abs(velocity_of(x, dt))
    moving = v > 0.01 * (float(v.max()) or 1.0)
    nper = int(min(x.size, max(256, 2 ** int(np.log2(max(x.size // 4, 2))))))
    f, p = signal.welch(x - np.mean(x), fs=1.0 / dt, nperseg=nper)
    c = np.cumsum(p) / (np.sum(p) or 1.0)
    return {
        "hold_s": float(held_after_step_mask(x, dt).sum() * dt),
        "peak_pos_m": float(max(np.max(x), 0.0)),
        "peak_neg_m": float(max(-np.min(x), 0.0)),
        "speed_m_per_s": float(np.quantile(v[moving], 0.95)) if moving.any() else 0.0,
        "band_lo_hz": float(f[np.searchsorted(c, 0.01)]),
        "band_hi_hz": float(f[min(np.searchsorted(c, 0.99), f.size - 1)]),
    }


def _pooled(regs: list[dict[str, float]]) -> dict[str, float]:
    return {
        "hold_s": sum(r["hold_s"] for r in regs),
        "peak_pos_m": max(r["peak_pos_m"] for r in regs),
        "peak_neg_m": max(r["peak_neg_m"] for r in regs),
        "speed_hi_m_per_s": max(r["speed_m_per_s"] for r in regs),
        "speed_lo_m_per_s": min(r["speed_m_per_s"] for r in regs),
        "band_lo_hz": min(r["band_lo_hz"] for r in regs),
        "band_hi_hz": max(r["band_hi_hz"] for r in regs),
    }


def shift_warnings(
    train: list[tuple[np.ndarray, float]], tests: list[tuple[str, np.ndarray, float]]
) -> list[dict[str, Any]]:
    """Warnings ``{test, regime, text}`` for regimes a TEST holds that TRAIN lacks."""
    ref = _pooled([record_regimes(x, dt) for x, dt in train])
    out = []
    for name, x, dt in tests:
        r = record_regimes(x, dt)

        def warn(regime: str, text: str, name: str = name) -> None:
            out.append({"test": name, "regime": regime, "text": f"TEST {name}: {text}"})

        if r["hold_s"] >= HOLD_MIN_S and ref["hold_s"] < 0.25 * r["hold_s"]:
            warn(
                "holds_after_step",
                f"holds after a step for {r['hold_s']:.3g} s; the identification records "
                f"hold for {ref['hold_s']:.3g} s",
            )
        span = max(ref["peak_pos_m"], ref["peak_neg_m"])
        for side in ("pos", "neg"):
            lim = ref[f"peak_{side}_m"]
            peak = r[f"peak_{side}_m"]
            if peak > AMPLITUDE_MARGIN * lim and peak > SIDE_FLOOR * span:
                sign = "+" if side == "pos" else "-"
                warn(
                    "amplitude_beyond",
                    f"deflection reaches {sign}{1e3 * r[f'peak_{side}_m']:.4g} mm, beyond the "
                    f"identification records' {sign}{1e3 * lim:.4g} mm",
                )
        if r["speed_m_per_s"] > RATE_MARGIN * ref["speed_hi_m_per_s"]:
            warn(
                "rate_beyond",
                f"moves at up to {1e3 * r['speed_m_per_s']:.4g} mm/s, faster than the "
                f"identification records' {1e3 * ref['speed_hi_m_per_s']:.4g} mm/s",
            )
        elif r["speed_m_per_s"] * RATE_MARGIN < ref["speed_lo_m_per_s"]:
            warn(
                "rate_below",
                f"moves at {1e3 * r['speed_m_per_s']:.4g} mm/s, slower than the "
                f"identification records' {1e3 * ref['speed_lo_m_per_s']:.4g} mm/s",
            )
        if r["band_hi_hz"] > BAND_MARGIN * ref["band_hi_hz"]:
            warn(
                "frequency_beyond",
                f"frequencies up to {r['band_hi_hz']:.3g} Hz, beyond the identification "
                f"records' band (up to {ref['band_hi_hz']:.3g} Hz)",
            )
    return out
