"""Specimens for the widened validation: each effect in forms the candidates do not assume.

The diagnosis must not win by knowing how its test data were made, so this module shares no
forms with the candidates nor with ``bushenv.reference``; it reads only their names (declared
on the effect classes) from them. Every form maps a fine-grid motion
(``x``, ``v``, ``a``: (T,) arrays in m, m/s, m/s^2, sample time ``dt`` s) to the force it adds
(N). Records are simulated on a grid 4-8 times finer than the one they are sampled at, so the
specimen is a continuous-time system seen through a sampler, as on a test machine.

``TRUTH_EFFECTS`` is the one list of effects and forms; each entry draws a form's parameters for
a record's scale, ``form_force`` evaluates an additive form. Forms add to the specimen force, except
``thermal`` (scales it), ``inertia`` (adds at the load cell) and ``delay`` (shifts the
measured force); each has a ``scale`` parameter in which its added force is (close to) linear,
so the validation can set how visible the effect is.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numba as nb
import numpy as np
from scipy import signal

from bushenv.diagnose.effects.backbone import Hardening
from bushenv.diagnose.effects.delay import Delay
from bushenv.diagnose.effects.friction import Friction, amplitude_envelope
from bushenv.diagnose.effects.inertia import Inertia
from bushenv.diagnose.effects.relaxation import Relaxation
from bushenv.diagnose.effects.thermal import Thermal

Params = dict[str, Any]


def _logu(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


# ----- relaxation: kernels G(t) convolved with the velocity ---------------------------------
def _kernel_force(kernel: np.ndarray, v: np.ndarray, dt: float) -> np.ndarray:
    """int_0^t G(t - s) v(s) ds on the grid (FFT convolution, trapezoid-free: dt is fine)."""
    return signal.fftconvolve(v, kernel)[: v.size] * dt


def _relax_power_law(p: Params, x, v, a, dt) -> np.ndarray:
    t = np.arange(x.size) * dt
    return p["scale"] * _kernel_force((1.0 + t / p["t0_s"]) ** -p["alpha"], v, dt)


def _relax_stretched(p: Params, x, v, a, dt) -> np.ndarray:
    t = np.arange(x.size) * dt
    return p["scale"] * _kernel_force(np.exp(-((t / p["tau_s"]) ** p["beta"])), v, dt)


def _relax_lognormal(p: Params, x, v, a, dt) -> np.ndarray:
    """A continuous spectrum: 40 branches, Gaussian weights in log(tau)."""
    taus = np.exp(np.log(p["tau_s"]) + p["width"] * np.linspace(-2.5, 2.5, 40))
    w = np.exp(-0.5 * np.linspace(-2.5, 2.5, 40) ** 2)
    t = np.arange(x.size) * dt
    kernel = (w[None, :] * np.exp(-t[:, None] / taus[None, :])).sum(axis=1) / w.sum()
    return p["scale"] * _kernel_force(kernel, v, dt)


def _relax_prony(p: Params, x, v, a, dt) -> np.ndarray:
    out = np.zeros_like(x)
    for k, tau in zip(p["k_rel"], p["tau_s"], strict=True):
        dec = np.exp(-dt / tau)
        out += k * signal.lfilter([tau * (1.0 - dec)], [1.0, -dec], v)
    return p["scale"] * out


def _draw_relaxation(form: str, rng, scale_hint: float, quasi_static: bool) -> Params:
    lo_tau = 1.0 if quasi_static else 0.01
    hi_tau = 300.0 if quasi_static else 20.0
    if form == "power_law":
        return {"t0_s": _logu(rng, 0.2 * lo_tau, 10 * lo_tau), "alpha": rng.uniform(0.15, 0.6)}
    if form == "stretched_exp":
        return {"tau_s": _logu(rng, 3 * lo_tau, hi_tau / 3), "beta": rng.uniform(0.3, 0.7)}
    if form == "lognormal":
        return {"tau_s": _logu(rng, 3 * lo_tau, hi_tau / 3), "width": rng.uniform(0.7, 2.0)}
    n = int(rng.integers(1, 7))
    return {
        "tau_s": [_logu(rng, lo_tau / 3, hi_tau) for _ in range(n)],
        "k_rel": [rng.uniform(0.2, 1.0) for _ in range(n)],
    }


# ----- friction: rate-independent hysteresis, amplitude-dependent stiffness ------------------
@nb.njit(cache=True)
def _bouc_wen_z(x, amp, beta, gamma, n):  # pragma: no cover - compiled
    """z' = amp v - beta |v| |z|^(n-1) z - gamma v |z|^n, sub-stepped in displacement."""
    z = np.zeros(x.size)
    zz = 0.0
    zmax = (amp / (beta + gamma)) ** (1.0 / n)
    for t in range(1, x.size):
        dx = x[t] - x[t - 1]
        m = int(abs(dx) / (0.02 * zmax / amp)) + 1
        h = dx / m
        for _ in range(m):
            az = abs(zz)
            zz += amp * h - beta * abs(h) * az ** (n - 1.0) * zz - gamma * h * az**n
        z[t] = zz
    return z


