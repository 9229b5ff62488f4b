"""Three-axis bushing physics: the coupled reference, the matrix, network and vector Bouc-Wen
forms of the registered kinds (``bushenv.models.MODELS``), their identification and checks.

The protocol is ``bushenv.models.base.BushingModel`` over the coordinates ``COORDS``.
"""

from bushenv.planar.base import COORDS, FORCE_UNITS, UNITS, PlanarModel, PlanarModelError

__all__ = ["COORDS", "FORCE_UNITS", "UNITS", "PlanarModel", "PlanarModelError"]
