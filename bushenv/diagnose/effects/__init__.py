"""Candidate unmodelled effects, one module each; the registry is ``diagnose.candidates``."""
