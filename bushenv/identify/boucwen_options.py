"""The options of the Bouc-Wen identifications, each field a flag of ``bushenv fit``: the
one-axis global search (``global_search.py``) and the vector Bouc-Wen's variable projection
over three coordinates (``vector_boucwen.py``). Kept apart from the searches so reading them
imports no scipy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.identify.data import IdentificationError
from bushenv.identify.options import option
from bushenv.models.planar_base import PlanarModelError

# two per decade over the band a vehicle bushing is driven in (corners 0.16 Hz to 50 Hz): fixed,
# not fitted, so the force stays linear in every gain
RELAXATION_TIMES = "0.003,0.01,0.03,0.1,0.3,1"


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


@dataclass(frozen=True)
class VectorBoucWenOptions:
    """Options of the vector Bouc-Wen identification; each is a flag of ``bushenv fit``."""

    evaluations: int = option(200, "shape evaluations of the bounded Powell search (after 8)")
    yield_surface: str = option(
        "vector",
        "vector: one yield surface on the deflection vector; axis: each coordinate its own",
        choices=("vector", "axis"),
    )
    time_limit_s: float = option(
        0.0,
        "wall-time limit of the search, s (0: none, the default: the evaluations decide, so "
        "the same records give the same parameters on every machine; a second search after a "
        "relaxation selection has its own); a stop by the clock is reported on the card",
    )

    relaxation_times: str = option(
        RELAXATION_TIMES,
        "time constants of the relaxation branches (Prony series, one per coordinate each, "
        "gains >= 0), s, comma-separated; '' for none",
    )

    relaxation_selection: str = option(
        "all",
        "all: keep every relaxation branch; extrapolation: drop the shortest ones when that "
        "predicts the training records' largest tenth of deflections clearly better from the "
        "rest (measured to help on one bushing and hurt on another: "
        "studies/2026-11-planar-fit-unseen)",
        choices=("all", "extrapolation"),
    )

    relaxation_form: str = option(
        "constant",
        "constant: the branches relax the deflection (gains in N/m); qlv: they relax the "
        "elastic force K q + G3(q) (Fung's quasi-linear viscoelasticity: the relaxing force "
        "follows the hardening and coupled stiffness; the same number of gains)",
        choices=("constant", "qlv"),
    )

    def taus(self) -> np.ndarray:
        """(M,) the relaxation time constants, s."""
        text = self.relaxation_times.strip()
        try:
            taus = np.array([float(x) for x in text.split(",")]) if text else np.zeros(0)
        except ValueError:
            raise PlanarModelError(
                f"relaxation_times: {self.relaxation_times!r} is not a comma-separated list of "
                "seconds (e.g. 0.01,0.1,1)"
            ) from None
        if np.any(~np.isfinite(taus)) or np.any(taus <= 0) or len(set(taus)) != len(taus):
            raise PlanarModelError(
                f"relaxation_times: {self.relaxation_times!r}: each must be a distinct time "
                "constant > 0 s"
            )
        return taus

    def check(self) -> None:
        self.taus()
        if self.evaluations < 1 or self.time_limit_s < 0:
            raise PlanarModelError(
                f"evaluations must be >= 1 and time_limit_s >= 0, got {self.evaluations}, "
                f"{self.time_limit_s}"
            )
