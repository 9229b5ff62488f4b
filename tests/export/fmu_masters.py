"""What the export tests share: bushenv excitations and FMPy-driven masters of an FMU.

The masters drive an exported FMU from outside, through FMPy's FMU classes, as an importer
would: ``set_then_read`` sets the inputs, then reads the outputs (many vehicle simulators do;
FMPy's own ``simulate_fmu`` reads after ``doStep``, before the next input);
``derivatives_then_step`` gives FMI 2 input derivatives; ``model_exchange_rk4`` integrates a
model-exchange FMU with a fixed-step RK4 of its own. ``converged`` is the converged Bouc-Wen
run the FMUs are judged against (tests/models/boucwen_converged.py).

studies/2026-11-fmu-accuracy/fmu_accuracy.py and scripts/bench_fmu.py use these masters too
(``sys.path`` gets this folder).
"""

import importlib.util
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from bushenv import excitation as ex
from bushenv.models import PAPER_DT

AXIS = {"linear": "axial", "nn": "axial", "hybrid": "axial", "boucwen": "radial"}


def _boucwen_converged():
    """tests/models/boucwen_converged.py (tests/models is not a package: loaded by path)."""
    path = Path(__file__).resolve().parents[1] / "models" / "boucwen_converged.py"
    spec = importlib.util.spec_from_file_location("boucwen_converged", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


converged = _boucwen_converged().converged


def inputs():
    """Excitations from bushenv: (name, x) at the papers' rate."""
    dt = PAPER_DT
    return {
        "random n=1": ex.random_rpc(1.0, 4.0, dt, seed=0),
        "4 mm step": ex.step_hold(4e-3, 1.0, dt),
        "sines": ex.sine(2.0, 3e-3, 1.0, dt) + ex.sine(23.0, 0.4e-3, 1.0, dt),
    }


@contextmanager
def opened(path, log=None, start_s: float = 0.0):
    """An initialised FMPy slave of the FMU at ``path``: yields (slave, value references by
    name, FMI 3 or not); frees it and its extracted folder afterwards."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    from fmpy.fmi3 import FMU3Slave

    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    three = md.fmiVersion.startswith("3")
    with tempfile.TemporaryDirectory(prefix="bushenv-fmu-") as folder:
        s = (FMU3Slave if three else FMU2Slave)(
            guid=md.guid,
            unzipDirectory=extract(str(path), folder),
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName="bushenv",
        )
        if three:
            s.instantiate(logMessage=log) if log else s.instantiate()
            s.enterInitializationMode(startTime=start_s)
        else:
            s.instantiate()
            s.setupExperiment(startTime=start_s)
            s.enterInitializationMode()
        s.exitInitializationMode()
        try:
            yield s, vr, three
        finally:
            s.terminate()
            s.freeInstance()


def set_then_read(path, t_comm, x_comm, v_comm, log=None) -> np.ndarray:
    """At each communication point set the inputs, read the force, ``doStep`` to the next
    point. Returns the forces read, (len(t_comm),); ``log``: FMI 3 log-message callback."""
    with opened(path, log, float(t_comm[0])) as (s, vr, three):
        setf = s.setFloat64 if three else s.setReal
        getf = s.getFloat64 if three else s.getReal
        out = np.empty(len(t_comm))
        for j, t in enumerate(t_comm):
            setf([vr["deflection"]], [float(x_comm[j])])
            if "velocity" in vr:
                setf([vr["velocity"]], [float(v_comm[j])])
            out[j] = getf([vr["force"]])[0]
            if j + 1 < len(t_comm):
                s.doStep(
                    currentCommunicationPoint=float(t), communicationStepSize=t_comm[j + 1] - t
                )
        return out


def derivatives_then_step(path, t_comm, x_comm, v_comm) -> np.ndarray:
    """FMI 2: at each point set the inputs and their slope to the next point
    (``fmi2SetRealInputDerivatives``), ``doStep``, read the force at the next point before
    setting its input. Returns the forces at t_comm[1:]."""
    with opened(path, None, float(t_comm[0])) as (s, vr, three):
        if three:
            raise ValueError("input derivatives are an FMI 2 co-simulation feature")
        out = np.empty(len(t_comm) - 1)
        for j in range(len(t_comm) - 1):
            h = t_comm[j + 1] - t_comm[j]
            names = ["deflection"] + (["velocity"] if "velocity" in vr else [])
            vals = {"deflection": x_comm, "velocity": v_comm}
            for n in names:
                s.setReal([vr[n]], [float(vals[n][j])])
                s.setRealInputDerivatives([vr[n]], [1], [float((vals[n][j + 1] - vals[n][j]) / h)])
            s.doStep(currentCommunicationPoint=float(t_comm[j]), communicationStepSize=h)
            out[j] = s.getReal([vr["force"]])[0]
        return out


def model_exchange_rk4(path, t, x, v, substeps: int = 64) -> np.ndarray:
    """Model exchange through FMPy's FMU classes with a fixed-step RK4 of our own: per sample,
    ``substeps`` steps with the inputs linear within the sample (as ``boucwen_reference``),
    the FMU giving the derivatives. Returns the force at each sample (inputs set, then read)."""
    from ctypes import c_double

    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model
    from fmpy.fmi3 import FMU3Model

    md = read_model_description(str(path))
    vr = {var.name: var.valueReference for var in md.modelVariables}
    three = md.fmiVersion.startswith("3")
    with tempfile.TemporaryDirectory(prefix="bushenv-fmu-") as folder:
        m = (FMU3Model if three else FMU2Model)(
            guid=md.guid,
            unzipDirectory=extract(str(path), folder),
            modelIdentifier=md.modelExchange.modelIdentifier,
            instanceName="bushenv",
        )
        m.instantiate()
        if three:
            m.enterInitializationMode(startTime=float(t[0]))
        else:
            m.setupExperiment(startTime=float(t[0]))
            m.enterInitializationMode()
        m.exitInitializationMode()
        if not three:
            m.newDiscreteStates()
        m.enterContinuousTimeMode()
        setf = m.setFloat64 if three else m.setReal
        getf = m.getFloat64 if three else m.getReal
        deriv = m.getContinuousStateDerivatives if three else m.getDerivatives
        q, dq = (c_double * 4)(), (c_double * 4)()
        m.getContinuousStates(q, 4)

        def rhs(tt, xx, uu, state):
            m.setTime(tt)
            setf([vr["deflection"], vr["velocity"]], [xx, uu])
            m.setContinuousStates((c_double * 4)(*state), 4)
            deriv(dq, 4)
            return np.array(dq[:])

        out = np.empty(len(t))
        y = np.array(q[:])
        x0 = u0 = 0.0
        dt = t[1] - t[0]
        h = dt / substeps
        for k in range(len(t)):
            for i in range(substeps):  # from rest before t[0], as the reference
                a, mid, e = i / substeps, (i + 0.5) / substeps, (i + 1.0) / substeps
                ta = t[k] - dt + a * dt
                k1 = rhs(ta, x0 + a * (x[k] - x0), u0 + a * (v[k] - u0), y)
                xm, um = x0 + mid * (x[k] - x0), u0 + mid * (v[k] - u0)
                k2 = rhs(ta + h / 2, xm, um, y + h / 2 * k1)
                k3 = rhs(ta + h / 2, xm, um, y + h / 2 * k2)
                k4 = rhs(ta + h, x0 + e * (x[k] - x0), u0 + e * (v[k] - u0), y + h * k3)
                y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            m.setTime(float(t[k]))
            setf([vr["deflection"], vr["velocity"]], [float(x[k]), float(v[k])])
            m.setContinuousStates((c_double * 4)(*y), 4)
            out[k] = getf([vr["force"]])[0]
            m.completedIntegratorStep()
            x0, u0 = float(x[k]), float(v[k])
        m.terminate()
        m.freeInstance()
        return out
