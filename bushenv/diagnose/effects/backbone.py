"""Hardening: a nonlinear elastic backbone of any monotone shape, stiffening or softening."""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.diagnose.effects.base import Effect, Scales, Signals

KNOT_QUANTILES = (0.3, 0.6, 0.9)  # of |x| on each side (Scales keeps 0.3, 0.6, 0.9, 1.0)
BASIS_PER_SIDE = 5
GRID = 4001  # points of the tangent's integral table


def _knots(q: tuple[float, ...]) -> tuple[float, float, float, float]:
    """(u1, u2, u3, L): knots (m, strictly increasing) and the decay length beyond u3."""
    u1, u2, u3, umax = q
    u3 = max(u3, 1e-12)
    u2 = float(np.clip(u2, 0.4 * u3, 0.85 * u3))
    u1 = float(np.clip(u1, 0.15 * u3, 0.8 * u2))
    return u1, u2, u3, max(umax - u3, 0.25 * u3)


def tangent_basis(s: np.ndarray, q: tuple[float, ...]) -> np.ndarray:
    """(len(s), 5) tangent-stiffness shapes of one side at |x| = ``s`` (dimensionless).

    Hats peaking at u1 and u2, and three shapes that rise from u2 to 1 at u3 and then stay
    at 1, grow linearly, or decay exponentially (length L): beyond the identification range
    the tangent may keep its value, stiffen or soften, and with weights >= 0 it stays >= 0.
    """
    u1, u2, u3, length = _knots(q)
    rise = np.interp(s, [u1, u2, u3], [0.0, 0.0, 1.0])
    beyond = np.maximum(s - u3, 0.0) / length
    return np.stack(
        [
            np.interp(s, [0.0, u1, u2], [0.0, 1.0, 0.0]),
            np.interp(s, [u1, u2, u3], [0.0, 1.0, 0.0]),
            rise,
            rise + beyond,
            rise * np.exp(-beyond),
        ],
        axis=1,
    )


def _shared_tangent(s: np.ndarray, q: tuple[float, ...]) -> np.ndarray:
    """The tangent shape at 0 shared by both sides: 1 at 0, 0 from u1 (1 everywhere for a
    side the records never reach, which then continues with the tangent at 0)."""
    if not q:
        return np.ones_like(s)
    return np.interp(s, [0.0, _knots(q)[0]], [1.0, 0.0])


def _integrated(mag: np.ndarray, tangents, q) -> np.ndarray:
    """int_0^|x| of each tangent shape, by a fine table (trapezoid) read by interpolation."""
    top = max(float(mag.max()) if mag.size else 0.0, 1e-12)
    s = np.linspace(0.0, top, GRID)
    h = tangents(s, q)
    h = h[:, None] if h.ndim == 1 else h
    table = np.concatenate([np.zeros((1, h.shape[1])), np.cumsum((h[1:] + h[:-1]) / 2, axis=0)])
    table *= s[1] - s[0]
    return np.stack([np.interp(mag, s, table[:, j]) for j in range(h.shape[1])], axis=1)


class Hardening(Effect):
    """The elastic force as a monotone function of x, replacing the linear spring ``k x``.

    Its tangent stiffness is a non-negative combination of shapes on knots at 0 and at the
    30, 60 and 90 % quantiles of the identification records' deflection, on each side
    (tension and compression) separately; beyond the 90 % knot it may stay, stiffen or
    soften (extrapolation beyond the identification range). All weights are tangent
    stiffnesses >= 0, so the backbone is monotone whatever the fit: a falling tangent is a
    softening backbone, a rising one hardening. A side the records never reach continues
    with the tangent at 0.
    """

    name = "hardening"
    form = (
        "F(x) = int_0^x k_t(s) ds replacing k x; k_t >= 0 piecewise linear on knots 0, x30, "
        "x60, x90 per side, then constant, growing or decaying"
    )
    weights = "tangent stiffnesses >= 0 (N/m): monotone, softening or stiffening"

    replaces_spring = True

    def columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        x = s.x
        cols = np.zeros((x.size, self.columns_count(shape, scales)))
        j = 1
        for q, on in ((scales.x_pos, x > 0), (scales.x_neg, x < 0)):
            mag = np.abs(x[on])
            sign = np.sign(x[on])
            cols[on, 0] = sign * _integrated(mag, _shared_tangent, q)[:, 0]
            if q:
                cols[on, j : j + BASIS_PER_SIDE] = sign[:, None] * _integrated(
                    mag, tangent_basis, q
                )
                j += BASIS_PER_SIDE
        return cols

    def columns_count(self, shape: Any, scales: Scales) -> int:
        return 1 + BASIS_PER_SIDE * (bool(scales.x_pos) + bool(scales.x_neg))

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        out: dict[str, Any] = {"tangent_stiffness_at_0_n_per_m": float(w[0])}
        kinds = []
        j = 1
        for side, q in (("positive", scales.x_pos), ("negative", scales.x_neg)):
            if not q:
                continue
            u1, u2, u3, _ = _knots(q)
            pts = np.array([0.0, u1, u2, u3, q[3], 1.5 * q[3]])
            k = w[0] * _shared_tangent(pts, q) + tangent_basis(pts, q) @ w[j : j + BASIS_PER_SIDE]
            j += BASIS_PER_SIDE
            out[f"{side}_side"] = [
                {"deflection_m": float(p), "tangent_stiffness_n_per_m": float(kk)}
                for p, kk in zip(pts, k, strict=True)
            ]
            ratio = k[4] / k[0] if k[0] > 0 else np.inf
            kinds.append("hardening" if ratio > 1.05 else "softening" if ratio < 0.95 else "linear")
        out["kind"] = "+".join(dict.fromkeys(kinds)) if kinds else "linear"
        return out
