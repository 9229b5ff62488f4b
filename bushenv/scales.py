"""The sizes a search and a verdict are made at, which belong to the bushing under test.

A search drives the bushing within a stroke and a velocity; a verdict resolves forces down to
a floor and knows the rig's force limit. For the built-in rubber these are the papers' test
machine (seed 002 Table 1) and the resolution argued in ``divergence.py`` (200 N). For a user's
bushing they come from the user's reference model (its static stiffness sets the floor), from
the records it was identified on (their stroke and velocity, with the papers' 50 % margin of
the n = 1.5 extrapolation record) or from flags -- in that order of priority: flags first.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from bushenv import excitation as ex
from bushenv.errors import BadInput

FORCE_FLOOR_N = 200.0  # the papers' bushing on the papers' machine (divergence.py says why)
RIG_FORCE_LIMIT_N = 25.0e3  # seed 002 Table 1, max dynamic force of the MTS test machine
FLOOR_AMPLITUDE_M = 0.5e-3  # the papers' smallest test amplitude (seed 001 §3.2.1)
RECORD_MARGIN = 1.5  # search this far beyond a record's range (the papers' n = 1.5 record)
STIFFNESS_MISMATCH = 2.0  # two models this far apart in static stiffness: different bushings
STATIC_HOLD_S = 2.0  # hold before reading a model's static force (rubber relaxes; NN settles)
STATIC_PROBE_M = 1.0e-3


class ScaleError(BadInput):
    """A scale that cannot be used (not positive, beyond the machine); names the value."""


@dataclass(frozen=True)
class BushingScales:
    """Stroke and velocity a search may drive; force floor and limit a verdict uses.

    Attributes
    ----------
    stroke_m : float
        Largest |x| a search profile reaches, m.
    velocity_m_per_s : float
        Largest |dx/dt|, m/s.
    force_floor_n : float
        Resolution of the verdicts: no relative criterion judges on a finer force scale, N.
    force_limit_n : float
        The rig's force limit, N (a model beyond it, where the reference is within, diverges).
    force_scale_n : float or None
        Typical peak force of the bushing, N: the verdicts' scale when there is no reference.
    source : str
        Where these numbers come from, for reports.
    """

    stroke_m: float = ex.MAX_DISPLACEMENT_M
    velocity_m_per_s: float = ex.MAX_VELOCITY_M_PER_S
    force_floor_n: float = FORCE_FLOOR_N
    force_limit_n: float = RIG_FORCE_LIMIT_N
    force_scale_n: float | None = None
    source: str = "the papers' test machine (seed 002 Table 1)"

    def __post_init__(self) -> None:
        for name in ("stroke_m", "velocity_m_per_s", "force_floor_n", "force_limit_n"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ScaleError(f"{name} must be a positive number, got {value!r}")
        if self.stroke_m > ex.MAX_DISPLACEMENT_M * (1 + 1e-9):
            raise ScaleError(
                f"stroke {self.stroke_m * 1e3:.4g} mm is beyond the test machine's "
                f"{ex.MAX_DISPLACEMENT_M * 1e3:.4g} mm"
            )
        if self.velocity_m_per_s > ex.MAX_VELOCITY_M_PER_S * (1 + 1e-9):
            raise ScaleError(
                f"velocity {self.velocity_m_per_s:.4g} m/s is beyond the test machine's "
                f"{ex.MAX_VELOCITY_M_PER_S:.4g} m/s"
            )

    def to_json(self) -> dict:
        return {
            "stroke_m": self.stroke_m,
            "velocity_m_per_s": self.velocity_m_per_s,
            "force_floor_n": self.force_floor_n,
            "force_limit_n": self.force_limit_n,
            "force_scale_n": self.force_scale_n,
            "source": self.source,
        }


MACHINE = BushingScales()


def static_force(model, x_m: float, hold_s: float = STATIC_HOLD_S) -> float:
    """The force ``model`` holds after a slow ramp to ``x_m`` and ``hold_s`` at it, N."""
    dt = model.dt
    ramp = np.linspace(0.0, x_m, max(2, int(round(0.2 / dt))))
    x = np.concatenate([ramp, np.full(int(round(hold_s / dt)), x_m)])
    f = model.simulate(x, np.gradient(x, dt))
    return float(f[-1])


def static_stiffness(model, x_m: float = STATIC_PROBE_M) -> float:
    """Secant static stiffness from holds at +-``x_m``, N/m (NaN if the model is not finite)."""
    up, down = static_force(model, x_m), static_force(model, -x_m)
    return (up - down) / (2 * x_m)


def stiffness_mismatch(model, reference) -> str | None:
    """A warning when the two differ in static stiffness by more than ``STIFFNESS_MISMATCH``."""
    k_m, k_r = static_stiffness(model), static_stiffness(reference)
    if not (np.isfinite(k_m) and np.isfinite(k_r)) or k_r <= 0:
        return None
    ratio = k_m / k_r
    if 1 / STIFFNESS_MISMATCH <= ratio <= STIFFNESS_MISMATCH:
        return None
    return (
        f"the model's static stiffness ({k_m / 1e3:.4g} N/mm) and the reference's "
        f"({k_r / 1e3:.4g} N/mm) differ by a factor {max(ratio, 1 / ratio):.3g}: are they models "
        "of the same bushing? (pass the reference of the bushing the model stands for)"
    )


def scales_of_reference(reference, builtin: bool) -> BushingScales:
    """The machine's scales; for a user's reference the force floor is its static force at
    the papers' smallest test amplitude (0.5 mm) -- for the papers' bushing that rule gives
    190 N (380 N/mm, seed 000 Table 1), the origin of the 200 N floor."""
    if builtin or reference is None:
        return MACHINE
    k = static_stiffness(reference)
    if not (np.isfinite(k) and k > 0):
        raise ScaleError(
            f"the reference's static stiffness is {k!r} N/m: it cannot set the force floor "
            "(give --force-floor-n)"
        )
    return replace(
        MACHINE,
        force_floor_n=k * FLOOR_AMPLITUDE_M,
        source=f"the reference's static stiffness ({k / 1e3:.4g} N/mm x 0.5 mm floor)",
    )


def record_range(peak, speed, top_stroke=np.inf, top_rate=np.inf) -> tuple[np.ndarray, np.ndarray]:
    """The range a search drives and a certificate holds over, from records' largest |q| and
    |dq/dt| (numbers, or one per coordinate): ``RECORD_MARGIN`` times each, within the
    machine's ``top_stroke`` and ``top_rate`` (none: no bound). The one rule for any number of
    coordinates (``scales_of_card``, ``search.limits.limits_of_records``)."""
    stroke = np.minimum(RECORD_MARGIN * np.asarray(peak, dtype=np.float64), top_stroke)
    rate = np.minimum(RECORD_MARGIN * np.asarray(speed, dtype=np.float64), top_rate)
    return stroke, rate


def scales_of_records(scales: BushingScales, x_m, dt: float) -> BushingScales:
    """``scales`` with stroke and velocity from measured displacement ``x_m`` (one or several
    arrays): their largest |x| and |dx/dt| times ``RECORD_MARGIN``, within the machine."""
    xs = [np.asarray(a, dtype=np.float64) for a in (x_m if isinstance(x_m, list) else [x_m])]
    peak = max(float(np.max(np.abs(a))) for a in xs)
    speed = max(float(np.max(np.abs(np.diff(a)))) / dt for a in xs if a.size > 1)
    stroke, rate = record_range(peak, speed, ex.MAX_DISPLACEMENT_M, ex.MAX_VELOCITY_M_PER_S)
    return replace(
        scales,
        stroke_m=float(stroke),
        velocity_m_per_s=float(rate),
        source=scales.source + f"; stroke and velocity 1.5 x the records' ({peak * 1e3:.3g} mm)",
    )


QUASI_STATIC_SHARE = 0.01  # displacement power at or below 1 Hz that shows static behaviour
HOLD_FOR_STATIC_S = 1.0  # a hold this long shows it too (the static criterion judges after 1 s)


def static_identified(card: dict) -> bool:
    """Whether a model card's training records show the bushing's static behaviour: holds of
    at least a second, or 1 % of the displacement's power at or below 1 Hz. A model fitted on
    records without either (a 5-150 Hz multisine, a 0.5-20 Hz random drive) extrapolates its
    static force; it cannot be the yardstick of the ``static`` criterion. A card without those
    figures (older cards) is taken at its word."""
    train = [r for r in card.get("records", []) if r.get("role") == "train"]
    if not train or any("quasi_static_share" not in r for r in train):
        return True
    return any(
        r["quasi_static_share"] >= QUASI_STATIC_SHARE or r["longest_hold_s"] >= HOLD_FOR_STATIC_S
        for r in train
    )


FLOOR_FRACTION = FLOOR_AMPLITUDE_M / ex.MAX_DISPLACEMENT_M  # 0.5 of 12.5 mm: 4 %


def has_range(card: dict | None) -> bool:
    """Whether a one-axis model card's training records state their range (older cards and
    cards of several coordinates do not: ``scales_of_card`` leaves the scales as they are)."""
    train = [r for r in (card or {}).get("records", []) if r.get("role") == "train"]
    return bool(train) and all("max_abs_displacement_m" in r for r in train)


def train_range(records: list[dict], coords) -> tuple[tuple, tuple | None] | None:
    """The training records' largest |q| and |dq/dt| per coordinate (the one-axis keys, or
    ``peak_deflection`` and ``peak_rate`` over several); None when they are not stated."""
    train = [r for r in records if r.get("role") == "train"]
    if train and all("max_abs_displacement_m" in r for r in train):
        return (
            (max(r["max_abs_displacement_m"] for r in train),),
            (max(r["max_abs_velocity_m_per_s"] for r in train),),
        )
    if not train or not all(isinstance(r.get("peak_deflection"), dict) for r in train):
        return None
    peaks = tuple(max(float(r["peak_deflection"][c]) for r in train) for c in coords)
    if not all(isinstance(r.get("peak_rate"), dict) for r in train):
        return peaks, None
    return peaks, tuple(max(float(r["peak_rate"][c]) for r in train) for c in coords)


def scales_of_card(scales: BushingScales, card: dict) -> BushingScales:
    """``scales`` from a model card's training records: stroke and velocity their largest |x|
    and |dx/dt| times ``RECORD_MARGIN`` (``record_range``, within the machine), their peak
    force the typical force, and -- when they do not show static behaviour
    (``static_identified``), so the static stiffness is an extrapolation -- the floor at
    ``FLOOR_FRACTION`` of that peak (the papers' rule, 0.5 mm of a 12.5 mm stroke, as a share
    of force). A card without those figures leaves ``scales`` as they are."""
    if not has_range(card):
        return scales
    train = [r for r in card.get("records", []) if r.get("role") == "train"]
    (peak,), (speed,) = train_range(train, ())
    force = max(r["max_abs_force_n"] for r in train)
    floor, source = scales.force_floor_n, scales.source
    if not static_identified(card):
        floor = FLOOR_FRACTION * force
        source = f"4 % of the card's training records' peak force ({force:.4g} N) as the floor"
    stroke, rate = record_range(peak, speed, ex.MAX_DISPLACEMENT_M, ex.MAX_VELOCITY_M_PER_S)
    return replace(
        scales,
        stroke_m=float(stroke),
        velocity_m_per_s=float(rate),
        force_scale_n=force,
        force_floor_n=floor,
        source=source + f"; stroke and velocity 1.5 x the card's training records "
        f"({peak * 1e3:.3g} mm, {speed:.3g} m/s)",
    )
