"""The options of the Bouc-Wen identification: one dataclass, each field a flag of ``bushenv
fit``. Kept apart from the search (``global_search.py``) so reading them imports no scipy.
"""

from __future__ import annotations

from dataclasses import dataclass

from bushenv.identify.data import IdentificationError
from bushenv.identify.options import option


@dataclass(frozen=True)
class BoucWenOptions:
    """Options of the Bouc-Wen global search; each is a flag of ``bushenv fit``."""

    generations: int = option(400, "differential-evolution generations")
    population: int = option(
        8, "population per search variable (scipy's popsize: 8 x 14 = 112 members)"
    )
    fit_seconds: float = option(
        8.0, "seconds of the records the search scores on (from the start, record after record)"
    )
    polish_evaluations: int = option(
        500, "Powell polish evaluations on all of every record (0: no polish)"
    )
    max_substeps: int = option(
        400, "integrator trial steps allowed per sample before a member scores inf"
    )
    time_limit_s: float = option(
        0.0,
        "wall-time limit of the search, s; 0: none (generations decide, so a seed reproduces "
        "the parameters); a limit that stops it early is reported and on the card",
    )
    progress_every_s: float = option(3.0, "seconds between progress lines")

    def check(self) -> None:
        for name in ("generations", "population", "max_substeps"):
            if getattr(self, name) < 1:
                raise IdentificationError(f"{name} must be >= 1, got {getattr(self, name)}")
        if self.time_limit_s < 0:
            raise IdentificationError(f"time_limit_s must be >= 0, got {self.time_limit_s}")
        if self.polish_evaluations < 0 or not self.fit_seconds > 0:
            raise IdentificationError("polish_evaluations must be >= 0 and fit_seconds > 0")
