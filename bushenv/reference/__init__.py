"""The reference ("real") rubber bushing: ``rubber.py`` (the model, registered as ``rubber``),
``kernel.py`` (its one compiled kernel). How it is measured against the papers:
``python scripts/reference_calibration.py --behaviour``. See docs/reference.md."""
