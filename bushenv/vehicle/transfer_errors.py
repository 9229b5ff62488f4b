"""Model errors of one kind on one coordinate of the reference rubber, sized by their component
error so that kinds are compared at equal error.

An error term is the reference bushing (the coupled three-axis rubber, ``rubber`` in
``bushenv.models.MODELS``, without its load cell) with one parameter group scaled on one
coordinate i (axial, radial, rotation) by a factor (1 + a):

| kind       | scaled                 | what the model then gets wrong                      |
|------------|------------------------|-----------------------------------------------------|
| stiffness  | ``stiffness[i]``       | k_i of the strain energy: the elastic force of i    |
|            |                        | (and what relaxes from it)                          |
| damping    | ``damping[i]``         | the viscous force c_i v_i                           |
| hysteresis | ``friction_fmax[i]``   | the friction loop's width: every Iwan element's     |
|            |                        | slip force and stiffness, so the friction force of  |
|            |                        | i scales by (1 + a) exactly                         |
| relaxation | ``relax_weight[:, i]`` | every Maxwell branch's force on i                   |

**Size**: the component-level error is the RMS force error ratio (``bushenv.metrics.rms_ratio``,
in %) on the erring coordinate's own force, the error term's law against the reference's, both
driven open loop by the bench's random motion at amplitude index n = 1 (independent random on
all three coordinates, ``bushenv.motions.random_independent``, 2 mm, 2 mm, 0.05 rad
peak, ``BENCH_S`` long, seed ``BENCH_SEED``): what a bushing test rig shows of the error. A
signed size s > 0 overstates the effect (a > 0), s < 0 understates it (a < 0); ``calibrate``
finds a by bisection for each kind and coordinate, so every kind errs by the same |s|.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from bushenv.errors import BadInput
from bushenv.metrics import rms_ratio

KINDS = ("stiffness", "damping", "hysteresis", "relaxation")
PARAMETER = {"stiffness": "stiffness", "damping": "damping", "hysteresis": "friction_fmax",
             "relaxation": "relax_weight"}  # fmt: skip
COORDS = ("axial", "radial", "rotation")
BENCH_S = 20.0  # s of bench motion the size is measured on
BENCH_SEED = 0
MAX_FACTOR = 64.0  # an error needing more than 64x its parameter is refused (not a small error)
# the smallest factor: the rubber keeps an effect it has on one coordinate only while every
# coordinate's friction and stiffness is above zero
MIN_FACTOR = 1e-6


class TransferInputError(BadInput):
    """An error term or a campaign setting is invalid; the message names it and its value."""


@dataclass(frozen=True)
class ErrorTerm:
    """One model error: ``kind`` on coordinate ``coord`` of the bushing at ``pivot``, of signed
    component-level size ``size_pct`` (RMS force error ratio on the bench, %)."""

    pivot: str
    coord: str
    kind: str
    size_pct: float

    @property
    def component(self) -> tuple[str, str, str]:
        return (self.pivot, self.coord, self.kind)

    def label(self) -> str:
        return f"{self.pivot}/{self.coord}/{self.kind} {self.size_pct:+.3g} %"


def reference_rubber(dt_s: float) -> Any:
    """The reference bushing as a car's pivot runs it (``rubber-torsion`` without its
    measurement)."""
    from bushenv.models import get_model
    from bushenv.rigs.halfcar_params import REFERENCE

    return get_model(REFERENCE, dt=dt_s, preset={"measurement": False}, coords=3)


def check_term(coord: str, kind: str) -> int:
    """The coordinate's index, or ``TransferInputError`` naming the unknown coordinate or kind."""
    if kind not in KINDS:
        raise TransferInputError(f"error kind {kind!r}; known: {', '.join(KINDS)}")
    if coord not in COORDS:
        raise TransferInputError(f"coordinate {coord!r}; known: {', '.join(COORDS)}")
    return COORDS.index(coord)


def scaled_rubber(base: Any, kind: str, coord: str, factor: float) -> Any:
    """A copy of the rubber ``base`` with ``kind``'s parameter on ``coord`` times ``factor``."""
    i = check_term(coord, kind)
    if not (np.isfinite(factor) and factor >= MIN_FACTOR):
        raise TransferInputError(
            f"{kind} factor must be finite and >= {MIN_FACTOR:g}, got {factor!r}"
        )
    params = {k: np.array(v, dtype=np.float64) for k, v in base.params.items()}
    name = PARAMETER[kind]
    if name == "relax_weight":
        params[name][:, i] *= factor
    else:
        params[name][i] *= factor
    return type(base).from_params(params, base.dt, base.extra_meta())


@lru_cache(maxsize=4)
def bench_motion(dt_s: float) -> np.ndarray:
    """(T, 3) the bench's random motion at n = 1 (module docstring), read-only."""
    from bushenv.motions import random_independent

    q = random_independent(1.0, BENCH_S, dt_s, BENCH_SEED)
    q.setflags(write=False)
    return q


@lru_cache(maxsize=4)
def _bench_force(dt_s: float) -> np.ndarray:
    f = reference_rubber(dt_s).simulate(bench_motion(dt_s))
    f.setflags(write=False)
    return f


def bench_errors_pct(model: Any, dt_s: float) -> np.ndarray:
    """(3,) RMS force error ratio of ``model`` against the reference on the bench, per
    coordinate, %."""
    f = model.simulate(bench_motion(dt_s))
    ref = _bench_force(dt_s)
    return np.array([100.0 * rms_ratio(ref[:, i], f[:, i]) for i in range(3)])


@lru_cache(maxsize=512)
def calibrate(kind: str, coord: str, size_pct: float, dt_s: float) -> float:
    """The factor (1 + a) that gives ``kind`` on ``coord`` the bench error |``size_pct``|,
    above 1 for a positive size, below for a negative (bisection on the factor)."""
    i = check_term(coord, kind)
    if not (np.isfinite(size_pct) and size_pct != 0):
        raise TransferInputError(f"an error's size must be a finite non-zero %, got {size_pct!r}")
    base = reference_rubber(dt_s)
    target = abs(size_pct)

    def err(factor: float) -> float:
        return float(bench_errors_pct(scaled_rubber(base, kind, coord, factor), dt_s)[i])

    if size_pct > 0:
        lo, hi = 1.0, 2.0
        while err(hi) < target:
            lo, hi = hi, 2.0 * hi
            if hi > MAX_FACTOR:
                raise TransferInputError(
                    f"{kind} on {coord}: {size_pct:+g} % needs the parameter over "
                    f"{MAX_FACTOR:g}x (at {MAX_FACTOR:g}x: {err(MAX_FACTOR):.3g} %)"
                )
    else:
        lo, hi = 1.0, MIN_FACTOR
        if err(hi) < target:
            raise TransferInputError(
                f"{kind} on {coord}: {size_pct:+g} % cannot be reached by understating it "
                f"(the whole effect is {err(hi):.3g} % of the {coord} force on the bench)"
            )
    for _ in range(60):  # err grows with |factor - 1| (each kind's force is ~linear in it)
        mid = 0.5 * (lo + hi)
        if err(mid) < target:
            lo = mid
        else:
            hi = mid
        if abs(hi - lo) < 1e-9 * max(1.0, abs(hi)):
            break
    return 0.5 * (lo + hi)


def erring_rubber(kind: str, coord: str, size_pct: float, dt_s: float) -> Any:
    """The reference rubber with one error of ``kind`` on ``coord`` of bench size ``size_pct``."""
    return scaled_rubber(
        reference_rubber(dt_s), kind, coord, calibrate(kind, coord, size_pct, dt_s)
    )
