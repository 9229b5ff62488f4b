"""What every candidate effect shares: the record's signals, TRAIN's scales, the Effect base
class (the whole contract of an effect) and the composition of effects
(``Relaxation() + Friction()``).

An effect turns a record's prescribed motion into regressor columns (its added force is a
weighted sum of them, weights by bounded least squares) for each of a few shape settings,
plus a time shift for the delay. Every form is continuous-time: columns computed at 204.8 Hz
and at 1024 Hz describe the same physical quantity, so weights identified at one rate apply
at another.
"""

from __future__ import annotations

import inspect
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any, ClassVar

import numpy as np

from bushenv.diagnose.effects.timeshift import shift_columns
from bushenv.models.base import velocity_of

STENCILS = ("central", "five_point")


@dataclass
class Signals:
    """One record's prescribed motion, derived once: (T,) arrays, SI units.

    ``stencil``: ``"central"`` is the project's convention (``np.gradient``, twice for the
    acceleration), what every bushenv model uses, so simulated records match it exactly;
    ``"five_point"`` is the fourth-order stencil, closer to the derivative of a continuous
    motion near Nyquist. The diagnosis picks the one that fits TRAIN better.

    A record run in a session (``bushenv.diagnose.session``) knows what ran before it:
    ``before`` is the record run just before and the rest between (s), ``session_time_s`` the
    time from the session's first sample to this record's, ``session_cold`` whether the
    session began with the specimen at rest (else it may have started warm). An effect with a
    state (a heat) carries it over; the others ignore it.
    """

    x: np.ndarray
    dt: float
    stencil: str = "central"
    v: np.ndarray = field(init=False)
    a: np.ndarray = field(init=False)
    before: tuple[Signals, float] | None = None
    session_time_s: float = 0.0
    session_cold: bool = False
    memo: dict = field(default_factory=dict, repr=False, compare=False)  # states carried over

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

    Fourth-order: at a fifth of the sample rate it is 7 % low where np.gradient is 24 % low.
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
    """Scales of the identification records, fixed for every record judged (SI units).

    ``x_pos`` / ``x_neg``: ``(largest deflection,)`` on the positive / negative side (m, as
    a magnitude; empty when that side is barely reached); ``sigma_x`` the deflection's
    standard deviation (m); ``duration_s`` the longest record; ``dt`` the largest sample time.
    """

    sigma_x: float
    duration_s: float
    dt: float
    v_rms: float
    x_pos: tuple[float, ...] = ()
    x_neg: tuple[float, ...] = ()

    @classmethod
    def of(cls, signals: list[Signals]) -> Scales:
        x = np.concatenate([s.x for s in signals])
        v = np.concatenate([s.v for s in signals])

        def side(mag: np.ndarray) -> tuple[float, ...]:
            # a side counts when it holds a few percent of the samples
            if mag.size < max(0.02 * x.size, 16) or float(mag.max()) <= 0:
                return ()
            return (float(mag.max()),)

        return cls(
            sigma_x=float(np.std(x)) or float(np.max(np.abs(x))) or 1.0,
            duration_s=max(s.x.size * s.dt for s in signals),
            dt=max(s.dt for s in signals),
            v_rms=float(np.sqrt(np.mean(v * v))) or 1.0,
            x_pos=side(x[x > 0]),
            x_neg=side(-x[x < 0]),
        )


