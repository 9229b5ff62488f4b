"""The stroke and rate per coordinate a search over C coordinates drives (``CoordinateLimits``,
any C: each coordinate with its name and unit): a rig's (BushRig3-v0's spec,
``machine_limits``), or a user's bushing's from its records (``limits_of_records``: the one-axis
rule, 1.5 x their peak |q| and |dq/dt|); how reports show them (mm for m, mrad for rad;
``limits_text``), and a profile kept within them (``clip_coords``, ``finish_coords``). Where the
coordinates are a rig's (``machine_of``), its stroke and rate bound the limits. A one-axis
bushing's limits are its ``BushingScales`` (``bushenv.scales``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from bushenv import excitation as ex
from bushenv.scales import RECORD_MARGIN, record_range
from bushenv.search.base import SearchError
from bushenv.search.family_base import MIN_HOLD_S, _n

TARGET = "rig3"
ENV_ID = "BushRig3-v0"
COORDS = ("axial", "radial", "rotation")
SI_UNITS = ("m", "m", "rad")  # BushRig3-v0's coordinates' units
SHOWN = {"m": "mm", "rad": "mrad"}  # how reports show a unit (x 1e3)


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


UNITS = tuple(SHOWN[u] for u in SI_UNITS)  # how reports show BushRig3-v0's coordinates
RATE_UNITS = tuple(f"{u}_per_s" for u in SI_UNITS)  # and their rates (SI)


def machine_of(coords) -> str | None:
    """The rig whose stroke and rate bound limits over ``coords``: BushRig3-v0 for its
    coordinates; None (no machine) for any others."""
    return ENV_ID if tuple(coords) == COORDS else None


def _tops(machine: str | None, coords: tuple[str, ...]):
    if machine is None:
        return None
    if machine != ENV_ID or coords != COORDS:
        raise SearchError(
            f"no machine {machine} over {', '.join(coords)} (the one known: {ENV_ID} over "
            f"{', '.join(COORDS)})"
        )
    return rig3_limits()


@dataclass(frozen=True)
class CoordinateLimits:
    """Stroke and rate per coordinate a search over C coordinates drives (the ``limits`` its
    families, its ``finish`` and its shrinking take, in the evaluator's ``scales`` slot).

    Attributes
    ----------
    stroke : tuple of C floats
        Largest |q| per coordinate, in its unit (m or rad).
    rate : tuple of C floats
        Largest |dq/dt| per coordinate (m/s or rad/s).
    source : str
        Where these numbers come from, for reports.
    records_peak : tuple of C floats or None
        Largest |q| per coordinate of the records the limits were taken from; None when they
        come from none.
    coords : tuple of C str
        The coordinates' names, in array order (default: BushRig3-v0's).
    units : tuple of C str
        Each coordinate's SI unit, ``m`` or ``rad``.
    machine : str or None
        The rig whose stroke and rate bound these (``machine_of(coords)`` by default); None:
        no machine, any positive value.
    """

    stroke: tuple[float, ...]
    rate: tuple[float, ...]
    source: str = "BushRig3-v0's stroke and rate (the machine's)"
    records_peak: tuple[float, ...] | None = None
    coords: tuple[str, ...] = COORDS
    units: tuple[str, ...] = SI_UNITS
    machine: str | None = ""  # "": the rig of ``coords`` (``machine_of``)

    def __post_init__(self) -> None:
        coords, units = tuple(self.coords), tuple(self.units)
        if not coords or len(units) != len(coords):
            raise SearchError(f"limits need one unit per coordinate: {coords} in {units}")
        bad = [u for u in units if u not in SHOWN]
        if bad:
            raise SearchError(f"a coordinate's unit is m or rad, got {bad[0]!r}")
        machine = machine_of(coords) if self.machine == "" else self.machine
        object.__setattr__(self, "coords", coords)
        object.__setattr__(self, "units", units)
        object.__setattr__(self, "machine", machine)
        tops = _tops(machine, coords)
        for name, vals, k, rate in (("stroke", self.stroke, 1e3, False),
                                    ("rate", self.rate, 1.0, True)):  # fmt: skip
            if len(vals) != len(coords):
                raise SearchError(
                    f"{name} needs {len(coords)} values ({', '.join(coords)}): {tuple(vals)}"
                )
            top = None if tops is None else tops[1 if rate else 0]
            for i, (c, u, v) in enumerate(zip(coords, units, vals, strict=True)):
                shown = f"{u}/s" if rate else SHOWN[u]
                t = np.inf if top is None else float(top[i])
                if not (np.isfinite(v) and 0 < v <= t * (1 + 1e-9)):
                    within = "> 0" if top is None else f"in (0, {k * t:.6g}] {shown} ({machine}'s)"
                    raise SearchError(f"the {c} {name} must be {within}, got {k * v:.6g} {shown}")
        if self.records_peak is not None and len(self.records_peak) != len(coords):
            raise SearchError(f"records_peak needs {len(coords)} values: {self.records_peak}")

    @property
    def n_coords(self) -> int:
        return len(self.coords)

    def to_json(self) -> dict:
        """Per coordinate with its unit in the key (mm or mrad; m_per_s or rad_per_s), and the
        source."""
        out: dict = {}
        for i, (c, u) in enumerate(zip(self.coords, self.units, strict=True)):
            out[c] = {f"stroke_{SHOWN[u]}": round(1e3 * self.stroke[i], 6),
                      f"rate_{u}_per_s": round(self.rate[i], 6)}  # fmt: skip
            if self.records_peak is not None:
                out[c][f"records_peak_{SHOWN[u]}"] = round(1e3 * self.records_peak[i], 6)
        out["source"] = self.source
        return out


@lru_cache(maxsize=1)
def machine_limits() -> CoordinateLimits:
    """BushRig3-v0's stroke and rate as ``CoordinateLimits``."""
    stroke, rate = rig3_limits()
    return CoordinateLimits(tuple(stroke.tolist()), tuple(rate.tolist()))


