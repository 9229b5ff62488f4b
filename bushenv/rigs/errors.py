"""The rigs' error: its own module, so reading a spec imports nothing of the rigs' machinery."""

from __future__ import annotations

from bushenv.errors import BadInput


class RigError(BadInput):
    """A rig argument, spec file or excitation is wrong; the message names it and the value."""
