"""The stroke and rate per coordinate a search over C coordinates drives (``Rig3Limits``): the
rig's (BushRig3-v0's spec, ``machine_limits``), or a user's bushing's from its records
(``limits_of_records``: the one-axis rule, 1.5 x their peak |q| and |dq/dt|); how reports show
them (``UNITS``: mm, mm, mrad; ``limits_text``), and a profile kept within them (``clip3``,
``finish3``). A one-axis bushing's limits are its ``BushingScales`` (``bushenv.scales``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from bushenv import excitation as ex
from bushenv.scales import RECORD_MARGIN
from bushenv.search.base import SearchError
from bushenv.search.family_base import MIN_HOLD_S, _n

TARGET = "rig3"
ENV_ID = "BushRig3-v0"
COORDS = ("axial", "radial", "rotation")


@lru_cache(maxsize=1)
def rig3_limits() -> tuple[np.ndarray, np.ndarray]:
    """BushRig3-v0's stroke and rate per coordinate (m, m, rad; m/s, m/s, rad/s)."""
    from bushenv.rigs.specs import load_spec

    kw = load_spec(ENV_ID)["kwargs"]
    stroke = np.array([float(kw["stroke"][c]) for c in COORDS])
    rate = np.array([float(kw["rate"][c]) for c in COORDS])
    stroke.setflags(write=False)
    rate.setflags(write=False)
    return stroke, rate


UNITS = ("mm", "mm", "mrad")  # how reports show each coordinate (x 1e3 of m, m, rad)
RATE_UNITS = ("m_per_s", "m_per_s", "rad_per_s")  # and its rate (SI)


@dataclass(frozen=True)
class Rig3Limits:
    """Stroke and rate per coordinate a rig3 search drives (the ``limits`` its families, its
    ``finish`` and its shrinking take, in the evaluator's ``scales`` slot).

    Attributes
    ----------
    stroke : tuple of 3 floats
        Largest |q| per coordinate: m, m, rad.
    rate : tuple of 3 floats
        Largest |dq/dt| per coordinate: m/s, m/s, rad/s.
    source : str
        Where these numbers come from, for reports.
    records_peak : tuple of 3 floats or None
        Largest |q| per coordinate of the records the limits were taken from (m, m, rad);
        None when they come from none.
    """

    stroke: tuple[float, float, float]
    rate: tuple[float, float, float]
    source: str = "BushRig3-v0's stroke and rate (the machine's)"
    records_peak: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        top_stroke, top_rate = rig3_limits()
        rates = [r.replace("_per_s", "/s") for r in RATE_UNITS]
        for name, vals, top, units, k in (("stroke", self.stroke, top_stroke, UNITS, 1e3),
                                          ("rate", self.rate, top_rate, rates, 1.0)):  # fmt: skip
            if len(vals) != 3:
                raise SearchError(f"rig3 {name} needs 3 values (axial, radial, rotation): {vals}")
            for c, v, t, u in zip(COORDS, vals, top, units, strict=True):
                if not (np.isfinite(v) and 0 < v <= t * (1 + 1e-9)):
                    raise SearchError(
                        f"the {c} {name} must be in (0, {k * t:.6g}] {u} (BushRig3-v0's), "
                        f"got {k * v:.6g} {u}"
                    )

    def to_json(self) -> dict:
        """Per coordinate with its unit in the key (mm, mm, mrad), and the source."""
        out: dict = {}
        for i, (c, u) in enumerate(zip(COORDS, UNITS, strict=True)):
            out[c] = {f"stroke_{u}": round(1e3 * self.stroke[i], 6),
                      f"rate_{RATE_UNITS[i]}": round(self.rate[i], 6)}  # fmt: skip
            if self.records_peak is not None:
                out[c][f"records_peak_{u}"] = round(1e3 * self.records_peak[i], 6)
        out["source"] = self.source
        return out


