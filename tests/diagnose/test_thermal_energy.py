"""Thermal drift is recognised by what only it does: a slow loss of stiffness and damping that
follows the energy the specimen dissipates, whatever order the programmes run in and however
warm the specimen starts; relaxation follows the deflection history instead.

One specimen runs four programmes as one session: a heat node fed by its own dissipated power
``c v^2`` with a leak of 60 s (off the candidate's grid of time constants), the heat carried
over 20 s rests, stiffness and damping lost in proportion to it. A strong 4 Hz sine heats it, a
slow small sine lets it cool. The same programmes on a relaxing specimen (two Maxwell arms)
must be named relaxation, not thermal.
"""

import numpy as np
import pytest
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


def _programmes() -> dict[str, np.ndarray]:
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


def _heat(v: np.ndarray, start: float) -> np.ndarray:
    """theta' = c v^2 - theta / tau from ``start`` (J)."""
    a = np.exp(-DT / TAU_S)
    return signal.lfilter([DT], [1.0, -a], C * v * v, zi=[a * start])[0]


def _thermal_forces(progs, order, warm: bool) -> dict[str, np.ndarray]:
    """The session's forces: the heat follows the dissipated energy through ``order``."""
    top = max(float(np.max(_heat(np.gradient(x, DT), 0.0))) for x in progs.values())
    heat = float(_heat(np.gradient(progs["hot"], DT), 0.0)[-1]) if warm else 0.0
    out = {}
    for name in order:
        x = progs[name]
        v = np.gradient(x, DT)
        theta = _heat(v, heat)
        soft = LOSS * theta / top
        out[name] = (1.0 - soft) * (K * x + C * v)
        heat = float(theta[-1]) * np.exp(-REST_S / TAU_S)
    return out


def _relaxing_forces(progs) -> dict[str, np.ndarray]:
    out = {}
    for name, x in progs.items():
        f = K * x + C * np.gradient(x, DT)
        for tau, share in ((0.3, 0.3), (5.0, 0.2)):
            a = np.exp(-DT / tau)
            f = f + share * K * (x - signal.lfilter([(1 - a) / 2, (1 - a) / 2], [1, -a], x))
        out[name] = f
    return out


def _diagnose(forces, progs, order) -> dict:
    rng = np.random.default_rng(7)
    recs = []
    for name in order:
        f = forces[name] + 0.005 * np.std(forces[name]) * rng.normal(size=forces[name].size)
        recs.append(Record.from_arrays(progs[name], f, DT, name=name))
    return diagnose(recs[0], recs[1:])


@pytest.mark.parametrize(
    "order,warm", [("hot first", False), ("slow first", False), ("hot first", True)]
)
def test_a_drift_that_follows_the_dissipated_energy_is_named_thermal(order, warm):
    progs = _programmes()
    r = _diagnose(_thermal_forces(progs, ORDERS[order], warm), progs, ORDERS[order])
    assert r["effect"] == "thermal", (r["effect"], r["top_two"])
    assert r["shrink"] > 0.4


@pytest.mark.parametrize("order", list(ORDERS))
def test_a_memory_of_the_deflection_is_named_relaxation_not_thermal(order):
    progs = _programmes()
    r = _diagnose(_relaxing_forces(progs), progs, ORDERS[order])
    assert r["effect"] == "relaxation", (r["effect"], r["top_two"])
    assert "thermal" not in r["effect"].split("+")