def _fric_bouc_wen(p: Params, x, v, a, dt) -> np.ndarray:
    n = p["n"]
    x_y = p["x_y_m"]  # yield displacement: z_max / amp
    total = p["beta_plus_gamma"]
    amp = 1.0
    zmax = amp * x_y
    # (amp / (beta + gamma))^(1/n) = z_max fixes beta + gamma
    bg = amp / zmax**n
    beta, gamma = bg * total, bg * (1.0 - total)
    z = _bouc_wen_z(np.ascontiguousarray(x), amp, beta, gamma, float(n))
    return p["scale"] * z / zmax


@nb.njit(cache=True)
def _iwan(x, k_e, slip):  # pragma: no cover - compiled
    z = np.zeros(slip.size)
    out = np.zeros(x.size)
    for t in range(1, x.size):
        dx = x[t] - x[t - 1]
        s = 0.0
        for j in range(slip.size):
            zj = z[j] + k_e * dx
            if zj > slip[j]:
                zj = slip[j]
            elif zj < -slip[j]:
                zj = -slip[j]
            z[j] = zj
            s += zj
        out[t] = s
    return out


def _fric_iwan(p: Params, x, v, a, dt) -> np.ndarray:
    n = 40
    q = (np.arange(n) + 0.5) / n
    slip_x = p["x_y_m"] * q ** p["shape"] * 2.0  # slip displacements, skewed distribution
    k_e = 1.0 / n
    return p["scale"] * _iwan(np.ascontiguousarray(x), k_e, k_e * slip_x) / p["x_y_m"]


def _fric_jenkins(p: Params, x, v, a, dt) -> np.ndarray:
    """One elasto-plastic element: a stiff spring up to the slip force, then sliding."""
    xy = p["x_y_m"]
    return p["scale"] * _iwan(np.ascontiguousarray(x), 1.0 / xy, np.array([1.0]))


def _fric_payne(p: Params, x, v, a, dt) -> np.ndarray:
    """Amplitude softening: stiffness falls with the recent amplitude A (peak hold, decays)."""
    env = amplitude_envelope(np.ascontiguousarray(x), float(np.exp(-dt / p["tau_a_s"])))
    return -p["scale"] * x * env / (env + p["a_c_m"])


def _draw_friction(form: str, rng, x_peak: float, v_rms: float) -> Params:
    if form == "bouc_wen":
        return {
            "n": float(rng.choice([1.0, 2.0])),
            "x_y_m": rng.uniform(0.02, 0.2) * x_peak,
            "beta_plus_gamma": rng.uniform(0.3, 0.9),
        }
    if form == "iwan_skewed":
        return {"x_y_m": rng.uniform(0.03, 0.25) * x_peak, "shape": _logu(rng, 0.4, 2.5)}
    if form == "jenkins":
        return {"x_y_m": rng.uniform(0.005, 0.05) * x_peak}
    return {"tau_a_s": _logu(rng, 0.5, 8.0), "a_c_m": rng.uniform(0.2, 1.0) * x_peak}


