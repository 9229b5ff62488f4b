"""bushenv: stress-test rubber-bushing force models before trusting them in a vehicle model.

Importing bushenv registers every environment spec in ``envs/`` with Gymnasium, under its id
(``BushRig-v0``) and in the ``bushenv/`` namespace, so ``gym.make("bushenv:bushenv/BushRig-v0")``
needs no import of its own.
"""

from __future__ import annotations

__version__ = "0.1.0"

from bushenv.models import get_model, get_reference, load_model, model_names  # noqa: E402
from bushenv.rigs.registration import register_all  # noqa: E402

register_all()

__all__ = ["__version__", "get_model", "get_reference", "load_model", "model_names"]
