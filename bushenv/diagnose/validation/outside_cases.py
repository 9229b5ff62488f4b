"""Blind cases whose gap comes from an effect **outside** the candidate set.

``make_outside_case(seed, index)`` draws a linear spring-damper specimen on the widened set's
bushing programmes, rates and noise (``widened_programmes``, ``widened_cases``), plus one
effect none of the candidates models, cycling over ``FORMS``:

- ``backlash``: a clearance in the fixture; the specimen follows the machine through a play
  operator of half-width ``g`` (rate-independent, but a dead band, not a friction element);
- ``mullins``: stress softening by the largest deflection reached so far in the record
  (``k (1 - m max|x|_past / x_peak)``): memory of the amplitude, not of dissipated heat;
- ``zero_drift``: the load cell's zero drifting during each record (a slow ramp plus a slow
  sinusoid, uncorrelated with the motion);
- ``hum``: mains pickup on the force channel (50 Hz or 60 Hz and a third harmonic).

Each effect is scaled so that alone it leaves a drawn share (``TARGET_GAP``) of the force to a
linear fit, as the widened set scales its effects. The right answer is
``outside_candidates``; any named effect is an effect that is not there.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from bushenv.diagnose.rule import OUTSIDE
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

FORMS = ("backlash", "mullins", "zero_drift", "hum")


@njit(cache=True)
def _play(x: np.ndarray, g: float) -> np.ndarray:
    """Play (backlash) operator of half-width ``g``: y moves only when |x - y| exceeds g."""
    y = np.empty_like(x)
    cur = 0.0
    for i, xi in enumerate(x):
        cur = min(max(cur, xi - g), xi + g)
        y[i] = cur
    return y


def outside_force(form: str, p: dict[str, Any], k: float, c: float, x: np.ndarray, dt: float):
    """Measured force (N) of the linear specimen ``k``, ``c`` with ``form`` at strength
    ``p["scale"]`` on the fine-grid motion ``x`` (m)."""
    s = p["scale"]
    if form == "backlash":
        y = _play(x, s * p["x_peak"])
        return k * y + c * np.gradient(y, dt)
    v = np.gradient(x, dt)
    base = k * x + c * v
    t = np.arange(x.size) * dt
    if form == "mullins":
        reached = np.maximum.accumulate(np.abs(x)) / p["x_peak"]
        return base - s * k * reached * x
    f_rms = float(np.sqrt(np.mean(base**2)))
    if form == "zero_drift":
        ramp = t / max(t[-1], dt) * p["sign"]
        wave = np.sin(2 * np.pi * t / p["period_s"] + p["phase"])
        return base + s * f_rms * (ramp + 0.5 * wave)
    if form == "hum":
        w = 2 * np.pi * p["mains_hz"] * t
        return base + s * f_rms * (np.sin(w + p["phase"]) + 0.3 * np.sin(3 * w))
    raise ValueError(f"unknown outside form {form!r}; known: {', '.join(FORMS)}")


def _draw(form: str, rng, x_peak: float) -> dict[str, Any]:
    return {
        "scale": 0.1,
        "x_peak": x_peak,
        "sign": float(rng.choice([-1.0, 1.0])),
        "period_s": _logu(rng, 5.0, 30.0),
        "phase": float(rng.uniform(0, 2 * np.pi)),
        "mains_hz": float(rng.choice([50.0, 60.0])),
    }


def make_outside_case(seed: int, index: int) -> Case:
    """Case ``index`` of outside run ``seed`` (deterministic): label ``outside_candidates``."""
    from bushenv.records import Record

    rng = np.random.default_rng([seed, index, 23])
    form = FORMS[index % len(FORMS)]
    rate = float(rng.choice([r for r in BUSHING_RATES_HZ if r >= 200.0]))  # hum below Nyquist
    dt_f = 1.0 / (rate * OVERSAMPLE)
    train_x, test_x, info = bushing_programmes(rng, dt_f, rate)
    progs = [(x, dt_f) for x in train_x + test_x]
    judged = [i >= len(train_x) for i in range(len(progs))]
    k = _logu(rng, 1e5, 2e6)
    c = k * _logu(rng, 2e-3, 20e-3)
    x_peak = max(float(np.max(np.abs(x))) for x, _ in progs)
    p = _draw(form, rng, x_peak)
    target = _logu(rng, *TARGET_GAP)

    def forces() -> list[np.ndarray]:
        return [outside_force(form, p, k, c, x, dt)[::OVERSAMPLE] for x, dt in progs]

    for _ in range(4):  # scale the effect to its visible target (all records together)
        gap = visible_gap(forces(), progs, [True] * len(progs))
        if gap <= 0:
            break
        p["scale"] *= target / gap
        if form in ("backlash", "mullins"):  # a clearance or a softening beyond the stroke
            p["scale"] = min(p["scale"], 0.5)
    visible = round(visible_gap(forces(), progs, judged), 4)
    drawn = {"rate_hz": rate, **info, "form": form, "k_n_per_m": round(k, 3),
             "c_ns_per_m": round(c, 4), "visible": visible}  # fmt: skip
    noise = {"fraction": _logu(rng, *NOISE_FRACTION), "pink": False, "quantum": 0.0,
             "x_fraction": 0.0}  # fmt: skip
    drawn["noise_fraction"] = round(noise["fraction"], 5)
    records = []
    for i, (f, (x, dt)) in enumerate(zip(forces(), progs, strict=True)):
        f, xs = _noisy(f, x[::OVERSAMPLE], rng, noise)
        name = "train" if i < len(train_x) else f"test{i - len(train_x) + 1}"
        records.append(Record.from_arrays(xs, f, dt * OVERSAMPLE, name=name))
    n_tr = len(train_x)
    return Case(index, (OUTSIDE,), records[:n_tr], records[n_tr:], False, drawn, None)
