"""Cases in forms no candidate shares, to calibrate and measure the partner test.

``make_partner_case(seed, index)`` draws a linear spring-damper specimen on the widened set's
bushing programmes, rates and noise with ``none``, one effect or two, each in a form that
neither the candidates, the widened set nor the reference rubber use:

- relaxation: a Maxwell arm with an **Eyring** (sinh) dashpot, ``h' = v - (s0 / k_a) sinh(k_a
  h / s0) / tau``: it relaxes faster the higher its stress (non-linear viscoelasticity);
- friction: a **Masing** hysteresis on a tanh backbone, ``F = F_r + 2 F_y tanh((x - x_r) d /
  (2 x_y)) d`` from the last reversal ``(x_r, F_r)`` in direction ``d``;
- hardening: a **tangent** law ``k_h (x_l tan(x / x_l) - x)``, its limit ``x_l`` drawn per side;
- thermal: a heat node fed by the power the specimen dissipates (its damper's, a relaxation
  arm's dashpot's, a friction's slip; a spring or a mass gives none), its leak faster with speed
  (forced convection), stiffness lost linearly and damping exponentially with the heat, at
  most a third of the stiffness anywhere in the session (a partner's dissipation heats too); the
  records run as **one session** in a drawn order, the heat carried over rests of 30-300 s, so
  TRAIN may start warm;
- delay: a **boxcar** average of the force channel over a few samples (linear phase);
- inertia: a fixture mass plus a **Basset** history force ``b int a(s) / sqrt(t - s) ds``.

One single-effect case in four has a **poor TRAIN** (a 1.5-4 Hz sine set at a third of the
TESTs' peak) that hardly excites the effect: the TESTs show it (``drawn["poor_train"]``).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy import signal

from bushenv.diagnose.validation.reference_cases import Case
from bushenv.diagnose.validation.widened_cases import (
    BUSHING_RATES_HZ,
    NOISE_FRACTION,
    OVERSAMPLE,
    TARGET_GAP,
    _logu,
    _noisy,
    visible_gap,
)
from bushenv.diagnose.validation.widened_programmes import bushing_programmes

EFFECTS = ("relaxation", "friction", "hardening", "thermal", "delay", "inertia")
SINGLES = ("none",) + EFFECTS
PAIR_EVERY = 4  # one case in four is a pair
MAX_LOSS = 0.33  # the most stiffness heat takes, anywhere in a session


@njit(cache=True)
def _eyring(x, dt, tau, s0_over_k):  # pragma: no cover - compiled
    """Arm deflection h of a Maxwell arm with an Eyring dashpot (m), sub-stepped explicitly."""
    h = np.zeros_like(x)
    cur = 0.0
    for i in range(1, x.size):
        dx = (x[i] - x[i - 1]) / 4.0
        for _ in range(4):
            cur += dx - dt / 4.0 / tau * s0_over_k * np.sinh(cur / s0_over_k)
        h[i] = cur
    return h


@njit(cache=True)
def _masing(x, f_y, x_y):  # pragma: no cover - compiled
    """Masing hysteresis on the tanh backbone ``f_y tanh(x / x_y)`` (N); a branch that meets
    the backbone's limit follows it (no ratcheting beyond +-f_y)."""
    out = np.zeros_like(x)
    x_r, f_r, d = 0.0, 0.0, 1.0
    for i in range(1, x.size):
        step = x[i] - x[i - 1]
        if step * d < 0:  # a reversal: the branch starts where the last one ended
            x_r, f_r, d = x[i - 1], out[i - 1], -d
        f = f_r + d * 2.0 * f_y * np.tanh(d * (x[i] - x_r) / (2.0 * x_y))
        out[i] = min(max(f, -f_y), f_y)
    return out


@njit(cache=True)
def _heat_loop(power, rate, dt, start):  # pragma: no cover - compiled
    out = np.empty_like(power)
    h = start
    for i in range(power.size):
        h += power[i] * dt - rate[i] * h
        out[i] = h
    return out


