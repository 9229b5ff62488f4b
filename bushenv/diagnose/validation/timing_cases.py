"""The records the diagnosis is timed on (``scripts/bench.py``, the speed study).

``rubber_records``: the reference rubber with all its effects under RPC-like random at
amplitude indices 1, 1, 1.3 and 1.5, the last record with a held step too: every record shows
the gap. ``lone_records``: a spring-damper behind a fixture mass, the first record RPC-like
random (the mass shows), the others 0.3 Hz sines (it does not): one record alone shows the gap,
and the diagnosis judges it again half against half (``diagnose/halves.py``).
"""

from __future__ import annotations

import numpy as np

from bushenv import excitation as ex
from bushenv.records import Record
from bushenv.reference.rubber import RubberBushing

N_INDEX = (1.0, 1.0, 1.3, 1.5)
K, C, MASS = 2e5, 2e3, 2.0  # N/m, N s/m, kg (the mass: 16 % of k x at 20 Hz, the band's top)


def rubber_records(lengths_s, dt: float) -> list[Record]:
    """Four records ``rec0``-``rec3`` of ``lengths_s`` (s) of the reference rubber."""
    ref = RubberBushing.preset("axial", dt=dt, seed=0)
    out = []
    for i, (seconds, n) in enumerate(zip(lengths_s, N_INDEX, strict=True)):
        x = ex.random_rpc(n, seconds, dt, seed=i)
        if i == 3:  # the last holds a step too
            x = ex.sequence(x, ex.step_hold(3e-3, 0.25 * seconds, dt, rise_s=0.05))
        ref.reset()
        out.append(Record.from_arrays(x, ref.simulate(x), dt, name=f"rec{i}"))
    return out


def lone_records(lengths_s, dt: float) -> list[Record]:
    """Records ``rec0``, ... of ``lengths_s`` (s): only ``rec0`` shows the mass; 0.5 % noise."""
    out = []
    for i, seconds in enumerate(lengths_s):
        t = np.arange(int(round(seconds / dt))) * dt
        if i == 0:
            x = ex.random_rpc(1.0, seconds, dt, seed=i)
        else:
            x = 2e-3 * np.sin(2 * np.pi * 0.3 * t + i)
        v = np.gradient(x, dt)
        f = K * x + C * v + MASS * np.gradient(v, dt)
        f = f + 0.005 * np.std(f) * np.random.default_rng(i).normal(size=f.size)
        out.append(Record.from_arrays(x, f, dt, name=f"rec{i}"))
    return out
