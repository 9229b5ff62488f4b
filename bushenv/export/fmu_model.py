"""An FMU as a bushing model: ``get_model("x.fmu")`` runs a co-simulation FMU through FMPy.

Any FMU with co-simulation, a Real input (``deflection``, else the only one; ``velocity`` if
present) and a Real output (``force``, else the only one) can stand as a model, a reference or
an attack's target, at the sample time its DefaultExperiment states. Each sample is one
communication step: set the inputs at t, read the force, ``doStep(t, dt)`` -- so the force at
t is the FMU's answer to the input at t, as ``BushingModel.step`` asks. B histories are B
instances of the FMU. An FMU that lacks one of these is refused, naming what is missing.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import weakref
import zipfile
from pathlib import Path

import numpy as np

from bushenv.models.base import DT_TOLERANCE, BushingModel, ModelError


def _fmpy():
    try:
        import fmpy
    except ImportError:
        raise ModelError(
            "loading an .fmu needs FMPy: pip install 'bushenv[fmi]' (or pip install fmpy)"
        ) from None
    return fmpy


def read_description(path: Path):
    """FMPy's reading of the FMU's modelDescription.xml; ModelError for a damaged file."""
    fmpy = _fmpy()
    if not path.is_file():
        raise ModelError(f"{path}: no such FMU")
    if not zipfile.is_zipfile(path):
        raise ModelError(f"{path}: damaged FMU: not a zip archive")
    try:
        return fmpy.read_model_description(str(path), validate=False)
    except Exception as exc:  # FMPy raises bare Exceptions and lxml errors alike
        text = " ".join(str(exc).split())[:200]
        raise ModelError(
            f"{path}: damaged FMU: its modelDescription.xml cannot be read ({text})"
        ) from None


def _pick(path: Path, variables, causality: str, name: str, required: bool):
    real = [v for v in variables if v.causality == causality and v.type in ("Real", "Float64")]
    named = [v for v in real if v.name == name]
    if named:
        return named[0]
    if len(real) == 1 and causality == "output":
        return real[0]
    if len(real) == 1 and name == "deflection":
        return real[0]
    if required:
        found = ", ".join(v.name for v in real) or "none"
        raise ModelError(
            f"{path}: the FMU lacks a Real {causality} {name!r} (its Real {causality}s: {found})"
        )
    return None


class FmuBushing(BushingModel):
    """A co-simulation FMU stepped at its own sample time (see the module docstring)."""

    name = "fmu"

    def __init__(self, path: str | os.PathLike, dt: float | None = None) -> None:
        self.path = Path(path)
        md = read_description(self.path)
        if md.coSimulation is None:
            raise ModelError(
                f"{self.path}: the FMU lacks co-simulation (model exchange only); bushenv steps "
                "FMUs as co-simulation slaves"
            )
        self._md = md
        self._x = _pick(self.path, md.modelVariables, "input", "deflection", True)
        self._v = _pick(self.path, md.modelVariables, "input", "velocity", False)
        if self._v is self._x:
            self._v = None
        self._f = _pick(self.path, md.modelVariables, "output", "force", True)
        step = md.defaultExperiment.stepSize if md.defaultExperiment else None
        file_dt = float(step) if step else None
        if file_dt is None and dt is None:
            raise ModelError(
                f"{self.path}: the FMU states no sample time (DefaultExperiment stepSize); pass dt"
            )
        if file_dt is not None and dt is not None and abs(file_dt - dt) > DT_TOLERANCE * dt:
            raise ModelError(
                f"{self.path}: FMU sampled at {1 / file_dt:.6g} Hz (dt={file_dt:.6g} s), "
                f"expected {1 / dt:.6g} Hz (dt={dt:.6g} s)"
            )
        self._unzipped = tempfile.mkdtemp(prefix="bushenv-fmu-")
        weakref.finalize(self, shutil.rmtree, self._unzipped, True)
        try:
            _fmpy().extract(str(self.path), self._unzipped)
        except Exception as exc:
            raise ModelError(f"{self.path}: damaged FMU: cannot extract it ({exc})") from None
        self._slaves: list = []
        self._n = 0  # samples done: time = n dt, never accumulated
        super().__init__(file_dt if file_dt is not None else dt)

    @property
    def params(self) -> dict:
        return {}

    def _instance(self, i: int):
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave

        md = self._md
        cls = FMU3Slave if md.fmiVersion.startswith("3") else FMU2Slave
        kw = dict(
            guid=md.guid,
            unzipDirectory=self._unzipped,
            instanceName=f"bushenv{i}",
            modelIdentifier=md.coSimulation.modelIdentifier,
        )
        try:
            slave = cls(**kw)
            slave.instantiate()
            if cls is FMU2Slave:
                slave.setupExperiment(startTime=0.0)
                slave.enterInitializationMode()
            else:
                slave.enterInitializationMode(startTime=0.0)
            slave.exitInitializationMode()
        except Exception as exc:
            raise ModelError(f"{self.path}: the FMU cannot be instantiated here ({exc})") from None
        return slave

    def reset(self, batch_size: int = 1) -> None:
        super().reset(batch_size)
        self._free()
        self._n = 0
        self._slaves = [self._instance(i) for i in range(self.batch_size)]

    def _free(self) -> None:
        for s in getattr(self, "_slaves", ()):
            try:
                s.terminate()
                s.freeInstance()
            except Exception:  # a failed FMU may refuse to terminate; its memory goes anyway
                pass
        self._slaves = []

    def __del__(self) -> None:
        self._free()

    def _advance(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        if len(self._slaves) != x.shape[1]:
            self.reset(x.shape[1])
        three = self._md.fmiVersion.startswith("3")
        vr_x, vr_f = [self._x.valueReference], [self._f.valueReference]
        vr_v = [self._v.valueReference] if self._v is not None else None
        for t in range(x.shape[0]):
            for b, s in enumerate(self._slaves):
                if three:
                    s.setFloat64(vr_x, [x[t, b]])
                    if vr_v:
                        s.setFloat64(vr_v, [v[t, b]])
                    out[t, b] = s.getFloat64(vr_f)[0]
                else:
                    s.setReal(vr_x, [x[t, b]])
                    if vr_v:
                        s.setReal(vr_v, [v[t, b]])
                    out[t, b] = s.getReal(vr_f)[0]
                s.doStep(currentCommunicationPoint=self._n * self.dt, communicationStepSize=self.dt)
            self._n += 1

    def copy(self) -> FmuBushing:
        return FmuBushing(self.path, self.dt)

    def save(self, path):
        raise ModelError(f"{self.path}: an FMU model is its .fmu file; it is not saved as .npz")

    def __repr__(self) -> str:
        return f"FmuBushing({str(self.path)!r}, dt={self.dt:.6g})"


def load_fmu(path: str | os.PathLike, dt: float | None = None) -> FmuBushing:
    """``get_model``'s loader for ``.fmu`` files."""
    return FmuBushing(path, dt=dt)
