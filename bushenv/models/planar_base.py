"""Three-coordinate bushing models: ``BushingModel`` over (axial m, radial m, rotation rad).

A three-axis model works in the bushing's own frame on ``q = (axial, radial, rotation)`` and
returns ``(axial N, radial N, moment N m)`` (``COORDS``, ``UNITS``, ``FORCE_UNITS``). It is a
``bushenv.models.base.BushingModel`` whose ``coords`` are these three: the same state, step,
simulate and file format (``save`` writes ``coords`` into the header; files written before,
tagged ``bushenv-planar-model``, still load through ``bushenv.models.load_model``).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from bushenv.models.base import PAPER_DT, BushingModel, ModelError

COORDS = ("axial", "radial", "rotation")
UNITS = ("m", "m", "rad")
FORCE_UNITS = ("N", "N", "N m")
LEGACY_FORMAT = "bushenv-planar-model"  # the tag three-axis files carried before the one format


class PlanarModelError(ModelError):
    """A three-axis model file or argument is wrong; the message names the file and problem."""


class PlanarModel(BushingModel):
    """A ``BushingModel`` over the three in-plane coordinates.

    Subclasses set ``name`` and ``param_names`` (arrays that define the model, kept as
    attributes), give ``n_state`` and implement ``_advance`` on (T, B, 3) arrays; settings that
    are not arrays go through ``extra_meta`` and back into the constructor.
    """

    coords: ClassVar[tuple[str, ...]] = COORDS
    units: ClassVar[tuple[str, ...]] = UNITS
    force_units: ClassVar[tuple[str, ...]] = FORCE_UNITS

    def __init__(self, dt: float = PAPER_DT) -> None:
        try:
            super().__init__(dt)
        except ModelError as exc:
            raise PlanarModelError(str(exc)) from None

    def reset(self, batch_size: int = 1) -> None:
        if int(batch_size) < 1:
            raise PlanarModelError(f"batch_size must be >= 1, got {batch_size}")
        super().reset(batch_size)

    def reset_columns(self, mask: np.ndarray) -> None:
        """Histories ``mask`` (B,) bool back to rest, the others kept (a vector env's autoreset)."""
        n = int(np.sum(mask))
        if n:
            self.state[:, mask] = self.initial_state(n)

    def step(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        try:
            return super().step(q, v)
        except PlanarModelError:
            raise
        except ModelError as exc:
            raise PlanarModelError(str(exc)) from None

    def simulate(self, q: np.ndarray, v: np.ndarray | None = None) -> np.ndarray:
        try:
            return super().simulate(q, v)
        except PlanarModelError:
            raise
        except ModelError as exc:
            raise PlanarModelError(str(exc)) from None


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
