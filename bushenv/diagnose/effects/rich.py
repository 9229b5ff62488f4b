"""An effect in another form, as a member of a combination: its richest admissible form, or
its usual form with a stiffness lost for good beside it.

``RichForm(Relaxation())`` fits the relaxation's ``rich_columns`` (a wider, denser spectrum)
under the same name; the ``Richest`` shape marker tells the column store which columns to
build. Used by ``bushenv.diagnose.partner``: a second effect is named beside a first only when
it adds to the first's whole family, not merely to its usual form. ``LastingForm(Friction())``
fits ``lasting_columns`` (``Lasting`` marker: a stiffness lost for good beside the usual
columns), used by ``bushenv.diagnose.lasting``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.diagnose.effects.base import Effect, Lasting, Richest, Scales, Signals


class RichForm(Effect):
    """``inner`` with its shapes wrapped in ``Richest`` (never registered)."""

    def __init__(self, inner: Effect) -> None:
        self.inner = inner
        self.name = inner.name  # the column store finds the registered class by name
        self.replaces_spring = inner.replaces_spring
        self.continuous_shape = False  # the rich grid is already fine

    def shapes(self, scales: Scales) -> list:
        return [Richest(s) for s in self.inner.rich_shapes(scales)]

    def columns(self, s: Signals, shape: Any, scales: Scales) -> np.ndarray:
        return self.inner.block_columns(s, shape, scales)

    def columns_count(self, shape: Any, scales: Scales) -> int:
        return self.inner.columns_count(shape, scales)

    def example(self, scales: Scales, k_n_per_m: float) -> tuple[Any, np.ndarray]:
        raise NotImplementedError("a rich form is a comparator, not a candidate")

    def delay_s(self, shape: Any) -> float:
        return self.inner.delay_s(shape.inner)

    def describe(self, shape: Any) -> str:
        return f"{self.inner.describe(shape.inner)}, richest form"

    def __repr__(self) -> str:
        return f"RichForm({self.inner!r})"


class LastingForm(RichForm):
    """``inner`` with its shapes wrapped in ``Lasting`` (never registered)."""

    def shapes(self, scales: Scales) -> list:
        return [Lasting(s) for s in self.inner.shapes(scales)]

    def describe(self, shape: Any) -> str:
        return f"{self.inner.describe(shape.inner)}, and a stiffness lost for good"

    def __repr__(self) -> str:
        return f"LastingForm({self.inner!r})"
