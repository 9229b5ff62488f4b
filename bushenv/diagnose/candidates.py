"""Candidate unmodelled effects: generic forms that augment a baseline force model.

Each candidate is one class registered by its name (``relaxation``, ``friction``, ``hardening``,
``thermal``, ``delay``, ``inertia``). A candidate turns a record's signals into regressor
columns whose weights are found by (bounded) linear least squares on TRAIN, plus a small grid
of nonlinear shape settings chosen on TRAIN. Every form is continuous-time: a column computed
at 204.8 Hz and at 1024 Hz describes the same physical quantity, so weights identified on one
rate apply at another.

| name       | generic form (added force)                            | weights  | shapes      |
|------------|-------------------------------------------------------|----------|-------------|
| relaxation | sum_i k_i h_i,  h_i' = v - h_i / tau_i (Maxwell)      | k_i >= 0 | tau grid    |
| friction   | sum_j F_j z_j,  dz_j/dx = (sgn(dx) - z_j) / x_j (Dahl)| F_j >= 0 | x_j grid    |
| hardening  | a3 (x/s)^3 + a5 (x/s)^5,  s = sigma_x(TRAIN)          | a3,a5>=0 | none        |
| thermal    | -theta (b_k x + b_c v), theta' = v^2 - theta / tau_th | b >= 0   | tau_th      |
| delay      | the whole predicted force at t - d (fractional shift) | none     | d, refined  |
| inertia    | m a,  a = d2x/dt2                                     | m >= 0   | none        |

- tau grid: 10^(-2 .. 2 in steps of 0.5) s, kept between 2 dt and TRAIN's duration; all
  branches at once, non-negative weights (a discrete relaxation spectrum).
- x_j grid: sigma_x(TRAIN) * {0.002, 0.006, 0.02, 0.06, 0.2}; all elements at once with
  non-negative weights (a discrete Iwan-like distribution of Dahl elements).
- tau_th in {10, 30, 100, 300, inf} s (inf: cumulative v^2), chosen by TRAIN error.
- d: 13 values from 0.25 to 40 ms, the best refined by a bounded 1-D search on TRAIN error.

The shapes are deliberately not the reference bushing's own laws (Berg/Iwan friction, its
relaxation spectrum, its hardening law): they are the textbook generic forms.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numba as nb
import numpy as np
from scipy import ndimage, signal

from bushenv.models.base import velocity_of

EFFECTS = ("relaxation", "friction", "hardening", "thermal", "delay", "inertia")
CANDIDATE_REGISTRY: dict[str, type[Candidate]] = {}


STENCILS = ("central", "five_point")


@dataclass
class Signals:
    """One record's prescribed motion, derived once: (T,) arrays, SI units.

    ``stencil`` says how velocity and acceleration are estimated from the sampled displacement:
    ``"central"`` is the project's convention (``np.gradient``, applied twice for the
    acceleration), what every bushenv model uses by default, so simulated records match it
    exactly; ``"five_point"`` is the fourth-order stencil, closer to the true derivative of a
    continuous motion near the Nyquist frequency. The diagnosis picks one on TRAIN.
    """

    x: np.ndarray
    dt: float
    stencil: str = "central"
    v: np.ndarray = field(init=False)
    a: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.x = np.ascontiguousarray(self.x, dtype=np.float64)
        if self.stencil == "central":
            self.v = velocity_of(self.x, self.dt)
            self.a = velocity_of(self.v, self.dt)
        elif self.stencil == "five_point":
            self.v = first_derivative(self.x, self.dt)
            self.a = second_derivative(self.x, self.dt)
        else:
            raise ValueError(f"unknown stencil {self.stencil!r}; known: {list(STENCILS)}")


def first_derivative(x: np.ndarray, dt: float) -> np.ndarray:
    """dx/dt by the 5-point central stencil (np.gradient at the two samples of each end).

    Fourth-order: at a fifth of the sample rate it is 7 % low where np.gradient is 24 % low,
    which matters when a fast record's force holds stiffness, damping and inertia together.
    """
    v = velocity_of(x, dt)
    if x.size >= 5:
        v[2:-2] = (-x[4:] + 8.0 * x[3:-1] - 8.0 * x[1:-3] + x[:-4]) / (12.0 * dt)
    return v


def second_derivative(x: np.ndarray, dt: float) -> np.ndarray:
    """d2x/dt2 by the 5-point central stencil (np.gradient twice near the ends)."""
    a = velocity_of(velocity_of(x, dt), dt)
    if x.size >= 5:
        a[2:-2] = (-x[4:] + 16.0 * x[3:-1] - 30.0 * x[2:-2] + 16.0 * x[1:-3] - x[:-4]) / (
            12.0 * dt * dt
        )
    return a


@dataclass(frozen=True)
class Scales:
    """Amplitude scales taken from TRAIN and kept fixed for every TEST (absolute units)."""

    sigma_x: float
    duration_s: float
    dt: float


def register_candidate(cls: type[Candidate]) -> type[Candidate]:
    CANDIDATE_REGISTRY[cls.name] = cls
    return cls


class Candidate:
    """One effect: ``columns(signals, shape, scales)`` -> (T, p) regressors, ``lower`` bounds."""

    name: ClassVar[str] = ""
    continuous_shape: ClassVar[bool] = False  # refine the best grid shape by a 1-D search

    def shapes(self, scales: Scales) -> list:
        """The shape settings to try on TRAIN (a list of hashable values; [None] if none)."""
        return [None]

    def columns(self, s: Signals, shape, scales: Scales) -> np.ndarray:
        return np.zeros((s.x.size, 0))

    def lower(self, shape, scales: Scales) -> np.ndarray:
        """Lower bounds of the column weights (0 where the physics fixes a sign)."""
        return np.full(self.columns_count(shape, scales), -np.inf)

    def columns_count(self, shape, scales: Scales) -> int:
        return 0

    def delay_s(self, shape) -> float:
        """Time shift applied to the whole predicted force (only ``delay`` has one)."""
        return 0.0

    def describe(self, shape) -> str:
        return self.name


# ----- relaxation ------------------------------------------------------------------------
TAU_GRID_S = 10.0 ** np.arange(-2.0, 2.01, 0.5)  # 0.01 .. 100 s


def maxwell_state(x: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """h with h' = v - h / tau, i.e. x minus its first-order low-pass (trapezoidal in x)."""
    a = np.exp(-dt / tau)
    # s[n] = a s[n-1] + (1 - a) (x[n] + x[n-1]) / 2 : the low-pass, exact for piecewise-linear x
    b = np.array([(1 - a) / 2, (1 - a) / 2])
    low = signal.lfilter(b, [1.0, -a], x)
    return x - low


