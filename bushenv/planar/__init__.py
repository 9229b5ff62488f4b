"""Planar bushing models: axial, radial and rotation at once (see ``base.py`` for the protocol).

The one-axis protocol (``bushenv.models``) is untouched; this package is its three-coordinate
sibling with its own registry, ``PLANAR_MODELS``.
"""

from bushenv.planar.base import COORDS, FORCE_UNITS, UNITS, PlanarModel, PlanarModelError
from bushenv.planar.registry import PLANAR_MODELS, load_planar_model, model_class

__all__ = [
    "COORDS",
    "FORCE_UNITS",
    "PLANAR_MODELS",
    "UNITS",
    "PlanarModel",
    "PlanarModelError",
    "load_planar_model",
    "model_class",
]
