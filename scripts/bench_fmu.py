"""The exported NN's step (``bushenv export``, docs/export.md) beside bushenv's own step.

Three ways of taking one sample of the shipped axial NN on a random n = 1 record, same run:

* bushenv: ``NarxBushing.step(x, v)`` on floats (the gym environments' call, numba kernel);
* through FMPy: ``setReal``, ``getReal``, ``doStep`` on FMPy's ``FMU2Slave`` (what a Python
  importer pays per sample: ctypes calls, argument arrays);
* compiled, measured in C: a small harness compiled on the fly against the FMU's own sources
  times ``model_step`` alone and the FMI 2 calls (set, get, doStep) per sample, no Python.

Targets: the FMPy step at most 10x bushenv's, the compiled step within 2x.
"""

from __future__ import annotations

import subprocess
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <time.h>
#include <stdlib.h>
#include "fmi2.c"

static void quiet(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c,
                  fmi2String m, ...) { (void)e; (void)n; (void)s; (void)c; (void)m; }

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

int main(int argc, char **argv) {
    long n = atol(argv[1]), reps = atol(argv[2]);
    double *x = malloc(n * sizeof(double)), *v = malloc(n * sizeof(double)), sum = 0.0;
    FILE *f = fopen(argv[3], "rb");
    if (fread(x, sizeof(double), n, f) != (size_t)n || fread(v, sizeof(double), n, f) != (size_t)n)
        return 1;
    fclose(f);
    double s[MODEL_N_STATE];
    double t0 = now();
    for (long r = 0; r < reps; r++) {
        model_reset(s);
        for (long i = 0; i < n; i++) sum += model_step(s, x[i], v[i]);
    }
    double model_s = (now() - t0) / (n * reps);
    fmi2CallbackFunctions cb = {quiet, NULL, NULL, NULL, NULL};
    fmi2ValueReference vx = VR_DEFLECTION, vv = VR_VELOCITY, vf = VR_FORCE;
    t0 = now();
    for (long r = 0; r < reps; r++) {
        fmi2Component c = fmi2Instantiate("h", fmi2CoSimulation, FMU_TOKEN, "", &cb, 0, 0);
        fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0);
        fmi2EnterInitializationMode(c);
        fmi2ExitInitializationMode(c);
        for (long i = 0; i < n; i++) {
            double force;
            fmi2SetReal(c, &vx, 1, &x[i]);
            if (HAS_VELOCITY) fmi2SetReal(c, &vv, 1, &v[i]);
            fmi2GetReal(c, &vf, 1, &force);
            sum += force;
            fmi2DoStep(c, i * MODEL_DT_S, MODEL_DT_S, fmi2True);
        }
        fmi2FreeInstance(c);
    }
    double fmi_s = (now() - t0) / (n * reps);
    printf("%.6g %.6g %.17g\n", 1e6 * model_s, 1e6 * fmi_s, sum);
    return 0;
}
"""


def c_step_us(fmu: Path, x: np.ndarray, v: np.ndarray, reps: int) -> tuple[float, float]:
    """(model_step alone, FMI 2 set/get/doStep) in us per sample, timed in C."""
    from bushenv.export import c_compiler
    from bushenv.export.build import CFLAGS

    flags = [f for f in CFLAGS if f not in ("-shared", "-fPIC", "-fvisibility=hidden")]
    with tempfile.TemporaryDirectory(prefix="bushenv-bench-") as tmp:
        folder = Path(tmp)
        with zipfile.ZipFile(fmu) as zf:
            for name in zf.namelist():
                if name.startswith("sources/"):
                    (folder / Path(name).name).write_bytes(zf.read(name))
        (folder / "harness.c").write_text(HARNESS)
        (folder / "inputs.bin").write_bytes(
            np.ascontiguousarray(x, "<f8").tobytes() + np.ascontiguousarray(v, "<f8").tobytes()
        )
        exe = folder / "harness"
        subprocess.run(
            [c_compiler(), *flags, "-o", str(exe), str(folder / "harness.c"), "-lm"],
            check=True,
            capture_output=True,
        )
        out = subprocess.run(
            [str(exe), str(len(x)), str(reps), str(folder / "inputs.bin")],
            check=True,
            capture_output=True,
            text=True,
        ).stdout.split()
    return float(out[0]), float(out[1])


def fmpy_step_us(fmu: Path, x: np.ndarray, v: np.ndarray, min_time: float) -> float:
    """setReal, getReal, doStep per sample on FMPy's FMU2Slave, us per sample."""
    from fmu_masters import opened  # tests/export, on sys.path by bench.py

    with opened(fmu) as (s, vr, _):
        vx, vf = [vr["deflection"]], [vr["force"]]
        dt = 1.0 / 204.8
        n, t0, done = len(x), time.perf_counter(), 0
        while done == 0 or time.perf_counter() - t0 < min_time:
            for i in range(n):
                s.setReal(vx, [x[i]])
                s.getReal(vf)
                s.doStep(currentCommunicationPoint=(done + i) * dt, communicationStepSize=dt)
            done += n
        return 1e6 * (time.perf_counter() - t0) / done


def bench_fmu(fig, quick: bool) -> None:
    from bushenv.excitation import random_rpc
    from bushenv.export import export_fmu
    from bushenv.models import get_model

    model = get_model("nn", axis="axial")
    x = random_rpc(1.0, 2.0 if quick else 20.0, model.dt, seed=0)
    v = np.gradient(x, model.dt)
    min_time = 0.05 if quick else 1.0
    with tempfile.TemporaryDirectory(prefix="bushenv-bench-") as tmp:
        fmu = export_fmu(model, Path(tmp) / "nn.fmu", "2.0").path
        model.reset(1)
        for i in range(len(x)):  # warm
            model.step(float(x[i]), float(v[i]))
        reps, t0 = 0, time.perf_counter()
        while reps == 0 or time.perf_counter() - t0 < min_time:
            model.reset(1)
            for i in range(len(x)):
                model.step(float(x[i]), float(v[i]))
            reps += 1
        own = 1e6 * (time.perf_counter() - t0) / (reps * len(x))
        fig.add(
            "fmu.nn.bushenv_step",
            own,
            "us/step",
            better="lower",
            note="NarxBushing.step on floats, one profile",
        )
        through = fmpy_step_us(fmu, x, v, min_time)
        fig.add(
            "fmu.nn.fmpy_step",
            through,
            "us/step",
            better="lower",
            note="FMPy 0.3.32 FMU2Slave: setReal, getReal, doStep per sample",
        )
        fig.add(
            "fmu.nn.fmpy_over_bushenv",
            through / own,
            "x",
            10.0,
            better="lower",
            note="the importer's ctypes overhead over bushenv's step",
        )
        alone, api = c_step_us(fmu, x, v, 20 if quick else 200)
        fig.add(
            "fmu.nn.c_model_step",
            alone,
            "us/step",
            better="lower",
            note="the generated model_step alone, timed in C",
        )
        fig.add(
            "fmu.nn.c_fmi_step",
            api,
            "us/step",
            better="lower",
            note="fmi2SetReal + fmi2GetReal + fmi2DoStep, timed in C",
        )
        fig.add(
            "fmu.nn.c_fmi_over_bushenv",
            api / own,
            "x",
            2.0,
            better="lower",
            note="the compiled FMU's step over bushenv's",
        )
