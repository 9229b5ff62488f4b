"""bushenv: stress-test rubber-bushing force models before trusting them in a vehicle model.

Importing bushenv registers every environment spec in ``envs/`` with Gymnasium.
"""

from __future__ import annotations

__version__ = "0.1.0"

from bushenv.models import get_model, get_reference, load_model, model_names  # noqa: E402


def _register_envs() -> None:
    try:
        from bushenv.rigs.registration import register_all
    except ImportError:  # rigs not built yet in this checkout
        return
    register_all()


_register_envs()

__all__ = ["__version__", "get_model", "get_reference", "load_model", "model_names"]
