"""Certificates for NARX bushing models (nn, hybrid): hold stability and small-signal passivity.

| module            | what it holds                                                        |
|-------------------|----------------------------------------------------------------------|
| ``network``       | the network seen with x held: phi(y), derivative bounds, lag gradients |
| ``fixed_points``  | every fixed point of a hold (exhaustive search), stability, folds    |
| ``ghosts``        | ghosts of vanished fixed points and how long the free run lingers    |
| ``holds``         | the free run after a step: where it settles, whether it departs      |
| ``passivity``     | dynamic stiffness K about a hold, Im K < 0 bands, K from sines       |
| ``energy``        | where the divergence judge's energy criterion fires on sines         |
| ``certificate``   | ``certify``: the whole certificate; cheap pieces for searchers       |
| ``reached_holds`` | the failing holds alone, reached after sines: the reference's vetting |
| ``plots``, ``command`` | the plots and ``bushenv certify``                               |
"""

from bushenv.certify.certificate import (
    Certificate,
    CertifyOptions,
    certify,
    least_stable_holds,
    non_passive_bands,
    stability_margin,
)
from bushenv.certify.fixed_points import FixedPoints, Fold, fixed_points, folds, spectral_radius
from bushenv.certify.network import CertifyError, NarxNet, narx_net

__all__ = [
    "Certificate",
    "CertifyError",
    "CertifyOptions",
    "FixedPoints",
    "Fold",
    "NarxNet",
    "certify",
    "fixed_points",
    "folds",
    "least_stable_holds",
    "narx_net",
    "non_passive_bands",
    "spectral_radius",
    "stability_margin",
]