@register_candidate
class Relaxation(Candidate):
    name = "relaxation"

    def taus(self, scales: Scales) -> np.ndarray:
        keep = (TAU_GRID_S >= 2 * scales.dt) & (TAU_GRID_S <= max(scales.duration_s, 0.05))
        return TAU_GRID_S[keep]

    def columns(self, s, shape, scales):
        return np.stack([maxwell_state(s.x, s.dt, t) for t in self.taus(scales)], axis=1)

    def columns_count(self, shape, scales):
        return int(self.taus(scales).size)

    def lower(self, shape, scales):
        return np.zeros(self.columns_count(shape, scales))


# ----- friction --------------------------------------------------------------------------
DAHL_FRACTIONS = np.array([0.002, 0.006, 0.02, 0.06, 0.2])


@nb.njit(cache=True, nogil=True)
def dahl_states(x, xs, out):  # pragma: no cover - compiled
    """Rate-independent Dahl elements: dz/dx = (sgn(dx) - z) / xs, exact per displacement step."""
    T = x.shape[0]
    J = xs.shape[0]
    for j in range(J):
        out[0, j] = 0.0
    for t in range(1, T):
        dx = x[t] - x[t - 1]
        if dx == 0.0:
            for j in range(J):
                out[t, j] = out[t - 1, j]
            continue
        sgn = 1.0 if dx > 0 else -1.0
        adx = abs(dx)
        for j in range(J):
            out[t, j] = sgn - (sgn - out[t - 1, j]) * np.exp(-adx / xs[j])


