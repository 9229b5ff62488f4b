"""Export bushing models as FMUs (FMI 2.0 / 3.0 co-simulation, compiled C), and load FMUs as
bushing models. ``export_fmu`` writes one; ``bushenv export`` is its command (docs/export.md).
"""

from bushenv.export.build import (
    Exported,
    ExportError,
    FailingCertificate,
    c_compiler,
    export_fmu,
)

__all__ = ["ExportError", "Exported", "FailingCertificate", "c_compiler", "export_fmu"]
