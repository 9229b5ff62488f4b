"""The command layer: each module parses one command's arguments into a typed config and
calls the library (``bushenv.cli`` maps command names to these modules). Argument parsing
lives here and in ``bushenv.cli`` only; library modules raise ``bushenv.errors`` errors."""