@register_candidate
class Friction(Candidate):
    name = "friction"

    def columns(self, s, shape, scales):
        xs = DAHL_FRACTIONS * scales.sigma_x
        out = np.empty((s.x.size, xs.size))
        dahl_states(s.x, xs, out)
        return out

    def columns_count(self, shape, scales):
        return int(DAHL_FRACTIONS.size)

    def lower(self, shape, scales):
        return np.zeros(DAHL_FRACTIONS.size)


# ----- hardening -------------------------------------------------------------------------
@register_candidate
class Hardening(Candidate):
    name = "hardening"

    def columns(self, s, shape, scales):
        u = s.x / scales.sigma_x
        return np.stack([u**3, u**5], axis=1)

    def columns_count(self, shape, scales):
        return 2

    def lower(self, shape, scales):
        return np.zeros(2)  # stiffening: both terms add force in the direction of x


# ----- thermal ---------------------------------------------------------------------------
THERMAL_TAUS_S = (10.0, 30.0, 100.0, 300.0, np.inf)


def heating_state(v: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """theta' = v^2 - theta / tau from rest (tau = inf: cumulative), units m^2/s."""
    p = v * v
    if np.isinf(tau):
        return np.cumsum(p) * dt
    a = np.exp(-dt / tau)
    return signal.lfilter([dt], [1.0, -a], p)


@register_candidate
class Thermal(Candidate):
    name = "thermal"

    def shapes(self, scales):
        return list(THERMAL_TAUS_S)

    def columns(self, s, shape, scales):
        theta = heating_state(s.v, s.dt, shape)
        # heating softens rubber: the columns are the force lost, weights >= 0
        return np.stack([-theta * s.x, -theta * s.v], axis=1)

    def columns_count(self, shape, scales):
        return 2

    def lower(self, shape, scales):
        return np.zeros(2)

    def describe(self, shape):
        return f"thermal (tau_th={shape:g} s)"


# ----- delay -----------------------------------------------------------------------------
DELAY_GRID_S = tuple(float(d) for d in 1e-3 * np.geomspace(0.25, 40.0, 13))


def shift_columns(cols: np.ndarray, delay_s: float, dt: float) -> np.ndarray:
    """cols(t - delay) by cubic-spline interpolation; the first value holds before t = 0."""
    if delay_s == 0.0:
        return cols
    n = delay_s / dt
    shift = (n,) + (0,) * (cols.ndim - 1)
    return ndimage.shift(cols, shift, order=3, mode="nearest")


@register_candidate
class Delay(Candidate):
    name = "delay"
    continuous_shape = True

    def shapes(self, scales):
        return list(DELAY_GRID_S)

    def delay_s(self, shape):
        return float(shape or 0.0)

    def describe(self, shape):
        return f"delay (d={1e3 * shape:.3g} ms)"


# ----- inertia ---------------------------------------------------------------------------
@register_candidate
class Inertia(Candidate):
    name = "inertia"

    def columns(self, s, shape, scales):
        return s.a[:, None].copy()

    def columns_count(self, shape, scales):
        return 1

    def lower(self, shape, scales):
        return np.zeros(1)


def get_candidate(name: str) -> Candidate:
    if name not in CANDIDATE_REGISTRY:
        raise ValueError(f"unknown candidate effect {name!r}; known: {list(EFFECTS)}")
    return CANDIDATE_REGISTRY[name]()