def limits_arrays(lim=None) -> tuple[np.ndarray, np.ndarray]:
    """(stroke, rate) (C,) arrays of ``lim`` when it is ``CoordinateLimits``, else
    BushRig3-v0's."""
    if isinstance(lim, CoordinateLimits):
        return np.array(lim.stroke), np.array(lim.rate)
    return rig3_limits()


def limits_of_records(
    q: list[np.ndarray], dt: float, what: str, coords=COORDS, units=SI_UNITS
) -> CoordinateLimits:
    """Limits from (T, C) displacement records ``q`` over ``coords`` (in ``units``): per
    coordinate their largest |q| and |dq/dt| times ``scales.RECORD_MARGIN`` (the one-axis rule,
    ``scales.scales_of_card``), within the coordinates' machine (``machine_of``) if any. A
    coordinate the records never move keeps the machine's limits (the source says so; with no
    machine, ``SearchError``). ``what`` names the records in the source."""
    coords, units = tuple(coords), tuple(units)
    tops = _tops(machine_of(coords), coords)
    top_stroke, top_rate = (np.inf, np.inf) if tops is None else tops
    peak = np.max([np.max(np.abs(a), axis=0) for a in q], axis=0)
    speed = np.max([np.max(np.abs(np.diff(a, axis=0)), axis=0) / dt for a in q], axis=0)
    moved = peak > 0
    if tops is None and not moved.all():
        still = ", ".join(c for c, m in zip(coords, moved, strict=True) if not m)
        raise SearchError(f"{what} never move {still} and no machine bounds it: give its range")
    stroke, rate = record_range(peak, speed, top_stroke, top_rate)
    stroke, rate = np.where(moved, stroke, top_stroke), np.where(moved, rate, top_rate)
    seen = ", ".join(
        f"{c} {1e3 * p:.4g} {SHOWN[u]} at {v:.4g} {u}/s"
        for c, u, p, v in zip(coords, units, peak, speed, strict=True)
    )
    source = f"{RECORD_MARGIN:g} x the peak |q| and |dq/dt| of {what} ({seen})"
    if not moved.all():
        still = ", ".join(c for c, m in zip(coords, moved, strict=True) if not m)
        source += f"; {still}: never moved there, the machine's"
    return CoordinateLimits(
        tuple(stroke.tolist()), tuple(rate.tolist()), source, tuple(peak.tolist()), coords, units
    )


def limits_text(limits: dict) -> str:
    """``axial +-3 mm at 0.2 m/s, ...`` from ``CoordinateLimits.to_json``, and the source."""
    parts = []
    for c, row in limits.items():
        if not isinstance(row, dict):
            continue
        (stroke_key,) = (k for k in row if k.startswith("stroke_"))
        (rate_key,) = (k for k in row if k.startswith("rate_"))
        unit, rate = stroke_key[len("stroke_") :], rate_key[len("rate_") :].replace("_per_s", "/s")
        parts.append(f"{c} +-{row[stroke_key]:.4g} {unit} at {row[rate_key]:.4g} {rate}")
    return f"{', '.join(parts)} ({limits['source']})"


def clip_coords(q: np.ndarray, dt: float, lim=None) -> np.ndarray:
    """Each coordinate clipped to its stroke and slew-limited to its rate (``limits_arrays``)."""
    stroke, rate = limits_arrays(lim)
    q = np.asarray(q, dtype=np.float64)
    cols = [ex.clip_to_limits(q[:, i], dt, stroke[i], rate[i]) for i in range(stroke.size)]
    return np.stack(cols, axis=1)


def finish_coords(q: np.ndarray, dt: float, max_s: float, lim=None) -> np.ndarray:
    """Start at rest, trim to ``max_s`` keeping a final hold, keep the limits
    (``limits_arrays``)."""
    c = limits_arrays(lim)[0].size
    q = np.asarray(q, dtype=np.float64).reshape(-1, c)
    if q.shape[0] == 0 or np.any(q[0] != 0.0):
        q = np.concatenate([np.zeros((1, c)), q])
    n_max = _n(max_s, dt)
    if q.shape[0] > n_max:
        n_hold = _n(MIN_HOLD_S, dt)
        last = q[n_max - n_hold - 1 : n_max - n_hold]
        q = np.concatenate([q[: n_max - n_hold], np.repeat(last, n_hold, axis=0)])
    q = clip_coords(q, dt, lim)
    q[0] = 0.0
    return q
