"""The planar model protocol: three coordinates in, two forces and a moment out.

A planar bushing model works in the bushing's own frame on the coordinate vector
``q = (axial m, radial m, rotation rad)`` and returns ``(axial N, radial N, moment N m)``
(``COORDS``, ``UNITS``). As the one-axis ``bushenv.models.base.BushingModel`` it is a small
stateful object at a fixed sample time ``dt``; its memory lives in ``self.state``, an array
of shape (n_state, B) for B independent histories.

Every model implements ``_advance(q, v, out)`` on C-contiguous float64 arrays of shape
(T, B, 3); ``step`` (one sample, (3,) or (B, 3)) and ``simulate`` ((T, 3) or (T, B, 3), free
run from rest) both call it, so looped and batched runs agree to the last bit.

Files: the one-axis format (``.npz``, ``allow_pickle=False``, one array per parameter plus a
``__meta__`` JSON) with the format tag ``bushenv-planar-model``, so a planar file is never
mistaken for a one-axis one and the other way round.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from bushenv.errors import BadInput, BushenvError, ModelRaised
from bushenv.models.base import PAPER_DT, SavedParameters, velocity_of

COORDS = ("axial", "radial", "rotation")
UNITS = ("m", "m", "rad")
FORCE_UNITS = ("N", "N", "N m")
FORMAT = "bushenv-planar-model"
FORMAT_VERSION = 1


class PlanarModelError(BadInput):
    """A planar model file or argument is wrong; the message names the file and the problem."""


class PlanarModel(SavedParameters):
    """Base class: state, step/simulate over one ``_advance``, parameters, save/load.

    Subclasses set ``name`` and ``param_names`` (arrays that define the model, kept as
    attributes), give ``n_state`` and implement ``_advance``; settings that are not arrays go
    through ``extra_meta`` and back into the constructor.
    """

    FILE_FORMAT: ClassVar[str] = FORMAT  # its own tag: a one-axis loader refuses the file

    name: ClassVar[str] = ""
    param_names: ClassVar[tuple[str, ...]] = ()
    optional_params: ClassVar[tuple[str, ...]] = ()  # may be absent from older files

    def __init__(self, dt: float = PAPER_DT) -> None:
        if not (np.isfinite(dt) and dt > 0):
            raise PlanarModelError(f"dt must be a positive number of seconds, got {dt!r}")
        self.dt = float(dt)
        self.reset(1)

    # ----- what subclasses provide -------------------------------------------------------
    @property
    def n_state(self) -> int:
        return 0

    def initial_state(self, batch_size: int) -> np.ndarray:
        """State at rest (zero deflection, zero force), shape (n_state, batch_size)."""
        return np.zeros((self.n_state, batch_size))

    def _advance(self, q: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        """Run T samples of (T, B, 3) ``q``, ``v`` into ``out`` (T, B, 3); update the state."""
        raise NotImplementedError

    @property
    def params(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in self.param_names}

    # ----- the protocol ------------------------------------------------------------------
    def reset(self, batch_size: int = 1) -> None:
        """Forget all history; prepare ``batch_size`` independent histories at rest."""
        if int(batch_size) < 1:
            raise PlanarModelError(f"batch_size must be >= 1, got {batch_size}")
        self.batch_size = int(batch_size)
        self.state = np.ascontiguousarray(self.initial_state(self.batch_size), dtype=np.float64)
        self._q1 = np.zeros((1, self.batch_size, 3))
        self._v1 = np.zeros((1, self.batch_size, 3))
        self._f1 = np.zeros((1, self.batch_size, 3))

    def backbone_alone(self) -> PlanarModel | None:
        """A hybrid's backbone as a model of its own (a fresh one, at rest), for judging what
        its network adds; None for a model without one."""
        return None

    def reset_columns(self, mask: np.ndarray) -> None:
        """Histories ``mask`` (B,) bool back to rest, the others kept (a vector env's autoreset)."""
        n = int(np.sum(mask))
        if n:
            self.state[:, mask] = self.initial_state(n)

    def step(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Advance one sample: (3,) in -> (3,) out (B == 1), (B, 3) in -> (B, 3) out."""
        q = np.asarray(q, dtype=np.float64)
        one = q.shape == (3,)
        want = (3,) if one and self.batch_size == 1 else (self.batch_size, 3)
        if q.shape != want or np.shape(v) != want:
            raise PlanarModelError(
                f"{self.name}: step got q {q.shape} and v {np.shape(v)}, expected {want} "
                f"(batch of {self.batch_size}; order {', '.join(COORDS)})"
            )
        self._q1[0] = q
        self._v1[0] = v
        self._guarded(self._q1, self._v1, self._f1)
        return self._f1[0, 0].copy() if one else self._f1[0].copy()

    def _guarded(self, q: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        """``_advance``; a non-bushenv exception from the model's code becomes ``ModelRaised``."""
        try:
            self._advance(q, v, out)
        except (BushenvError, ArithmeticError):
            raise
        except Exception as exc:
            raise ModelRaised(self.name, exc) from exc

    def simulate(self, q: np.ndarray, v: np.ndarray | None = None) -> np.ndarray:
        """Free run from rest: (T, 3) -> (T, 3) or (T, B, 3) -> (T, B, 3).

        ``v`` defaults to the central-difference velocity of ``q`` (``np.gradient``). The model
        is reset to B histories first and keeps its final state afterwards.
        """
        q = np.asarray(q, dtype=np.float64)
        two_d = q.ndim == 2
        q3 = q[:, None, :] if two_d else q
        if q3.ndim != 3 or q3.shape[0] < 1 or q3.shape[2] != 3:
            raise PlanarModelError(
                f"{self.name}: simulate expects (T, 3) or (T, B, 3) ({', '.join(COORDS)}), "
                f"got {q.shape}"
            )
        if v is None:
            v3 = velocity_of(q3, self.dt)
        else:
            v3 = np.asarray(v, dtype=np.float64)
            v3 = v3[:, None, :] if v3.ndim == 2 else v3
            if v3.shape != q3.shape:
                raise PlanarModelError(f"{self.name}: v shape {v3.shape} differs from q {q.shape}")
        q3 = np.ascontiguousarray(q3)
        v3 = np.ascontiguousarray(v3)
        self.reset(q3.shape[1])
        out = np.empty_like(q3)
        self._guarded(q3, v3, out)
        return out[:, 0, :] if two_d else out

    # ----- files -------------------------------------------------------------------------


def as_matrix(name: str, value: Any, shape: tuple[int, ...] = (3, 3)) -> np.ndarray:
    """``value`` as a finite float64 array of ``shape``, or ``PlanarModelError`` naming it."""
    try:
        a = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise PlanarModelError(f"{name} must be numbers, got {value!r}") from None
    if a.shape != shape:
        raise PlanarModelError(f"{name} has shape {list(a.shape)}, expected {list(shape)}")
    if not np.all(np.isfinite(a)):
        raise PlanarModelError(f"{name} holds NaN or inf")
    return a
