"""A co-simulation master on FMPy's FMU classes that sets the inputs, then reads the outputs.

FMPy's own ``simulate_fmu`` reads outputs after ``doStep`` and before it sets the next input;
many vehicle simulators set the inputs at t, then read the outputs at t (an output that
depends directly on an input asks for that). ``set_then_read`` is that master, for the tests,
docs/export.md's accuracy table and the benchmark.
"""

from __future__ import annotations

import tempfile
from contextlib import contextmanager

import numpy as np


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