def _heat(power: np.ndarray, v: np.ndarray, dt: float, p: dict, start: float) -> np.ndarray:
    """Heat state (J) through one record from ``start``: leak 1 / tau (1 + |v| / v_0)."""
    rate = dt / p["tau_s"] * (1.0 + np.abs(v) / p["v0"])
    return _heat_loop(power, rate, dt, float(start))


def effect_force(name: str, p: dict, x: np.ndarray, dt: float) -> np.ndarray:
    """The force (N) effect ``name`` adds on the fine-grid motion ``x`` (thermal, delay: 0)."""
    v = np.gradient(x, dt)
    s = p["scale"]
    if name == "relaxation":
        return s * p["k_a"] * _eyring(x, dt, p["tau_s"], p["s0"])
    if name == "friction":
        return s * _masing(x, p["f_y"], p["x_y"])
    if name == "hardening":
        xl = np.where(x >= 0, p["x_l_pos"], p["x_l_neg"])
        return s * p["k"] * (xl * np.tan(np.clip(x / xl, -1.4, 1.4)) - x)
    if name == "inertia":
        a = np.gradient(v, dt)
        n = int(min(x.size, 2.0 / dt))
        kern = 1.0 / np.sqrt((np.arange(n) + 0.5) * dt)
        basset = signal.fftconvolve(a, kern)[: x.size] * dt
        return s * (p["mass"] * a + p["basset"] * basset)
    return np.zeros_like(x)


def dissipated_power(name: str, p: dict, force: np.ndarray, x: np.ndarray, dt: float):
    """The power (W) effect ``name`` dissipates, its force ``force`` on the motion ``x``: the
    relaxation arm's dashpot, the friction's slip (its force times the velocity less the
    elastic part it stores, ``F F' / k_0``); a spring's or a mass's energy comes back (0)."""
    v = np.gradient(x, dt)
    if name == "relaxation":  # the arm's force times its dashpot's rate v - h'
        h = force / (p["scale"] * p["k_a"])
        return np.maximum(force * (v - np.gradient(h, dt)), 0.0)
    if name == "friction":
        k0 = p["scale"] * p["f_y"] / p["x_y"]
        return np.maximum(force * v - force * np.gradient(force, dt) / k0, 0.0)
    return np.zeros_like(x)


def specimen_forces(label, p: dict, k, c, progs, order, rests_s) -> list[np.ndarray]:
    """Noise-free forces of every record (sampled), the thermal heat carried in ``order``."""
    return _session(label, p, k, c, progs, order, rests_s)[0]


def _session(label, p: dict, k, c, progs, order, rests_s) -> tuple[list[np.ndarray], float]:
    """The forces and the highest heat (J) the session reaches (0 without thermal)."""
    out: list[np.ndarray | None] = [None] * len(progs)
    heat = p.get("thermal", {}).get("warm", 0.0)
    top = 0.0
    for j, i in enumerate(order):
        x, dt = progs[i]
        v = np.gradient(x, dt)
        elastic, viscous = k * x, c * v
        own = {n: effect_force(n, p[n], x, dt) for n in label}
        extra = sum(own.values(), np.zeros_like(x))
        if "thermal" in label:
            q = p["thermal"]
            partner = sum(dissipated_power(n, p[n], f, x, dt) for n, f in own.items())
            theta = _heat(c * v * v + partner, v, dt, q, heat)
            top = max(top, float(np.max(theta)))
            soft = q["scale"] * theta
            f = (1 - soft) * (elastic + extra) + np.exp(-q["damping_ratio"] * soft) * viscous
            heat = float(theta[-1]) * np.exp(-rests_s[j] / q["tau_s"])
        else:
            f = elastic + extra + viscous
        if "delay" in label:
            n = p["delay"]["width"]
            f = np.convolve(f, np.ones(n) / n)[: f.size]
        out[i] = f[::OVERSAMPLE]
    return out, top


