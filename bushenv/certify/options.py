"""The settings of a certificate (``certify``) and the holds they give, for C coordinates."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.certify.holds import HOLD_S
from bushenv.certify.network import CertifyError


@dataclass(frozen=True)
class CertifyOptions:
    """Settings of :func:`certify` (SI units: m, rad, s).

    ``span``: the holds' half-width per coordinate (C,); empty: ``stroke_m`` (one coordinate).
    ``holds``: held deflections in all (over C > 1 coordinates ``per_coordinate(holds, C)``
    per coordinate). ``extra_holds_m``: one coordinate's displacements added to the grid.
    ``passivity_holds_m``: one coordinate's holds about which K is computed; over C > 1, rest
    and +- ``passivity_fraction`` of the span along each coordinate.
    """

    holds: int = 201
    extra_holds_m: tuple[float, ...] = ()
    stroke_m: float = 12.5e-3  # the machine's +-12.5 mm (seed 002 Table 1)
    span: tuple[float, ...] = ()
    hold_s: float = HOLD_S
    velocity: str = "central"
    passivity_holds_m: tuple[float, ...] = (-4e-3, -1e-3, 0.0, 1e-3, 4e-3)
    passivity_fraction: float = 0.5
    reference_amplitude_m: float = 0.1e-3
    reference_freq_hz: tuple[float, ...] = tuple(float(f) for f in np.arange(2.0, 101.0, 4.0))
    energy_amplitudes_m: tuple[float, ...] = (0.25e-3, 0.5e-3, 1e-3, 2e-3)
    energy_freq_hz: tuple[float, ...] = tuple(float(f) for f in np.arange(2.0, 81.0, 2.0))

    def spans(self, coords: int) -> np.ndarray:
        """(C,) the holds' half-widths, checked."""
        span = np.array(self.span if self.span else (self.stroke_m,) * coords, dtype=np.float64)
        if span.size != coords or not np.all(np.isfinite(span) & (span > 0)):
            what = "stroke must be a positive length" if coords == 1 else "span must be"
            raise CertifyError(f"{what} ({coords} positive numbers), got {tuple(span)}")
        return span

    def check(self, coords: int = 1) -> None:
        if self.holds < 3:
            raise CertifyError(f"holds must be >= 3 (a grid over the stroke), got {self.holds}")
        self.spans(coords)
        if not (np.isfinite(self.hold_s) and self.hold_s >= 2.0):
            raise CertifyError(f"hold must last at least 2 s, got {self.hold_s!r} s")
        if not np.all(np.isfinite(self.extra_holds_m)):
            raise CertifyError(f"extra holds must be finite, got {self.extra_holds_m}")
        if not (np.isfinite(self.reference_amplitude_m) and self.reference_amplitude_m > 0):
            raise CertifyError(f"sine amplitude must be positive, got {self.reference_amplitude_m}")


def per_coordinate(holds: int, coords: int) -> int:
    """Holds per coordinate for about ``holds`` holds in all: ``holds`` for one coordinate;
    over several, odd (rest among them) and >= 3."""
    if coords == 1:
        return holds
    n = max(3, int(round(holds ** (1.0 / coords))))
    return n if n % 2 else n + 1


def hold_axes(opts: CertifyOptions, coords: int) -> list[np.ndarray]:
    """The grid's values per coordinate (one coordinate: with the extra holds)."""
    n = per_coordinate(opts.holds, coords)
    axes = [np.linspace(-s, s, n) for s in opts.spans(coords)]
    if coords == 1:
        axes[0] = np.unique(np.r_[axes[0], opts.extra_holds_m])
    return axes


def passivity_holds(opts: CertifyOptions, coords: int) -> np.ndarray:
    """(M, C) the holds about which K is computed (see :class:`CertifyOptions`)."""
    if coords == 1:
        return np.array(opts.passivity_holds_m, dtype=np.float64)[:, None]
    out = [np.zeros(coords)]
    for i, s in enumerate(opts.spans(coords)):
        for sign in (1.0, -1.0):
            q = np.zeros(coords)
            q[i] = sign * opts.passivity_fraction * s
            out.append(q)
    return np.array(out)


def span_text(coords, units, span) -> str:
    """``+-3 mm`` for one coordinate, ``axial +-3 mm, ..., rotation +-75 mrad`` over several
    (what ``bushenv certify`` and an FMU's certificate say of the holds' span)."""
    parts = [
        f"+-{v * 1e3:.4g} {'mrad' if u == 'rad' else 'mm'}"
        for u, v in zip(units, span, strict=True)
    ]
    if len(parts) == 1:  # a lone coordinate needs no name
        return parts[0]
    return ", ".join(f"{c} {p}" for c, p in zip(coords, parts, strict=True))