# ----- hardening: a nonlinear elastic backbone (minus the linear spring) ---------------------
def _hard_poly_asym(p: Params, x, v, a, dt) -> np.ndarray:
    u = x / p["x_h_m"]
    return p["scale"] * p["x_h_m"] * (p["a2"] * u * u + u**3)


def _hard_softening(p: Params, x, v, a, dt) -> np.ndarray:
    xs = p["x_s_m"]
    return p["scale"] * (xs * np.tanh(x / xs) - x)


def _hard_bump_stop(p: Params, x, v, a, dt) -> np.ndarray:
    w = p["width_m"]
    over = w * np.logaddexp(0.0, (np.abs(x) - p["gap_m"]) / w)
    return p["scale"] * np.sign(x) * over


def _hard_exp_asym(p: Params, x, v, a, dt) -> np.ndarray:
    xh = p["x_h_m"]
    return p["scale"] * (xh * np.expm1(x / xh) - x)


def _hard_gent(p: Params, x, v, a, dt) -> np.ndarray:
    """Gent rubber in uniaxial stretch lam = 1 + x / L0 (nominal force), minus its tangent at 0."""
    lam = 1.0 + x / p["l0_m"]
    jm = p["jm"]
    i1 = lam**2 + 2.0 / lam
    force = (lam - lam**-2) * jm / (jm - (i1 - 3.0))
    return p["scale"] * p["l0_m"] * (force - 3.0 * x / p["l0_m"])


def _draw_hardening(form: str, rng, x_peak: float) -> Params:
    if form == "poly_asym":
        return {"x_h_m": x_peak, "a2": rng.uniform(-0.5, 0.5)}
    if form == "softening":
        return {"x_s_m": rng.uniform(0.3, 1.0) * x_peak}
    if form == "bump_stop":
        return {"gap_m": rng.uniform(0.4, 0.8) * x_peak, "width_m": rng.uniform(0.03, 0.1) * x_peak}
    if form == "gent":
        return {"l0_m": rng.uniform(0.5, 1.0) * x_peak, "jm": rng.uniform(8.0, 60.0)}
    return {"x_h_m": rng.uniform(0.5, 1.5) * x_peak}


def hardening_is_monotone(p: Params, form: str, k: float, x_peak: float) -> bool:
    """Tangent of k x + the form's force stays > 0 within 2 x_peak (checked on a grid)."""
    xs = np.linspace(-2 * x_peak, 2 * x_peak, 4001)
    f = k * xs + form_force(Hardening.name, form, p, xs, None, None, 1.0)
    return bool(np.all(np.diff(f) > 0))


# ----- thermal: modulus falls with self-heating by the dissipated power ----------------------
def thermal_factor(p: Params, power_w: np.ndarray, dt: float) -> np.ndarray:
    """exp(-a dT), dT' = (P - dT / R) / C: the stiffness and damping scale factor (T,)."""
    tau = p["tau_s"]
    dec = np.exp(-dt / tau)
    heat = signal.lfilter([dt], [1.0, -dec], power_w)  # J, leaking with the time constant
    return np.exp(-p["scale"] * heat)


def _draw_thermal(form: str, rng) -> Params:
    return {"tau_s": _logu(rng, 10.0, 400.0), "viscous_ratio": rng.uniform(0.3, 3.0)}


# ----- delay and inertia at the load cell ----------------------------------------------------
def delayed(force: np.ndarray, p: Params, dt: float, form: str) -> np.ndarray:
    """The measured force channel's lag: a pure fractional delay or a Bessel low-pass."""
    if form == "bessel":
        b, a = signal.bessel(4, 1.0 / p["delay_s"], norm="delay", analog=True)
        bz, az = signal.bilinear(b, a, fs=1.0 / dt)
        return signal.lfilter(bz, az, force - force[0]) + force[0]
    t = np.arange(force.size) * dt
    return np.interp(t - p["delay_s"], t, force, left=force[0])


def inertia_force(a: np.ndarray, p: Params, dt: float, form: str) -> np.ndarray:
    """m a, or m a seen through a compliant load cell (2nd-order resonance above the band)."""
    f = p["scale"] * a
    if form == "compliant_cell":
        wn = 2 * np.pi * p["f_n_hz"]
        b, den = signal.bilinear([wn * wn], [1.0, 2 * p["zeta"] * wn, wn * wn], fs=1.0 / dt)
        f = signal.lfilter(b, den, f)
    return f


