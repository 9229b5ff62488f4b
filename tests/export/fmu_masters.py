"""What the export tests share: bushenv excitations and FMPy-driven masters of an FMU.

The masters drive an exported FMU from outside, as an importer would: ``set_then_read`` (FMPy's
FMU classes) sets the inputs, then reads the outputs (many vehicle simulators do);
``derivatives_then_step`` gives FMI 2 input derivatives; ``fmpy_simulate`` is FMPy's own
``simulate_fmu`` (co-simulation: it reads after ``doStep``, before the next input; model
exchange: its solver, the samples as time events); ``libcosim`` is libcosim's execution (FMI
Library; ``pip install libcosimpy``), which sets the inputs, calls ``doStep``, then reads.
``backward_velocity`` is the velocity rule of the FMU and the rigs; ``held`` is bushenv's force
held over each sample, what the forces read at communication points are judged against.
``converged`` is the converged Bouc-Wen run (tests/models/boucwen_converged.py).

studies/2026-11-fmu-accuracy/fmu_accuracy.py, studies/2026-11-fmu-masters/fmu_masters_study.py
and scripts/bench_fmu.py use these masters too (``sys.path`` gets this folder).
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


def backward_velocity(x: np.ndarray, dt: float) -> np.ndarray:
    """(x_k - x_(k-1)) / dt along axis 0, x_(-1) = 0: the FMU's own velocity rule (and the
    rigs')."""
    x = np.asarray(x, dtype=float)
    return np.diff(x, axis=0, prepend=np.zeros((1, *x.shape[1:]))) / dt


def held(force: np.ndarray, t_comm: np.ndarray, dt: float) -> np.ndarray:
    """bushenv's ``force`` (one per sample) held over each sample, at the times ``t_comm``."""
    return force[np.floor(np.asarray(t_comm) / dt + 1e-6).astype(int)]


def ports(vr: dict):
    """The FMU's coordinates (``description.PORTS``): one, or axial, radial and rotation."""
    from bushenv.export.description import PORTS

    return PORTS[1] if "deflection" in vr else PORTS[3]


def set_then_read(path, t_comm, x_comm, v_comm=None, log=None) -> np.ndarray:
    """At each communication point set the inputs (``v_comm`` None: the deflection only, the
    FMU's own velocity), read the force, ``doStep`` to the next point. ``x_comm``, ``v_comm``
    (T,) or, for a three-axis FMU, (T, 3). Returns the forces read, (T,) or (T, 3); ``log``:
    FMI 3 log-message callback."""
    with opened(path, log, float(t_comm[0])) as (s, vr, three):
        setf = s.setFloat64 if three else s.setReal
        getf = s.getFloat64 if three else s.getReal
        ps = ports(vr)
        xs = np.asarray(x_comm, dtype=float).reshape(len(t_comm), -1)
        vs = None if v_comm is None else np.asarray(v_comm, dtype=float).reshape(len(t_comm), -1)
        vr_x, vr_v, vr_f = ([vr[getattr(p, a)] for p in ps] for a in ("x", "v", "f"))
        out = np.empty((len(t_comm), len(ps)))
        for j, t in enumerate(t_comm):
            setf(vr_x, [float(a) for a in xs[j]])
            if vs is not None:
                setf(vr_v, [float(a) for a in vs[j]])
            out[j] = getf(vr_f)
            if j + 1 < len(t_comm):
                s.doStep(
                    currentCommunicationPoint=float(t), communicationStepSize=t_comm[j + 1] - t
                )
        return out[:, 0] if np.ndim(x_comm) == 1 else out


def derivatives_then_step(path, t_comm, x_comm, v_comm=None) -> np.ndarray:
    """FMI 2: at each point set the inputs and their slope to the next point
    (``fmi2SetRealInputDerivatives``; ``v_comm`` None: the deflection only), ``doStep``, read
    the force at the next point before setting its input. Returns the forces at t_comm[1:]."""
    with opened(path, None, float(t_comm[0])) as (s, vr, three):
        if three:
            raise ValueError("input derivatives are an FMI 2 co-simulation feature")
        out = np.empty(len(t_comm) - 1)
        for j in range(len(t_comm) - 1):
            h = t_comm[j + 1] - t_comm[j]
            names = ["deflection"] + (["velocity"] if v_comm is not None else [])
            vals = {"deflection": x_comm, "velocity": v_comm}
            for n in names:
                s.setReal([vr[n]], [float(vals[n][j])])
                s.setRealInputDerivatives([vr[n]], [1], [float((vals[n][j + 1] - vals[n][j]) / h)])
            s.doStep(currentCommunicationPoint=float(t_comm[j]), communicationStepSize=h)
            out[j] = s.getReal([vr["force"]])[0]
        return out


def fmpy_simulate(path, t, x, h: float, fmi_type: str = "CoSimulation"):
    """FMPy's ``simulate_fmu`` on the record ``x`` at samples ``t`` ((T,), or (T, 3) for a
    three-axis FMU; the coordinates only: FMPy interpolates them linearly), output every ``h``.
    Returns (times, forces): forces (N,) or (N, 3)."""
    from fmpy import read_model_description, simulate_fmu

    md = read_model_description(str(path))
    ps = ports({v.name: v.valueReference for v in md.modelVariables})
    cols = np.asarray(x, dtype=float).reshape(len(t), -1)
    signal = np.array(
        list(zip(t, *cols.T, strict=True)),
        dtype=[("time", float)] + [(p.x, float) for p in ps],
    )
    res = simulate_fmu(
        str(path),
        stop_time=float(t[-1]),
        output_interval=h,
        input=signal,
        output=[p.f for p in ps],
        fmi_type=fmi_type,
        record_events=False,
    )
    forces = np.stack([res[p.f] for p in ps], axis=1)
    return res["time"], forces[:, 0] if np.ndim(x) == 1 else forces


def libcosim(path, t, x, h: float):
    """libcosim's execution (FMI 2 FMUs: libcosimpy 0.0.6 crashes loading an FMI 3 one) with
    the deflection only (an override manipulator sets it before
    each step; a last-value observer reads the force after it). libcosim counts time in whole
    nanoseconds: the step is ``h`` rounded up to one. Returns (times, forces): the force read
    after the step that ends at each time."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    step_ns = int(np.ceil(h * 1e9))
    execution = CosimExecution.from_step_size(step_ns)
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(path), instance_name="bushing"))
    vr = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    manipulator = CosimManipulator.create_override()
    execution.add_manipulator(manipulator)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    n = int(np.floor(t[-1] / (step_ns * 1e-9)))
    times = np.arange(1, n + 1) * step_ns * 1e-9
    out = np.empty(n)
    for k in range(n):
        x_k = float(np.interp(k * step_ns * 1e-9, t, x))
        manipulator.slave_real_values(index, [vr["deflection"]], [x_k])
        execution.step()
        out[k] = observer.last_real_values(index, [vr["force"]])[0]
    return times, out
