"""Three-axis stages still being merged into their one-axis kin (fit, card, vetting, certificate,
machine); the physics lives in ``bushenv.models`` and ``bushenv.reference``."""
