"""Hardening: a nonlinear elastic backbone of any monotone shape, stiffening or softening."""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.diagnose.effects.base import Effect, Scales, Signals

KNOTS = (0.25, 0.5, 0.8)  # fractions of the largest deflection
RICH_KNOTS = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)  # the richest form's
GRID = 4001  # points of the tangent's integral table
EXAMPLE_GROWTH = 1.5  # tangent 2.5 k at the last knot: about 78 % more force at the top


def _knots(scales: Scales) -> tuple[float, float, float]:
    """Knots u1 < u2 < u3 (m): fractions KNOTS of the largest deflection on either side.

    Fractions of the range, not quantiles: a held step would pile quantiles onto one level.
    """
    top = max([q[-1] for q in (scales.x_pos, scales.x_neg) if q] or [scales.sigma_x])
    return tuple(f * max(top, 1e-12) for f in KNOTS)


def tangent_shapes(s: np.ndarray, scales: Scales) -> np.ndarray:
    """(len(s), 6) tangent-stiffness shapes at |x| = ``s`` (dimensionless), both sides alike.

    Hats peaking at 0, u1 and u2; a shape rising from u2 to 1 at u3 that stays at 1 beyond;
    and the growth (s/u3)^2, (s/u3)^4 (the tangent of a cubic and a quintic term). Beyond
    the identification range the tangent keeps its last value or stiffens polynomially;
    with weights >= 0 it stays >= 0.
    """
    u1, u2, u3 = _knots(scales)
    r = s / u3
    return np.stack(
        [
            np.interp(s, [0.0, u1], [1.0, 0.0]),
            np.interp(s, [0.0, u1, u2], [0.0, 1.0, 0.0]),
            np.interp(s, [u1, u2, u3], [0.0, 1.0, 0.0]),
            np.interp(s, [u1, u2, u3], [0.0, 0.0, 1.0]),
            r * r,
            r**4,
        ],
        axis=1,
    )


def _integrated(mag: np.ndarray, scales: Scales) -> np.ndarray:
    """int_0^|x| of each tangent shape, by a fine table (trapezoid) read by interpolation."""
    top = max(float(mag.max()) if mag.size else 0.0, 1e-12)
    s = np.linspace(0.0, top, GRID)
    h = tangent_shapes(s, scales)
    table = np.concatenate([np.zeros((1, h.shape[1])), np.cumsum((h[1:] + h[:-1]) / 2, axis=0)])
    table *= s[1] - s[0]
    return np.stack([np.interp(mag, s, table[:, j]) for j in range(h.shape[1])], axis=1)


def _ramp_integral(mag: np.ndarray, a: float, b: float | None) -> np.ndarray:
    """int_0^mag of a tangent that rises linearly from 0 at ``a`` to 1 at ``b`` and stays 1
    (``b`` == ``a``: a step at ``a``), in m."""
    if b is None or b <= a:
        return np.maximum(mag - a, 0.0)
    u = np.clip(mag, a, b)
    return (u - a) ** 2 / (2 * (b - a)) + np.maximum(mag - b, 0.0)


def _two_sided(scales: Scales) -> bool:
    return bool(scales.x_pos) and bool(scales.x_neg)


class Hardening(Effect):
    """The elastic force as a monotone function of x, replacing the linear spring ``k x``.

    Its tangent stiffness is a non-negative combination of shapes of ``|x|``: hats on knots
    at 0, 25, 50 and 80 % of the identification records' largest deflection, constant
    beyond the last knot, and a growth ``(x/x80)^2``, ``(x/x80)^4`` -- the same on both sides
    (what tension teaches extrapolates to compression), plus, when the records load both
    sides, a constant extra tangent on each side (tension and compression may differ). All
    weights are tangent stiffnesses >= 0, so the backbone is monotone whatever the fit: a
    falling tangent is a softening backbone, a rising one hardening.
    """

    name = "hardening"
    form = (
        "F(x) = int_0^x k_t(s) ds replacing k x; k_t(abs(x)) >= 0 piecewise linear on knots at "
        "0, 25, 50, 80 % of the range + (x/x80)^2, (x/x80)^4, + a constant per side"
    )
    weights = "tangent stiffnesses >= 0 (N/m): monotone, softening or stiffening"
    telling_test = (
        "a slow ramp to beyond the largest deflection so far (a force not proportional to "
        "deflection, without a loop)"
    )
    replaces_spring = True
    holds_its_law = True

    def columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        x = s.x
        cols = np.sign(x)[:, None] * _integrated(np.abs(x), scales)
        if _two_sided(scales):
            cols = np.concatenate(
                [cols, np.maximum(x, 0.0)[:, None], np.minimum(x, 0.0)[:, None]], axis=1
            )
        return cols

    def rich_columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        """Tangent hats on knots every 10 % of the range, growth up to (x/x90)^6, and, when
        both sides are loaded, each side's own constant and quadratic growth of the tangent:
        any monotone backbone, asymmetric too (all weights tangent stiffnesses >= 0)."""
        x = s.x
        top = max([q[-1] for q in (scales.x_pos, scales.x_neg) if q] or [scales.sigma_x])
        k = [0.0] + [f * max(top, 1e-12) for f in RICH_KNOTS]
        mag = np.abs(x)
        cols = [mag - _ramp_integral(mag, 0.0, k[1])]  # tangent 1 at 0, falling to 0 at k1
        for i in range(1, len(k) - 1):  # hats rising from k[i-1] to k[i], falling to k[i+1]
            cols.append(_ramp_integral(mag, k[i - 1], k[i]) - _ramp_integral(mag, k[i], k[i + 1]))
        cols.append(_ramp_integral(mag, k[-2], k[-1]))  # the plateau beyond the last knot
        r = mag / k[-1]
        cols += [k[-1] * r**3 / 3, k[-1] * r**5 / 5, k[-1] * r**7 / 7]
        out = np.sign(x)[:, None] * np.stack(cols, axis=1)
        if _two_sided(scales):
            for side in (np.maximum(x, 0.0), np.minimum(x, 0.0)):
                extra = np.stack([side, side**3 / (3 * k[-1] ** 2)], axis=1)
                out = np.concatenate([out, extra], axis=1)
        return out

    def example(self, scales: Scales, k_n_per_m: float) -> tuple[Any, np.ndarray]:
        """The spring k (the hats and the plateau sum to a constant tangent) plus a
        quadratic growth of the tangent: a cubic hardening, alike on both sides."""
        w = np.zeros(6 + 2 * _two_sided(scales))
        w[:4] = k_n_per_m
        w[4] = EXAMPLE_GROWTH * k_n_per_m
        return None, w

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        u1, u2, u3 = _knots(scales)
        out: dict[str, Any] = {}
        kinds = []
        for i, (side, q) in enumerate((("positive", scales.x_pos), ("negative", scales.x_neg))):
            if not q:
                continue
            pts = np.array([0.0, u1, u2, u3, q[-1], 1.5 * q[-1]])
            k = tangent_shapes(pts, scales) @ w[:6]
            if _two_sided(scales):
                k = k + w[6 + i]
            out[f"{side}_side"] = [
                {"deflection_m": float(p), "tangent_stiffness_n_per_m": float(kk)}
                for p, kk in zip(pts, k, strict=True)
            ]
            ratio = k[4] / k[0] if k[0] > 0 else np.inf
            kinds.append("hardening" if ratio > 1.05 else "softening" if ratio < 0.95 else "linear")
        out["kind"] = "+".join(dict.fromkeys(kinds)) if kinds else "linear"
        return out