def member_visibility(label, p: dict, k, c, progs, order, rests_s) -> dict[str, list[float]]:
    """Per effect of ``label``, per record: the share of the record's force (noise-free, RMS)
    that the effect adds and the record's own spring, damper and offset cannot take. A record
    where an effect stays below the noise cannot show it: a held-out judge confirms an effect
    only where it shows in a record fitted and in one judged."""
    full = specimen_forces(label, p, k, c, progs, order, rests_s)
    out = {}
    for m in label:
        rest = tuple(n for n in label if n != m)
        without = specimen_forces(rest, {n: p[n] for n in rest}, k, c, progs, order, rests_s)
        shares = []
        for f, g, (x, dt) in zip(full, without, progs, strict=True):
            xs = x[::OVERSAMPLE]
            a = np.stack([xs, np.gradient(xs, dt * OVERSAMPLE), np.ones_like(xs)], axis=1)
            d = f - g
            r = d - a @ np.linalg.lstsq(a, d, rcond=None)[0]
            shares.append(round(float(np.sqrt(np.mean(r**2) / np.mean(f**2))), 4))
        out[m] = shares
    return out


def _draw(name: str, rng, k: float, c: float, x_peak: float, band_hz: float, dt: float) -> dict:
    if name == "relaxation":
        return {"scale": 1.0, "k_a": k * _logu(rng, 0.3, 1.0), "tau_s": _logu(rng, 0.05, 3.0),
                "s0": x_peak * _logu(rng, 0.3, 1.5)}  # fmt: skip
    if name == "friction":
        return {"scale": 1.0, "f_y": 0.1 * k * x_peak, "x_y": x_peak * _logu(rng, 0.01, 0.15)}
    if name == "hardening":
        return {"scale": 1.0, "k": k, "x_l_pos": x_peak * _logu(rng, 1.2, 3.0),
                "x_l_neg": x_peak * _logu(rng, 1.2, 3.0)}  # fmt: skip
    if name == "thermal":
        return {"scale": 1e-3 / (c * x_peak**2 * band_hz), "tau_s": _logu(rng, 20.0, 400.0),
                "v0": x_peak * band_hz * _logu(rng, 1.0, 5.0),
                "damping_ratio": _logu(rng, 0.5, 3.0), "warm": 0.0}  # fmt: skip
    if name == "delay":
        return {"scale": 1.0, "width": int(rng.integers(3, 9)) * OVERSAMPLE}
    return {"scale": 1.0, "mass": 0.1 * k / (2 * np.pi * band_hz) ** 2,
            "basset": 0.02 * k / (2 * np.pi * band_hz) ** 1.5}  # fmt: skip


