"""The reference blind validation set: the reference rubber bushing with switchable effects.

``make_case(seed, index)`` draws, from ``(seed, index)``, a ``bushenv.reference.rubber``
bushing with a hidden label -- ``none`` (backbone + noise), one effect, or two -- and simulates
a TRAIN record and two TEST records.

| what            | drawn                                                                        |
|-----------------|------------------------------------------------------------------------------|
| backbone        | k log-uniform 150..1500 kN/m, c = k * (4..20) ms                             |
| relaxation      | 1..5 Maxwell branches, tau log-uniform 0.01..10 s, each k_i = k * (0.08..0.4) |
| friction        | Berg or Iwan law, F_max = (4..18) % of k x_pk, x2 = (2..15) % of x_pk         |
| hardening       | cubic, tangent or exponential (sinh) law, 4..25 % extra force at the TEST peak |
| thermal         | heating by the reference's own dissipated power, time constant 20..300 s,    |
|                 | stiffness drop 4..20 % over TRAIN, a_c/a_k 0.5..3                            |
| delay           | 0.4..8 ms, linear interpolation inside the reference                         |
| inertia         | fixture mass with m (2 pi 15 Hz)^2 / k = 3..30 %, backward-difference accel. |
| noise           | always on: std log-uniform 0.2..3 % of the backbone force RMS                |
| sample rate     | 204.8, 512 or 1024 Hz; in a third of the cases the TESTs run at another rate |
| records         | TRAIN: RPC-like random n = 0.8..1.2, 20..60 s, then a held step 2..4 mm;     |
|                 | TEST 1: RPC-like random n = 1.2..1.6, 8..25 s; TEST 2: a step held 3..10 s,  |
|                 | then a sine (1..15 Hz) or a chirp (0.5..20 Hz)                               |

The case mix: three cases in four are single-class (cycling through ``none`` and the effects
that have a draw here), one in four a random pair. ``DRAWS`` holds one parameter draw per
effect, keyed by the candidates' names (declared on their classes); each draw sets the
parameters of the reference's effect of that name (``bushenv.reference.rubber.REFERENCE_EFFECTS``,
the specimen's own list: a test holds the two together).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bushenv.diagnose.candidates import effect_names
from bushenv.diagnose.effects.backbone import Hardening
from bushenv.diagnose.effects.delay import Delay
from bushenv.diagnose.effects.friction import Friction
from bushenv.diagnose.effects.inertia import Inertia
from bushenv.diagnose.effects.relaxation import Relaxation
from bushenv.diagnose.effects.thermal import Thermal

RATES_HZ = (204.8, 512.0, 1024.0)


@dataclass
class Case:
    """One blind case: hidden label, records, diagnosis mode and what was drawn."""

    index: int
    label: tuple[str, ...]  # () for none
    train: list[Any]
    tests: list[Any]
    cross: bool = False
    drawn: dict[str, Any] = field(default_factory=dict)
    truth: Any = None  # the simulated specimen, for inspection (never shown to the diagnosis)

    @property
    def label_text(self) -> str:
        return "+".join(self.label) if self.label else "none"


def _loguniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


@dataclass
class Draw:
    """What a parameter draw may use: the generator, backbone, TEST peak and TRAIN motion."""

    rng: np.random.Generator
    k: float
    c: float
    x_pk: float
    x_train: np.ndarray
    dt_train: float


def _relaxation(d: Draw) -> dict[str, Any]:
    n = int(d.rng.integers(1, 6))
    ks = tuple(d.k * d.rng.uniform(0.08, 0.4) for _ in range(n))
    taus = tuple(_loguniform(d.rng, 0.01, 10.0) for _ in range(n))
    return {"relax_k_n_per_m": ks, "relax_tau_s": taus}


def _friction(d: Draw) -> dict[str, Any]:
    return {
        "friction_law": str(d.rng.choice(["berg", "iwan"])),
        "friction_fmax_n": d.rng.uniform(0.04, 0.18) * d.k * d.x_pk,
        "friction_x2_m": d.rng.uniform(0.02, 0.15) * d.x_pk,
    }


def _hardening(d: Draw) -> dict[str, Any]:
    law = str(d.rng.choice(["cubic", "tangent", "exponential"]))
    extra = d.rng.uniform(0.04, 0.25)  # extra force at the TEST peak
    # g(x) ~ x (1 + (x/xh)^2 / q) for small x: q = 1 cubic, 3 tangent, 6 sinh
    q = {"cubic": 1.0, "tangent": 3.0, "exponential": 6.0}[law]
    return {"hardening_law": law, "hardening_x_m": d.x_pk / np.sqrt(q * extra)}


def _delay(d: Draw) -> dict[str, Any]:
    return {"delay_s": d.rng.uniform(0.4e-3, 8e-3)}


def _inertia(d: Draw) -> dict[str, Any]:
    return {"fixture_mass_kg": d.rng.uniform(0.03, 0.3) * d.k / (2 * np.pi * 15.0) ** 2}


def _thermal(d: Draw) -> dict[str, Any]:
    v = np.gradient(d.x_train, d.dt_train)
    energy = float(np.sum(d.c * v * v) * d.dt_train)  # J dissipated in the damper over TRAIN
    tau = d.rng.uniform(20.0, 300.0)
    rise = d.rng.uniform(5.0, 30.0)  # K, roughly, at the end of TRAIN
    heat_cap = energy / rise
    drop = d.rng.uniform(0.04, 0.2)
    ak = drop / rise
    return {
        "thermal_c_j_per_k": heat_cap,
        "thermal_r_k_per_w": tau / heat_cap,
        "thermal_ak_per_k": ak,
        "thermal_ac_per_k": ak * d.rng.uniform(0.5, 3.0),
    }


# One draw per effect, in the order the draws consume random numbers.
DRAWS: dict[str, Callable[[Draw], dict[str, Any]]] = {
    Relaxation.name: _relaxation,
    Friction.name: _friction,
    Hardening.name: _hardening,
    Delay.name: _delay,
    Inertia.name: _inertia,
    Thermal.name: _thermal,
}


def classes() -> tuple[str, ...]:
    """``none`` and every registered candidate effect this set can draw."""
    return ("none",) + tuple(e for e in effect_names() if e in DRAWS)


def case_label(index: int, rng: np.random.Generator) -> tuple[str, ...]:
    """Balanced mix: index % 4 == 3 is a random pair, the rest cycle through the classes."""
    effects = classes()[1:]
    if index % 4 == 3:
        pair = rng.choice(len(effects), size=2, replace=False)
        return tuple(effects[i] for i in sorted(pair))
    single = index - (index + 1) // 4  # how many single-class cases came before
    name = classes()[single % len(classes())]
    return () if name == "none" else (name,)


def _programmes(rng: np.random.Generator, dt_train: float, dt_test: float, seed: int):
    from bushenv import excitation as ex

    n_train = rng.uniform(0.8, 1.2)
    d_train = rng.uniform(20.0, 60.0)
    step = rng.uniform(2e-3, 4e-3) * rng.choice([-1.0, 1.0])
    hold = rng.uniform(3.0, 8.0)
    x_train = ex.sequence(
        ex.random_rpc(n_train, d_train, dt_train, seed),
        ex.step_hold(step, hold, dt_train, pre_s=0.5, rise_s=0.05),
        step - ex.step_hold(step, 2.0, dt_train, pre_s=0.0, rise_s=0.05),
    )
    n_test = rng.uniform(1.2, 1.6)
    x_test1 = ex.random_rpc(n_test, rng.uniform(8.0, 25.0), dt_test, seed + 1)
    step2 = rng.uniform(2e-3, 4e-3) * rng.choice([-1.0, 1.0])
    hold2 = rng.uniform(3.0, 10.0)
    if rng.random() < 0.5:
        tail = ex.sine(rng.uniform(1.0, 15.0), rng.uniform(1e-3, 3e-3), rng.uniform(4, 10), dt_test)
        tail_name = "sine"
    else:
        tail = ex.chirp(0.5, 20.0, rng.uniform(1e-3, 2.5e-3), rng.uniform(8, 20), dt_test)
        tail_name = "chirp"
    x_test2 = ex.sequence(
        ex.step_hold(step2, hold2, dt_test, pre_s=0.5, rise_s=0.05),
        step2 - ex.step_hold(step2, 1.0, dt_test, pre_s=0.0, rise_s=0.05),
        tail,
    )
    info = {
        "train_s": round(x_train.size * dt_train, 2),
        "test_s": [round(x_test1.size * dt_test, 2), round(x_test2.size * dt_test, 2)],
        "test2": f"step {1e3 * step2:.2f} mm held {hold2:.1f} s + {tail_name}",
    }
    return x_train, [x_test1, x_test2], info


def make_case(seed: int, index: int) -> Case:
    """Draw case ``index`` of validation run ``seed``: reference bushing, records, label."""
    from bushenv.records import Record
    from bushenv.reference.rubber import RubberBushing

    rng = np.random.default_rng([seed, index])
    label = case_label(index, rng)
    rate_train = float(rng.choice(RATES_HZ))
    rate_test = float(rng.choice(RATES_HZ)) if rng.random() < 1 / 3 else rate_train
    dt_train, dt_test = 1.0 / rate_train, 1.0 / rate_test
    case_seed = int(rng.integers(0, 2**31 - 1))
    x_train, x_tests, info = _programmes(rng, dt_train, dt_test, case_seed)

    k = _loguniform(rng, 150e3, 1.5e6)
    c = k * rng.uniform(0.004, 0.02)
    x_pk = max(float(np.max(np.abs(x))) for x in x_tests)
    params: dict[str, Any] = {"k_n_per_m": k, "c_ns_per_m": c}
    drawn: dict[str, Any] = {"rate_train_hz": rate_train, "rate_test_hz": rate_test, **info}
    draw = Draw(rng, k, c, x_pk, x_train, dt_train)
    for name, fn in DRAWS.items():
        if name in label:
            params.update(fn(draw))
    drawn.update({k: v for k, v in params.items() if k.endswith("_law")})

    # noise relative to the backbone force RMS on TRAIN
    backbone = k * x_train + c * np.gradient(x_train, dt_train)
    noise_frac = _loguniform(rng, 0.002, 0.03)
    noise_std = noise_frac * float(np.sqrt(np.mean(backbone**2)))
    drawn["noise_fraction"] = round(noise_frac, 4)

    def simulate(x: np.ndarray, dt: float, noise_seed: int) -> np.ndarray:
        model = RubberBushing(dt=dt, seed=noise_seed, noise_std_n=noise_std, **params)
        return model.simulate(x)

    f_train = simulate(x_train, dt_train, case_seed + 11)
    train = Record.from_arrays(x_train, f_train, dt_train, name="train")
    tests = []
    for j, x in enumerate(x_tests):
        f = simulate(x, dt_test, case_seed + 12 + j)
        tests.append(Record.from_arrays(x, f, dt_test, name=f"test{j + 1}"))
    return Case(index, label, [train], tests, False, drawn)
