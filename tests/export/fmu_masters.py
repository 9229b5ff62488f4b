"""Masters and inputs the export tests share: bushenv excitations, a master on FMPy's classes."""

import numpy as np

from bushenv import excitation as ex
from bushenv.models import PAPER_DT

AXIS = {"linear": "axial", "nn": "axial", "hybrid": "axial", "boucwen": "radial"}


def inputs():
    """Excitations from bushenv: (name, x) at the papers' rate."""
    dt = PAPER_DT
    return {
        "random n=1": ex.random_rpc(1.0, 4.0, dt, seed=0),
        "4 mm step": ex.step_hold(4e-3, 1.0, dt),
        "sines": ex.sine(2.0, 3e-3, 1.0, dt) + ex.sine(23.0, 0.4e-3, 1.0, dt),
    }


def set_then_read(path, t_comm, x_comm, v_comm, log=None):
    """A master on FMPy's FMU classes: at each point set the inputs, read the force, doStep to
    the next point. Returns the forces read, (len(t_comm),)."""
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave
    from fmpy.fmi3 import FMU3Slave

    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    three = md.fmiVersion.startswith("3")
    cls = FMU3Slave if three else FMU2Slave
    from fmpy import extract

    s = cls(
        guid=md.guid,
        unzipDirectory=extract(str(path)),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="test",
    )
    if three:
        s.instantiate(logMessage=log) if log else s.instantiate()
        s.enterInitializationMode(startTime=float(t_comm[0]))
    else:
        s.instantiate()
        s.setupExperiment(startTime=float(t_comm[0]))
        s.enterInitializationMode()
    s.exitInitializationMode()
    setf = s.setFloat64 if three else s.setReal
    getf = s.getFloat64 if three else s.getReal
    out = np.empty(len(t_comm))
    for j, t in enumerate(t_comm):
        setf([vr["deflection"]], [float(x_comm[j])])
        if "velocity" in vr:
            setf([vr["velocity"]], [float(v_comm[j])])
        out[j] = getf([vr["force"]])[0]
        if j + 1 < len(t_comm):
            s.doStep(currentCommunicationPoint=float(t), communicationStepSize=t_comm[j + 1] - t)
    s.terminate()
    s.freeInstance()
    return out
