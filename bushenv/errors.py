"""The error types every part of bushenv raises, under one root.

Three kinds a user must tell apart (``bushenv.cli`` maps them to exit codes):

- ``BadInput`` (exit 2): a file, argument or value that cannot be what it claims; the message
  names the file, line or value and the fix. Every module's own error (``RecordError``,
  ``ModelError``, ``CampaignError``, ...) is one of these.
- ``ModelRaised`` (exit 3): a bushing model raised while it ran (a bug or a guard in the
  model's own code, e.g. a numpy shape error). It is the model's fault, not a divergence and not
  the user's input: it carries the model's label and its own message.
- anything else (exit 1): a bug in bushenv.

``ModelRefused`` marks the one kind of raise that *is* a divergence: a model refusing to go on
because its own state ran away (Bouc-Wen's step-size guard); the verdict treats the force from
that sample on as not finite. ``ArithmeticError`` (1/0, overflow) counts the same.
"""

from __future__ import annotations


class BushenvError(Exception):
    """Root of every error bushenv raises on purpose."""


class BadInput(BushenvError, ValueError):
    """Input that cannot be used; the message names file, line or value and how to fix it."""


class ModelRefused(BushenvError):
    """A model refusing to go on because its own state ran away: a divergence, not a bug."""


class ModelRaised(BushenvError):
    """A model raised while running: reported with its own message, never as a divergence."""

    def __init__(self, label: str, exc: BaseException) -> None:
        self.label = label
        self.original = exc
        text = " ".join(str(exc).split()) or type(exc).__name__
        super().__init__(f"{label}: {type(exc).__name__}: {text}")


# What a model's step or simulate may raise that is its own divergence (see module doc).
DIVERGENCE_RAISES = (ModelRefused, ArithmeticError)
