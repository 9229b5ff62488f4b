"""One specimen, four programmes run as one session: a thermal drift to tell from relaxation.

A heat node fed by the specimen's own dissipated power ``c v^2`` (or a friction's ``|v|``) with
a leak of 60 s (off the candidate's grid of time constants), the heat carried over 20 s rests,
stiffness and damping lost in proportion to it (a quarter at the session's hottest). A strong
4 Hz sine heats it, a slow small sine lets it cool. The relaxing specimen (two Maxwell arms)
runs the same programmes. Used by the thermal tests and the two-record study.
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from bushenv.diagnose.fit import diagnose
from bushenv.records import Record

DT = 1 / 200.0
K, C = 2e5, 2e3  # N/m, N s/m
DURATION_S = 30.0
TAU_S, REST_S, LOSS = 60.0, 20.0, 0.25
ORDERS = {
    "hot first": ("hot", "broad", "slow", "mixed"),
    "slow first": ("slow", "mixed", "hot", "broad"),
}


def programmes() -> dict[str, np.ndarray]:
    """The four displacement programmes (m), 30 s at 200 Hz each."""
    rng = np.random.default_rng(1)
    t = np.arange(int(DURATION_S / DT)) * DT
    ramp = np.minimum(1.0, t / 0.5)

    def band(lo: float, hi: float, peak: float) -> np.ndarray:
        b, a = signal.butter(2, [lo * 2 * DT, hi * 2 * DT], btype="band")
        x = signal.lfilter(b, a, rng.normal(size=t.size))
        return peak * x / np.max(np.abs(x)) * ramp

    return {
        "hot": 4e-3 * np.sin(2 * np.pi * 4.0 * t) * ramp,
        "broad": band(0.3, 10.0, 3e-3),
        "slow": 1.5e-3 * np.sin(2 * np.pi * 0.5 * t) * ramp,
        "mixed": band(0.2, 4.0, 4e-3),
    }


def heat(v: np.ndarray, start: float, law: str = "viscous") -> np.ndarray:
    """theta' = P - theta / tau from ``start`` (J): P = c v^2 (viscous), or a friction's
    F0 |v| with F0 = c x 0.1 m/s (hysteretic)."""
    a = np.exp(-DT / TAU_S)
    power = C * v * v if law == "viscous" else C * 0.1 * np.abs(v)
    return signal.lfilter([DT], [1.0, -a], power, zi=[a * start])[0]


def thermal_forces(progs, order, warm: bool, law: str = "viscous") -> dict[str, np.ndarray]:
    """The session's forces: the heat follows the dissipated energy through ``order``;
    ``warm``: the specimen ran the hot programme just before."""
    top = max(float(np.max(heat(np.gradient(x, DT), 0.0, law))) for x in progs.values())
    h = float(heat(np.gradient(progs["hot"], DT), 0.0, law)[-1]) if warm else 0.0
    out = {}
    for name in order:
        x = progs[name]
        v = np.gradient(x, DT)
        theta = heat(v, h, law)
        out[name] = (1.0 - LOSS * theta / top) * (K * x + C * v)
        h = float(theta[-1]) * np.exp(-REST_S / TAU_S)
    return out


def relaxing_forces(progs) -> dict[str, np.ndarray]:
    """The same programmes on a relaxing specimen: two Maxwell arms (0.3 s, 5 s)."""
    out = {}
    for name, x in progs.items():
        f = K * x + C * np.gradient(x, DT)
        for tau, share in ((0.3, 0.3), (5.0, 0.2)):
            a = np.exp(-DT / tau)
            f = f + share * K * (x - signal.lfilter([(1 - a) / 2, (1 - a) / 2], [1, -a], x))
        out[name] = f
    return out


def diagnose_session(forces, progs, order, run_order: bool = False) -> dict:
    """The diagnosis of the session's records (0.5 % noise, seeded), the first as TRAIN;
    ``run_order``: it is told the order and the rests (not the start)."""
    rng = np.random.default_rng(7)
    recs = []
    for name in order:
        f = forces[name] + 0.005 * np.std(forces[name]) * rng.normal(size=forces[name].size)
        recs.append(Record.from_arrays(progs[name], f, DT, name=name))
    given = [(order[0], None)] + [(n, REST_S) for n in order[1:]] if run_order else None
    return diagnose(recs[0], recs[1:], run_order=given)
