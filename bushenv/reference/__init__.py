"""The reference ("real") rubber bushing: ``rubber.py`` (the model, registered as ``rubber``),
``kernel.py`` (its one compiled kernel), ``calibration.py`` (how it is measured against the
papers: ``python -m bushenv.commands.calibration --behaviour``). See docs/reference.md."""