@lru_cache(maxsize=1)
def machine_limits() -> Rig3Limits:
    """BushRig3-v0's stroke and rate as ``Rig3Limits``."""
    stroke, rate = rig3_limits()
    return Rig3Limits(tuple(stroke.tolist()), tuple(rate.tolist()))


def limits3(lim=None) -> tuple[np.ndarray, np.ndarray]:
    """(stroke, rate) (3,) arrays of ``lim`` when it is ``Rig3Limits``, else the machine's."""
    if isinstance(lim, Rig3Limits):
        return np.array(lim.stroke), np.array(lim.rate)
    return rig3_limits()


def limits_of_records(q: list[np.ndarray], dt: float, what: str) -> Rig3Limits:
    """Limits from (T, 3) displacement records ``q``: per coordinate their largest |q| and
    |dq/dt| times ``scales.RECORD_MARGIN`` (the one-axis rule, ``scales.scales_of_card``),
    within the machine. A coordinate the records never move keeps the machine's limits (the
    source says so). ``what`` names the records in the source."""
    top_stroke, top_rate = rig3_limits()
    peak = np.max([np.max(np.abs(a), axis=0) for a in q], axis=0)
    speed = np.max([np.max(np.abs(np.diff(a, axis=0)), axis=0) / dt for a in q], axis=0)
    moved = peak > 0
    stroke = np.where(moved, np.minimum(RECORD_MARGIN * peak, top_stroke), top_stroke)
    rate = np.where(moved, np.minimum(RECORD_MARGIN * speed, top_rate), top_rate)
    seen = ", ".join(
        f"{c} {1e3 * p:.4g} {u} at {v:.4g} {r.replace('_per_s', '/s')}"
        for c, u, r, p, v in zip(COORDS, UNITS, RATE_UNITS, peak, speed, strict=True)
    )
    source = f"{RECORD_MARGIN:g} x the peak |q| and |dq/dt| of {what} ({seen})"
    if not moved.all():
        still = ", ".join(c for c, m in zip(COORDS, moved, strict=True) if not m)
        source += f"; {still}: never moved there, the machine's"
    return Rig3Limits(tuple(stroke.tolist()), tuple(rate.tolist()), source, tuple(peak.tolist()))


def limits_text(limits: dict) -> str:
    """``axial +-3 mm at 0.2 m/s, ...`` from ``Rig3Limits.to_json``, and the source."""
    parts = []
    for c, u, r in zip(COORDS, UNITS, RATE_UNITS, strict=True):
        row = limits[c]
        rate = r.replace("_per_s", "/s")
        parts.append(f"{c} +-{row[f'stroke_{u}']:.4g} {u} at {row[f'rate_{r}']:.4g} {rate}")
    return f"{', '.join(parts)} ({limits['source']})"


def clip3(q: np.ndarray, dt: float, lim=None) -> np.ndarray:
    """Each coordinate clipped to its stroke and slew-limited to its rate (``limits3``)."""
    stroke, rate = limits3(lim)
    q = np.asarray(q, dtype=np.float64)
    return np.stack([ex.clip_to_limits(q[:, i], dt, stroke[i], rate[i]) for i in range(3)], axis=1)


def finish3(q: np.ndarray, dt: float, max_s: float, lim=None) -> np.ndarray:
    """Start at rest, trim to ``max_s`` keeping a final hold, keep the limits (``limits3``)."""
    q = np.asarray(q, dtype=np.float64).reshape(-1, 3)
    if q.shape[0] == 0 or np.any(q[0] != 0.0):
        q = np.concatenate([np.zeros((1, 3)), q])
    n_max = _n(max_s, dt)
    if q.shape[0] > n_max:
        n_hold = _n(MIN_HOLD_S, dt)
        last = q[n_max - n_hold - 1 : n_max - n_hold]
        q = np.concatenate([q[: n_max - n_hold], np.repeat(last, n_hold, axis=0)])
    q = clip3(q, dt, lim)
    q[0] = 0.0
    return q