class Effect(ABC):
    """One candidate effect: the whole contract, checked over every registered effect by
    ``bushenv.diagnose.checks``.

    Declared once, on the class (the docs table is made of them): ``name`` (the registry
    name; every other list of effects reads it from here), ``form`` (the force it adds),
    ``weights`` (their bounds, in words), ``shape_text`` (the shape settings tried),
    ``telling_test`` (a programme that shows what only this effect does, offered when an
    answer cannot tell two effects apart). ``shows_dissipation``: the effect's own evidence is
    the energy it dissipates (a hysteresis loop): it is named only when the records show the
    dissipation it claims (``rule.dissipation_evidence``). ``holds_its_law``: the effect is a
    force law of the deflection and its history, the same at every moment (a backbone, a
    friction; not a heat that builds up): it is named only when that law holds through each
    record (``rule.law_drift``). ``replaces_spring``: the columns
    replace the linear spring ``k x`` (a backbone of its own); ``continuous_shape``: the best
    grid shape is refined by a 1-D search on the fitting error.

    Implemented by each effect: ``columns`` (its regressors) and ``example`` (a typical
    instance: what synthetic records and the checks are made of). ``lower`` (the weights'
    admissible bounds), ``shapes``, ``delay_s``, ``describe`` and ``parameters`` where the
    defaults do not fit. Derived, never kept by hand: ``columns_count`` (from ``columns``)
    and ``forward`` (the force the effect adds, from the same regressors and delay the
    diagnosis predicts with).
    """

    name: ClassVar[str] = ""
    form: ClassVar[str] = ""
    weights: ClassVar[str] = ""
    shape_text: ClassVar[str] = "none"
    telling_test: ClassVar[str] = "a programme that excites it alone"
    shows_dissipation: ClassVar[bool] = False
    holds_its_law: ClassVar[bool] = False
    replaces_spring: ClassVar[bool] = False
    continuous_shape: ClassVar[bool] = False

    def shapes(self, scales: Scales) -> list:
        """The shape settings to try (hashable values; ``[None]`` if none)."""
        return [None]

    @abstractmethod
    def columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        """(T, p) regressors of the added force for one record; p depends on ``shape`` and
        ``scales`` only (``np.zeros((T, 0))`` for an effect without weights)."""

    @abstractmethod
    def example(self, scales: Scales, k_n_per_m: float) -> tuple[Any, np.ndarray]:
        """A typical instance ``(shape, weights)`` on a bushing of stiffness ``k_n_per_m``
        whose records have ``scales``: clearly visible, physically admissible (weights within
        ``lower``). A ``replaces_spring`` effect's weights include that stiffness."""

    def lower(self, shape: Any, scales: Scales) -> np.ndarray:
        """(p,) lower bounds of the weights (0 where the physics fixes a sign)."""
        return np.zeros(self.columns_count(shape, scales))

    def columns_count(self, shape: Any, scales: Scales) -> int:
        """p of ``columns``, read off them on a short probe motion (so it cannot disagree)."""
        try:
            return _probed_count(type(self), shape, scales)
        except TypeError:  # an unhashable shape: probe without the cache
            return _probed_count.__wrapped__(type(self), shape, scales)

    def delay_s(self, shape: Any) -> float:
        """Time shift of the whole predicted force (only the delay has one)."""
        return 0.0

    def shape_value(self, shape: Any) -> float:
        """The part of ``shape`` a ``continuous_shape`` effect refines (default: all of it)."""
        return float(shape)

    def with_shape_value(self, shape: Any, value: float) -> Any:
        """``shape`` with its refined part set to ``value``."""
        return value

    def shape_family(self, shape: Any) -> Any:
        """What of ``shape`` the refinement keeps (a thermal leak's heating law): shapes of one
        family differ only in their ``shape_value``."""
        return self.with_shape_value(shape, 1.0)

    def rich_shapes(self, scales: Scales) -> list:
        """The shapes of the richest admissible form (default: the usual ones)."""
        return self.shapes(scales)

    def rich_columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        """Regressors of the effect's richest admissible form: a wider spectrum, more
        elements, a freer shape within the same physics (default: the usual columns).
        A partner is named beside this effect only when it adds to this form."""
        return self.columns(s, shape, scales)

    def rich_lower(self, shape: Any, scales: Scales) -> np.ndarray:
        """Lower bounds of ``rich_columns`` at ``shape`` (a ``rich_shapes`` entry): ``lower``
        where the richest form is the usual one, else 0 for each of its columns. An effect
        whose ``rich_columns`` add columns of free sign says so here."""
        if type(self).rich_columns is Effect.rich_columns:
            return self.lower(shape, scales)
        return np.zeros(self.columns_count(Richest(shape), scales))

    def lasting_columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        """The usual columns and a stiffness lost for good, a saturating function of the
        largest deflection so far (``-x (1 - exp(-max|x| / (a sigma_x)))``, ``a`` in
        ``LOST_SATURATION``, weights >= 0; never recovered): what a row is compared with
        (``lasting.py``; no candidate is such a softening)."""
        peak = np.maximum.accumulate(np.abs(s.x)) / scales.sigma_x
        lost = [-s.x * (1.0 - np.exp(-peak / a)) for a in LOST_SATURATION]
        return np.concatenate([self.columns(s, shape, scales), np.stack(lost, axis=1)], axis=1)

    def nuisance_columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        """(T, q) columns whose weights (>= 0) each record has of its own, fitted on that
        record even when it is judged (a state the record starts in that no other record
        can tell: the heat of a specimen that ran before). Default: none."""
        return np.zeros((s.x.size, 0))

    def nuisance_parameters(self, shape: Any, scales: Scales, ws: list) -> dict[str, Any]:
        """The per-record weights ``ws`` in physical terms (default: none)."""
        return {}

    def block_columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        """``columns``; ``rich_columns`` for a ``Richest`` shape, ``lasting_columns`` for a
        ``Lasting`` one, ``nuisance_columns`` for a ``Nuisance`` one (of those shapes too):
        what the fits call."""
        if isinstance(shape, Nuisance):
            marked = isinstance(shape.inner, Richest | Lasting)
            return self.nuisance_columns(s, shape.inner.inner if marked else shape.inner, scales)
        if isinstance(shape, Richest):
            return self.rich_columns(s, shape.inner, scales)
        if isinstance(shape, Lasting):
            return self.lasting_columns(s, shape.inner, scales)
        return self.columns(s, shape, scales)

    def block_lower(self, shape: Any, scales: Scales) -> np.ndarray:
        """``lower`` of ``block_columns``: ``rich_lower`` for a ``Richest`` shape, a
        ``Lasting`` shape's lost stiffness >= 0 after the effect's own bounds, 0 for a
        ``Nuisance`` one (an effect's ``lower`` is only ever asked about its usual shapes)."""
        if isinstance(shape, Nuisance):
            return np.zeros(self.columns_count(shape, scales))
        if isinstance(shape, Richest):
            return self.rich_lower(shape.inner, scales)
        if isinstance(shape, Lasting):
            lost = np.zeros(len(LOST_SATURATION))
            return np.concatenate([self.lower(shape.inner, scales), lost])
        return self.lower(shape, scales)

    def forward(
        self, s: Signals, force: np.ndarray, shape: Any, w: np.ndarray, scales: Scales
    ) -> np.ndarray:
        """The force measured when this effect (``shape``, weights ``w``) acts on a specimen
        whose own force is ``force`` (T,), N: the regressors' weighted sum added, the whole
        seen through the delay -- the diagnosis's own prediction (``fitting.predict``)."""
        total = np.asarray(force, dtype=np.float64)
        cols = self.columns(s, shape, scales)
        if cols.shape[1]:
            total = total + cols @ np.asarray(w, dtype=np.float64)
        return shift_columns(total, self.delay_s(shape), s.dt)

    def describe(self, shape: Any) -> str:
        return self.name

    def parameters(self, shape: Any, scales: Scales, w: np.ndarray) -> dict[str, Any]:
        """The identified effect in physical terms, SI units in the key names."""
        return {}

    def __add__(self, other: Effect | Combination) -> Combination:
        return Combination((self,)) + other

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


