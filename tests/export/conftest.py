"""FMUs compiled once per test session (a second or so each), and FMPy-driven masters."""

import pytest

from .fmu_masters import AXIS

pytest.importorskip("fmpy")


@pytest.fixture(scope="session")
def fmu(tmp_path_factory):
    """fmu(model, version) -> path of that model's FMU (compiled on first use)."""
    from bushenv.export import export_fmu

    folder = tmp_path_factory.mktemp("fmus")
    made = {}

    def get(model: str, version: str):
        key = (model, version)
        if key not in made:
            out = folder / f"{model}-{version}.fmu"
            made[key] = export_fmu(model, out, version, axis=AXIS[model]).path
        return made[key]

    return get
