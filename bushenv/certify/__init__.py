"""Certificates for NARX bushing models of any number of coordinates (nn, hybrid, nn-axis): hold
stability over held deflection vectors and small-signal passivity as a matrix test.

| module            | what it holds                                                        |
|-------------------|----------------------------------------------------------------------|
| ``network``       | the network of C coordinates seen with q held: phi(y), lag matrices  |
| ``cells``, ``boxes`` | the exhaustive root searches: cells (C = 1), interval boxes (C > 1) |
| ``fixed_points``  | every fixed point of a hold, stability, folds (crossings of a grid)  |
| ``ghosts``        | ghosts of vanished fixed points and how long the free run lingers    |
| ``holds``         | the free run after a step: where it settles, whether it departs      |
| ``stiffness``     | dynamic stiffness K (C x C) about a hold: analytic, linearised, sines |
| ``passivity``     | the loss matrix test (C = 1: Im K < 0 bands), the passivity report   |
| ``energy``        | where the divergence judge's energy criterion fires on sines         |
| ``options``       | ``CertifyOptions``: the grid, the spans, the passivity holds         |
| ``certificate``   | ``certify``: the whole certificate; cheap pieces for searchers       |
| ``document``      | the certificate's JSON layout, one for every C                       |
| ``reached_holds`` | the failing holds alone, reached after sines: the reference's vetting |
| ``plots``         | the plots (``bushenv certify`` is ``commands/certify.py``)           |
"""

from bushenv.certify.certificate import (
    Certificate,
    certify,
    least_stable_holds,
    non_passive_bands,
    stability_margin,
)
from bushenv.certify.fixed_points import (
    FixedPoints,
    Fold,
    fixed_points,
    folds,
    grid,
    spectral_radius,
)
from bushenv.certify.network import CertifyError, NarxNet, narx_net
from bushenv.certify.options import CertifyOptions, per_coordinate
from bushenv.certify.passivity import PassivityReport, passivity
from bushenv.certify.range_holds import range_holds

__all__ = [
    "Certificate",
    "CertifyError",
    "CertifyOptions",
    "FixedPoints",
    "Fold",
    "NarxNet",
    "PassivityReport",
    "certify",
    "fixed_points",
    "folds",
    "grid",
    "least_stable_holds",
    "narx_net",
    "non_passive_bands",
    "passivity",
    "per_coordinate",
    "range_holds",
    "spectral_radius",
    "stability_margin",
]
