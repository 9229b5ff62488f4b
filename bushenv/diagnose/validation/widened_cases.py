"""The widened blind validation set: specimens and programmes the candidates do not assume.

``make_widened_case(seed, index)`` draws, from ``(seed, index)`` only, a hidden label (none, one
effect or two), each effect in one of several forms (``truth_forms.TRUTH_EFFECTS``: power-law,
stretched-exponential, log-normal and off-grid Prony relaxation; Bouc-Wen, skewed Iwan,
smoothed Coulomb and Payne amplitude softening; asymmetric, softening, bump-stop, exponential
and Gent backbones; self-heating; pure and Bessel-filter delays; rigid and resonant fixtures),
its visible strength (each member of a pair on its own), programmes (random, multisine,
sweeps, sine blocks at several amplitudes, step-holds, constant-rate ramps), sample rates,
record lengths and noise (white, pink, quantised, on the displacement too). One case in five
is quasi-static: 50 Hz constant-rate pulls of 40-160 mm and relaxation holds, diagnosed with
``cross=True`` (leave one record out). The specimen runs on a grid four times finer than the
records and is sampled.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bushenv.diagnose.effects.backbone import Hardening
from bushenv.diagnose.effects.delay import Delay
from bushenv.diagnose.effects.friction import Friction
from bushenv.diagnose.effects.inertia import Inertia
from bushenv.diagnose.effects.relaxation import Relaxation
from bushenv.diagnose.effects.thermal import Thermal
from bushenv.diagnose.validation import truth_forms as tf
from bushenv.diagnose.validation.reference_cases import Case
from bushenv.diagnose.validation.widened_programmes import (
    bushing_programmes,
    quasi_static_programmes,
    regrid,
)

BUSHING_RATES_HZ = (100.0, 200.0, 204.8, 256.0, 500.0, 512.0, 1000.0, 1024.0, 2048.0)
QUASI_STATIC_RATE_HZ = 50.0
OVERSAMPLE = 4
TARGET_GAP = (0.04, 0.3)  # visible strength of one effect: linear-fit residual / force RMS
NOISE_FRACTION = (0.001, 0.03)
MAX_THERMAL_DROP = 0.35  # stiffness lost to heating, at most
ATTEMPTS = 6  # programmes are drawn again while an effect cannot be seen in them


def _logu(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


# ----- the specimen ----------------------------------------------------------------------------
@dataclass
class Specimen:
    """Linear spring and damper plus drawn effects: ``effects[name] = (form, params)``."""

    k_n_per_m: float
    c_ns_per_m: float
    effects: dict[str, tuple[str, dict[str, Any]]] = field(default_factory=dict)

    def force(self, x: np.ndarray, dt: float) -> np.ndarray:
        """Noise-free measured force (N) for the fine-grid motion ``x`` (m), (T,)."""
        v = np.gradient(x, dt)
        a = np.gradient(v, dt)
        elastic = self.k_n_per_m * x
        extra = np.zeros_like(x)
        for name, (form, p) in self.effects.items():
            if tf.TRUTH_EFFECTS[name].stage != "specimen":
                continue
            f = tf.form_force(name, form, p, x, v, a, dt)
            if name == Hardening.name:
                elastic = elastic + f
            else:
                extra = extra + f
        viscous = self.c_ns_per_m * v
        if Thermal.name in self.effects:
            p = self.effects[Thermal.name][1]
            power = self.c_ns_per_m * v * v + np.abs(extra * v)
            fac = tf.thermal_factor(p, power, dt)
            out = fac * (elastic + extra) + fac ** p["viscous_ratio"] * viscous
        else:
            out = elastic + extra + viscous
        if Inertia.name in self.effects:
            form, p = self.effects[Inertia.name]
            out = out + tf.inertia_force(a, p, dt, form)
        if Delay.name in self.effects:
            form, p = self.effects[Delay.name]
            out = tf.delayed(out, p, dt, form)
        return out


Programme = tuple[np.ndarray, float]  # fine-grid motion (m) and its sample time (s)


def _sampled(specimen: Specimen, progs: list[Programme]) -> list[np.ndarray]:
    return [specimen.force(x, dt)[::OVERSAMPLE] for x, dt in progs]


def visible_gap(forces: list[np.ndarray], progs: list[Programme], judged: list[bool]) -> float:
    """What a linear spring-damper fitted on all records leaves on the judged records: RMS
    of the residual over the force RMS (noise-free)."""
    cols = []
    for x, dt in progs:
        xs = x[::OVERSAMPLE]
        cols.append(np.stack([xs, np.gradient(xs, dt * OVERSAMPLE)], axis=1))
    w = np.linalg.lstsq(np.concatenate(cols), np.concatenate(forces), rcond=None)[0]
    res = [f - a @ w for f, a, j in zip(forces, cols, judged, strict=True) if j]
    f_j = np.concatenate([f for f, j in zip(forces, judged, strict=True) if j])
    return float(np.sqrt(np.mean(np.concatenate(res) ** 2) / np.mean(f_j**2)))


def _initial_scale(name: str, k: float, x_peak: float, band_hz: float) -> float:
    return {
        Relaxation.name: k,
        Friction.name: 0.1 * k * x_peak,
        Hardening.name: k,
        Thermal.name: 1e-3,
        Inertia.name: 0.1 * k / (2 * np.pi * band_hz) ** 2,
    }.get(name, 1.0)


def calibrate(
    specimen: Specimen, name: str, target: float, progs: list[Programme], judged: list[bool]
) -> float:
    """Scale effect ``name`` so that alone it leaves ``target`` of the force (all records
    together) to a linear fit: one specimen for all records, as on a test machine.

    Returns the visible gap reached on the judged records. A delay is scaled in seconds
    (within 0.1 ms and its form's limit); a backbone is scaled down until it is monotone.
    """
    alone = Specimen(specimen.k_n_per_m, specimen.c_ns_per_m, {name: specimen.effects[name]})
    form, p = specimen.effects[name]
    key = "delay_s" if name == Delay.name else "scale"
    for _ in range(3):
        gap = visible_gap(_sampled(alone, progs), progs, [True] * len(progs))
        if gap <= 0:
            return gap
        p[key] *= target / gap
        if name == Delay.name:  # a lag of 0.1 ms up to the form's limit, whatever the target asks
            p[key] = float(np.clip(p[key], 1e-4, p["max_delay_s"]))
    if name == Thermal.name:  # a specimen that loses more than MAX_THERMAL_DROP is not a bushing
        power = [specimen.c_ns_per_m * np.gradient(x, dt) ** 2 for x, dt in progs]
        low = min(
            float(np.min(tf.thermal_factor(p, pw, dt)))
            for pw, (_, dt) in zip(power, progs, strict=True)
        )
        if low < 1.0 - MAX_THERMAL_DROP:
            p["scale"] *= np.log(1.0 - MAX_THERMAL_DROP) / np.log(low)
    if name == Hardening.name:
        x_peak = max(float(np.max(np.abs(x))) for x, _ in progs)
        while not tf.hardening_is_monotone(p, form, specimen.k_n_per_m, x_peak):
            p["scale"] *= 0.7
    return visible_gap(_sampled(alone, progs), progs, judged)


# ----- noise and records -----------------------------------------------------------------------
def _noisy(f: np.ndarray, x: np.ndarray, rng, noise: dict) -> tuple[np.ndarray, np.ndarray]:
    sd = noise["fraction"] * float(np.sqrt(np.mean(f**2)))
    out = f + sd * rng.normal(size=f.size)
    if noise["pink"]:
        w = np.fft.rfft(rng.normal(size=f.size))
        w[1:] /= np.sqrt(np.arange(1, w.size))
        w[0] = 0.0
        pink = np.fft.irfft(w, f.size)
        out += sd * pink / (np.std(pink) or 1.0)
    if noise["quantum"]:
        q = noise["quantum"] * float(np.max(np.abs(f)))
        out = np.round(out / q) * q
    x_out = x
    if noise["x_fraction"]:
        x_out = x + noise["x_fraction"] * float(np.std(x)) * rng.normal(size=x.size)
    return out, x_out


def case_label_widened(index: int, rng) -> tuple[tuple[str, ...], bool]:
    """(label, quasi_static): every fifth case quasi-static; otherwise 7 single classes cycle
    and three in ten are pairs of any two effects."""
    effects = tuple(tf.TRUTH_EFFECTS)
    if index % 5 == 4:
        relax, hard, fric = Relaxation.name, Hardening.name, Friction.name
        qs = ((relax,), (), (hard,), (relax, hard), (fric,), (relax, fric))
        return qs[(index // 5) % len(qs)], True
    j = index - (index + 1) // 5  # dynamic cases before this one
    if j % 10 >= 7:
        pair = rng.choice(len(effects), size=2, replace=False)
        return tuple(effects[i] for i in sorted(pair)), False
    single = j - 3 * (j // 10)
    classes = ("none",) + effects
    name = classes[single % len(classes)]
    return (() if name == "none" else (name,)), False


def _draw_specimen(rng, label, qs: bool, progs, judged, band_hz: float, drawn: dict):
    """(specimen, seen): ``seen`` when every effect reaches half its visible target."""
    if qs:
        k = _logu(rng, 2.0, 50.0)
        c = k * _logu(rng, 0.02, 0.5)
    else:
        k = _logu(rng, 1e5, 2e6)
        c = k * _logu(rng, 2e-3, 20e-3)
    x_peak = max(float(np.max(np.abs(x))) for x, _ in progs)
    x0, dt0 = progs[0]
    scale = tf.RecordScale(x_peak, float(np.std(np.gradient(x0, dt0))), band_hz, qs)
    spec = Specimen(k, c)
    hi = 0.4 if qs else TARGET_GAP[1]
    first = _logu(rng, TARGET_GAP[0], hi)
    targets = [first, float(np.clip(first * _logu(rng, 0.25, 4.0), TARGET_GAP[0], hi))]
    drawn.update(k_n_per_m=round(k, 3), c_ns_per_m=round(c, 4), forms={}, visible={})
    for name in label:
        form = str(rng.choice(tf.forms_for(name, qs)))
        p = tf.TRUTH_EFFECTS[name].draw(form, rng, scale)
        p["scale"] = _initial_scale(name, k, x_peak, band_hz)
        spec.effects[name] = (form, p)
        drawn["forms"][name] = form
    seen = True
    for name, target in zip(label, targets, strict=False):
        got = calibrate(spec, name, target, progs, judged)
        drawn["visible"][name] = round(got, 4)
        seen = seen and got >= 0.5 * target
    return spec, seen


def make_widened_case(seed: int, index: int) -> Case:
    """Case ``index`` of widened run ``seed``: label, specimen, records (deterministic).

    Programmes are drawn again (up to ``ATTEMPTS`` times) while an effect of the label stays
    below half its visible target in them (a delay on constant-rate ramps, say, is absorbed
    by the damper): the label must describe something the records show.
    """
    from bushenv.records import Record

    rng = np.random.default_rng([seed, index, 16])
    label, qs = case_label_widened(index, rng)
    rate = QUASI_STATIC_RATE_HZ if qs else float(rng.choice(BUSHING_RATES_HZ))
    test_rate = rate if qs or rng.random() < 0.75 else float(rng.choice(BUSHING_RATES_HZ))
    dt_f, dt_tf = 1.0 / (rate * OVERSAMPLE), 1.0 / (test_rate * OVERSAMPLE)
    make = quasi_static_programmes if qs else bushing_programmes
    for attempt in range(ATTEMPTS):
        train_x, test_x, info = make(rng, dt_f, min(rate, test_rate))
        if test_rate != rate:  # the same TEST programmes on the TEST rate's grid
            test_x = [regrid(x, dt_f, dt_tf) for x in test_x]
        progs = [(x, dt_f) for x in train_x] + [(x, dt_tf) for x in test_x]
        judged = [qs or i >= len(train_x) for i in range(len(progs))]
        drawn: dict[str, Any] = {"rate_hz": rate, "test_rate_hz": test_rate, **info}
        band_hz = info.get("band_hz", [0.0, 1.0])[1]
        spec, seen = _draw_specimen(rng, label, qs, progs, judged, band_hz, drawn)
        drawn["attempts"] = attempt + 1
        if seen:
            break
    noise = {
        "fraction": _logu(rng, *NOISE_FRACTION),
        "pink": bool(rng.random() < 0.3),
        "quantum": _logu(rng, 1e-3, 4e-3) if rng.random() < 0.2 else 0.0,
        "x_fraction": _logu(rng, 5e-4, 3e-3) if rng.random() < 0.2 else 0.0,
    }
    drawn["noise"] = {k: (round(v, 5) if isinstance(v, float) else v) for k, v in noise.items()}
    records = []
    for i, (x, dt) in enumerate(progs):
        f = spec.force(x, dt)[::OVERSAMPLE]
        f, xs = _noisy(f, x[::OVERSAMPLE], rng, noise)
        name = "train" if i < len(train_x) else f"test{i - len(train_x) + 1}"
        records.append(Record.from_arrays(xs, f, dt * OVERSAMPLE, name=name))
    n_tr = len(train_x)
    return Case(index, label, records[:n_tr], records[n_tr:], qs, drawn, spec)