def label_of(index: int, rng) -> tuple[str, ...]:
    if index % PAIR_EVERY == PAIR_EVERY - 1:
        a, b = rng.choice(len(EFFECTS), size=2, replace=False)
        return tuple(sorted((EFFECTS[a], EFFECTS[b]), key=EFFECTS.index))
    name = SINGLES[(index - index // PAIR_EVERY) % len(SINGLES)]
    return () if name == "none" else (name,)


def _poor_train(rng, dt: float, peak: float) -> np.ndarray:
    t = np.arange(int(24.0 / dt)) * dt
    freqs = rng.uniform(1.5, 4.0, size=3)
    blocks = np.array_split(t, 3)
    parts = [np.sin(2 * np.pi * f * (b - b[0])) for f, b in zip(freqs, blocks, strict=True)]
    x = np.concatenate(parts)
    return peak / 3 * x * np.minimum(1.0, t / 0.5)


def make_partner_case(
    seed: int, index: int, poor_train: bool | None = None, label: tuple[str, ...] | None = None
) -> Case:
    """Case ``index`` of partner run ``seed`` (deterministic); ``poor_train`` True / False
    forces the poor TRAIN on or off (None: one single-effect case in four); ``label`` forces
    the effects (a pair the drawn labels seldom hold, such as thermal + relaxation)."""
    from bushenv.records import Record

    rng = np.random.default_rng([seed, index, 41])
    drawn_label = label_of(index, rng)
    if label is None:
        label = drawn_label
    else:
        unknown = [n for n in label if n not in EFFECTS]
        if unknown or len(set(label)) != len(label) or not 1 <= len(label) <= 2:
            raise ValueError(f"label {label!r}: one or two distinct effects of {EFFECTS}")
        label = tuple(sorted(label, key=EFFECTS.index))
    rate = float(rng.choice(BUSHING_RATES_HZ))
    dt_f = 1.0 / (rate * OVERSAMPLE)
    train_x, test_x, info = bushing_programmes(rng, dt_f, rate)
    poor = len(label) == 1 and rng.random() < 0.25
    poor = poor if poor_train is None else poor_train
    peak = max(float(np.max(np.abs(x))) for x in train_x + test_x)
    if poor:
        train_x = [_poor_train(rng, dt_f, peak)]
    progs = [(x, dt_f) for x in train_x + test_x]
    judged = [i >= len(train_x) for i in range(len(progs))]
    k = _logu(rng, 1e5, 2e6)
    c = k * _logu(rng, 2e-3, 20e-3)
    band_hz = info["band_hz"][1]
    p = {n: _draw(n, rng, k, c, peak, band_hz, dt_f) for n in label}
    order = list(rng.permutation(len(progs))) if "thermal" in label else list(range(len(progs)))
    rests = [float(rng.uniform(30.0, 300.0)) for _ in progs]
    for n in label:  # each effect alone leaves its drawn share of the force to a linear fit
        target = _logu(rng, *TARGET_GAP)
        for _ in range(3):
            alone = {n: p[n]}
            gap = visible_gap(specimen_forces((n,), alone, k, c, progs, order, rests),
                              progs, [True] * len(progs))  # fmt: skip
            if gap <= 0 or n == "delay":
                break
            p[n]["scale"] *= target / gap
    if "thermal" in label and rng.random() < 0.5:  # the specimen ran warm before the session
        p["thermal"]["warm"] = 0.5 * _peak_heat(p["thermal"], c, progs)
    if "thermal" in label:  # at most a third of the stiffness lost, all through the session:
        # a partner's own dissipation heats too, as do a warm start and the heat carried over
        top = _session(label, p, k, c, progs, order, rests)[1]
        p["thermal"]["scale"] = min(p["thermal"]["scale"], MAX_LOSS / max(top, 1e-300))
    by_record = member_visibility(label, p, k, c, progs, order, rests)
    forces = specimen_forces(label, p, k, c, progs, order, rests)
    drawn = {"rate_hz": rate, **info, "poor_train": poor, "order": [int(i) for i in order],
             "rests_s": [round(r, 3) for r in rests],
             "k_n_per_m": round(k, 3), "c_ns_per_m": round(c, 4),
             "visible": round(visible_gap(forces, progs, judged), 4),
             "visible_by_record": by_record}  # fmt: skip
    noise = {"fraction": _logu(rng, *NOISE_FRACTION), "pink": False, "quantum": 0.0,
             "x_fraction": 0.0}  # fmt: skip
    drawn["noise_fraction"] = round(noise["fraction"], 5)
    records = []
    for i, (f, (x, dt)) in enumerate(zip(forces, progs, strict=True)):
        f, xs = _noisy(f, x[::OVERSAMPLE], rng, noise)
        name = "train" if i < len(train_x) else f"test{i - len(train_x) + 1}"
        records.append(Record.from_arrays(xs, f, dt * OVERSAMPLE, name=name))
    n_tr = len(train_x)
    return Case(index, label, records[:n_tr], records[n_tr:], False, drawn, None)


def _peak_heat(q: dict, c: float, progs) -> float:
    """The heat each record would reach alone from cold, at most (J)."""
    top = 0.0
    for x, dt in progs:
        v = np.gradient(x, dt)
        top = max(top, float(np.max(_heat(c * v * v, v, dt, q, 0.0))))
    return max(top, 1e-300)