PROBE_SAMPLES = 16
LOST_SATURATION = (0.5, 1.5, 5.0)  # peak deflections (x sigma_x) at which a lost stiffness
# saturates: from a loss set by the first excursions to one growing with the peak


@dataclass(frozen=True)
class Richest:
    """A shape marker: the effect's richest admissible form at shape ``inner``
    (``Effect.rich_columns``), used only to test whether a partner adds to it."""

    inner: Any


@dataclass(frozen=True)
class Lasting:
    """A shape marker: the effect at shape ``inner`` with a stiffness lost for good beside it
    (``Effect.lasting_columns``), used only to test whether that explains what it leaves."""

    inner: Any


@dataclass(frozen=True)
class Nuisance:
    """A shape marker: the effect's per-record columns at shape ``inner``
    (``Effect.nuisance_columns``), whose weights each record has of its own."""

    inner: Any


@lru_cache(maxsize=4096)
def _probed_count(cls: type[Effect], shape: Any, scales: Scales) -> int:
    x = scales.sigma_x * np.sin(np.linspace(0.0, 3.0, PROBE_SAMPLES))
    return int(cls().block_columns(Signals(x, scales.dt), shape, scales).shape[1])


RESERVED_NAMES = ("none",)  # the answer "no effect"; "+" joins the names of a pair


def contract_problem(name: str, cls: Any) -> str | None:
    """Why ``cls`` cannot be registered as effect ``name`` (None: it can).

    What can be told without data; ``bushenv.diagnose.checks`` runs the rest.
    """
    if not (isinstance(cls, type) and issubclass(cls, Effect)):
        return f"effect {name!r}: {cls!r} is not an Effect subclass"
    if name != cls.name:
        return (
            f"effect {name!r}: the class declares name {cls.name!r}; an effect's name is "
            "declared once, on its class (register it under that name)"
        )
    if not name or name != name.lower() or "+" in name or name in RESERVED_NAMES:
        return f"effect {name!r}: names are lowercase, without '+', and not 'none'"
    if inspect.isabstract(cls):
        missing = ", ".join(sorted(cls.__abstractmethods__))
        return f"effect {name!r}: {cls.__name__} does not implement {missing}"
    for attr in ("form", "weights"):
        if not getattr(cls, attr):
            return f"effect {name!r}: {cls.__name__}.{attr} is empty (the docs table shows it)"
    return None


@dataclass(frozen=True)
class Combination:
    """Effects fitted together, as pysindy's ConcatLibrary: ``Relaxation() + Friction()``."""

    members: tuple[Effect, ...]

    def __add__(self, other: Effect | Combination) -> Combination:
        more = other.members if isinstance(other, Combination) else (other,)
        names = [m.name for m in self.members]
        if any(m.name in names for m in more):
            raise ValueError(f"effect added twice: {names} + {[m.name for m in more]}")
        return Combination(self.members + tuple(more))

    @property
    def name(self) -> str:
        return "+".join(m.name for m in self.members) if self.members else "none"

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(m.name for m in self.members)

    @property
    def replaces_spring(self) -> bool:
        return any(m.replaces_spring for m in self.members)


NULL = Combination(())