def _draw_delay(form: str, rng, band_hz: float) -> Params:
    """A lag of 0.4-8 ms; a Bessel filter's lag keeps its cutoff well above the band."""
    hi = 8e-3 if form == "pure" else min(8e-3, 0.5 / (2 * np.pi * band_hz))
    return {"delay_s": _logu(rng, min(0.4e-3, hi / 2), hi), "max_delay_s": hi}


def _draw_inertia(form: str, rng, band_hz: float) -> Params:
    if form == "compliant_cell":
        return {"f_n_hz": rng.uniform(5.0, 12.0) * band_hz, "zeta": rng.uniform(0.05, 0.4)}
    return {}


@dataclass(frozen=True)
class RecordScale:
    """What a form's parameters are drawn relative to: peak |x| (m), RMS velocity (m/s), the
    excitation's upper band edge (Hz), and whether the records are quasi-static pulls."""

    x_peak: float
    v_rms: float
    band_hz: float
    quasi_static: bool


FormFn = Callable[..., np.ndarray]


@dataclass(frozen=True)
class TruthEffect:
    """One effect of the widened set: its forms (name -> force function, None where the stage
    applies it) and how a form's parameters are drawn."""

    stage: str  # "specimen" (adds force), "thermal" (scales it), "cell" (inertia), "channel"
    forms: dict[str, FormFn | None]
    draw: Callable[[str, np.random.Generator, RecordScale], Params]


TRUTH_EFFECTS: dict[str, TruthEffect] = {
    Relaxation.name: TruthEffect(
        "specimen",
        {
            "power_law": _relax_power_law,
            "stretched_exp": _relax_stretched,
            "lognormal": _relax_lognormal,
            "prony_offgrid": _relax_prony,
        },
        lambda f, rng, sc: _draw_relaxation(f, rng, sc.x_peak, sc.quasi_static),
    ),
    Friction.name: TruthEffect(
        "specimen",
        {
            "bouc_wen": _fric_bouc_wen,
            "iwan_skewed": _fric_iwan,
            "jenkins": _fric_jenkins,
            "payne": _fric_payne,
        },
        lambda f, rng, sc: _draw_friction(f, rng, sc.x_peak, sc.v_rms),
    ),
    Hardening.name: TruthEffect(
        "specimen",
        {
            "poly_asym": _hard_poly_asym,
            "softening": _hard_softening,
            "bump_stop": _hard_bump_stop,
            "exp_asym": _hard_exp_asym,
            "gent": _hard_gent,
        },
        lambda f, rng, sc: _draw_hardening(f, rng, sc.x_peak),
    ),
    Thermal.name: TruthEffect(
        "thermal", {"power_heating": None}, lambda f, rng, sc: _draw_thermal(f, rng)
    ),
    Delay.name: TruthEffect(
        "channel",
        {"pure": None, "bessel": None},
        lambda f, rng, sc: _draw_delay(f, rng, sc.band_hz),
    ),
    Inertia.name: TruthEffect(
        "cell",
        {"rigid": None, "compliant_cell": None},
        lambda f, rng, sc: _draw_inertia(f, rng, sc.band_hz),
    ),
}
# forms that only make sense on one kind of record
QUASI_STATIC_ONLY = {"gent"}
DYNAMIC_ONLY = {"jenkins", "payne", "bump_stop"}


def forms_for(effect: str, quasi_static: bool) -> list[str]:
    """The forms of ``effect`` that suit the record kind."""
    skip = DYNAMIC_ONLY if quasi_static else QUASI_STATIC_ONLY
    return [f for f in TRUTH_EFFECTS[effect].forms if f not in skip]


def form_force(effect: str, form: str, p: Params, x, v, a, dt) -> np.ndarray:
    """The force an additive specimen form adds (N), (T,)."""
    fn = TRUTH_EFFECTS[effect].forms[form]
    if fn is None:
        raise ValueError(f"{effect}/{form} is not an additive specimen form")
    return fn(p, x, v, a, dt)
