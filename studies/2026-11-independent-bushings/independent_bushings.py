"""Three bushings bushenv was not tuned on, written from scratch (numpy/scipy only).

Nothing here imports bushenv: the physics, the excitation and the CSV writer are this file's
own, so a fit that does well on these records did not learn them from the project's reference
rubber or its diagnosis candidates. Each bushing differs from the reference rubber (radial:
about 1.1 kN/mm, 204.8 Hz, Maxwell branches, smooth hardening, a stiff friction element):

- stiff-cubic, 500 Hz: 1.0 kN/mm plus a cubic spring (+50 % stiffness at 2 mm), viscous
  damping only: no memory.
- soft-prony, 1024 Hz: 0.12 kN/mm long-term, mild cubic, five Maxwell branches from 2 ms to
  2 s weighted as a Prony series of a fractional element (relaxation ~ t^-0.3).
- berg, 204.8 Hz: 0.45 kN/mm, Berg's smooth Coulomb friction (250 N), one Maxwell branch of
  30 ms.

Records: ``python studies/2026-11-independent-bushings/independent_bushings.py --out runs/independent`` writes, per bushing,
``NAME_train.csv`` (40 s) and ``NAME_held.csv`` (20 s, another drive seed), columns
time,displacement,force in s, m, N. The drive is band-limited Gaussian noise (flat 0.5-20 Hz
spectrum, RMS 0.8 mm), the force has 0.5 % RMS white sensor noise. The dynamics are integrated
at 8 times the record rate (exact exponentials for the Maxwell branches) and every 8th sample
is kept.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

OVERSAMPLE = 8
BAND_HZ = (0.5, 20.0)
X_RMS_M = 0.8e-3
NOISE_SHARE = 0.005


def drive(duration_s: float, rate_hz: float, seed: int) -> np.ndarray:
    """Band-limited Gaussian displacement, m, at ``rate_hz * OVERSAMPLE`` (flat in BAND_HZ,
    0.5 s cosine fade-in from rest)."""
    fs = rate_hz * OVERSAMPLE
    n = int(round(duration_s * fs))
    rng = np.random.default_rng(seed)
    spec = rng.normal(size=n // 2 + 1) + 1j * rng.normal(size=n // 2 + 1)
    freq = np.fft.rfftfreq(n, 1.0 / fs)
    spec[(freq < BAND_HZ[0]) | (freq > BAND_HZ[1])] = 0.0
    x = np.fft.irfft(spec, n)
    x *= X_RMS_M / np.sqrt(np.mean(x * x))
    fade = np.minimum(1.0, np.arange(n) / (0.5 * fs))
    return x * 0.5 * (1.0 - np.cos(np.pi * fade))


def maxwell_forces(x: np.ndarray, dt: float, k: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Sum of Maxwell branches (spring k_i in series with a damper k_i tau_i), exact for x
    linear between samples: dF_i/dt = k_i dx/dt - F_i / tau_i."""
    k, tau = np.asarray(k, float), np.asarray(tau, float)
    decay = np.exp(-dt / tau)
    gain = k * tau / dt * (1.0 - decay)  # response to a unit ramp of x over one step
    fi = np.zeros_like(k)
    out = np.empty_like(x)
    prev = 0.0
    for i, xi in enumerate(x):
        fi = decay * fi + gain * (xi - prev)
        prev = xi
        out[i] = fi.sum()
    return out


def berg_friction(x: np.ndarray, f_max_n: float, x2_m: float) -> np.ndarray:
    """Berg's smooth friction element (Berg 1998): from the last reversal (x_s, F_s) the force
    moves towards +-f_max_n as F_s + (x - x_s) (f_max - F_s) / (x2 (1 - a) + (x - x_s)),
    a = F_s / f_max, with x2 the displacement to reach half the span."""
    out = np.empty_like(x)
    xs, fs, direction, f = 0.0, 0.0, 0.0, 0.0
    for i in range(x.size):
        dx = x[i] - (x[i - 1] if i else 0.0)
        if dx != 0.0 and np.sign(dx) != direction:
            xs, fs, direction = (x[i - 1] if i else 0.0), f, np.sign(dx)
        if direction > 0:
            d = x[i] - xs
            f = fs + d * (f_max_n - fs) / (x2_m * (1.0 - fs / f_max_n) + d)
        elif direction < 0:
            d = xs - x[i]
            f = fs - d * (f_max_n + fs) / (x2_m * (1.0 + fs / f_max_n) + d)
        out[i] = f
    return out


def prony_of_fractional(g: float, alpha: float, taus: np.ndarray) -> np.ndarray:
    """Branch stiffnesses whose Maxwell sum approximates g (tau0/t)^alpha relaxation: weights
    of a log-spaced Prony series (alpha-power law of the time constants)."""
    w = (taus / taus[0]) ** (-alpha)
    return g * w / w.sum()


def force(name: str, x: np.ndarray, dt: float) -> np.ndarray:
    """Force, N, of bushing ``name`` driven by x (m, every ``dt`` s, from rest)."""
    v = np.gradient(x, dt)
    if name == "stiff-cubic":
        k, k3, c = 1.0e6, 1.25e11, 900.0
        return k * x + k3 * x**3 + c * v
    if name == "soft-prony":
        k_inf, k3, c = 1.2e5, 8.0e9, 60.0
        taus = np.logspace(np.log10(2e-3), np.log10(2.0), 5)
        return (
            k_inf * x
            + k3 * x**3
            + c * v
            + maxwell_forces(x, dt, prony_of_fractional(1.5e5, 0.3, taus), taus)
        )
    if name == "berg":
        k, c = 4.5e5, 150.0
        return (
            k * x
            + c * v
            + maxwell_forces(x, dt, np.array([2.0e5]), np.array([0.03]))
            + berg_friction(x, 250.0, 0.15e-3)
        )
    raise ValueError(f"unknown bushing {name!r}; known: {', '.join(BUSHINGS)}")


BUSHINGS = {"stiff-cubic": 500.0, "soft-prony": 1024.0, "berg": 204.8}
RECORDS = {"train": (40.0, 100), "held": (20.0, 200)}  # duration s, drive seed offset


def record(name: str, which: str, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t s, x m, F N) of one record at the bushing's own rate."""
    rate = BUSHINGS[name]
    duration, offset = RECORDS[which]
    x_fine = drive(duration, rate, seed + offset + list(BUSHINGS).index(name))
    f_fine = force(name, x_fine, 1.0 / (rate * OVERSAMPLE))
    x, f = x_fine[::OVERSAMPLE], f_fine[::OVERSAMPLE]
    rng = np.random.default_rng(seed + offset + 7)
    f = f + NOISE_SHARE * np.sqrt(np.mean(f * f)) * rng.normal(size=f.size)
    return np.arange(x.size) / rate, x, f


def write_csv(path: Path, t: np.ndarray, x: np.ndarray, f: np.ndarray) -> None:
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("time,displacement,force\n")
        for row in zip(t.tolist(), x.tolist(), f.tolist(), strict=True):
            fh.write(f"{row[0]!r},{row[1]!r},{row[2]!r}\n")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="runs/independent", help="folder for the CSV records")
    p.add_argument("--seed", type=int, default=0, help="drive and noise seed (default: 0)")
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name, rate in BUSHINGS.items():
        for which in RECORDS:
            t, x, f = record(name, which, args.seed)
            write_csv(out / f"{name}_{which}.csv", t, x, f)
            print(
                f"{name:12s} {which:5s} {rate:7.1f} Hz {t.size:6d} samples: x RMS "
                f"{1e3 * np.sqrt(np.mean(x * x)):.2f} mm, F RMS {np.sqrt(np.mean(f * f)):.0f} N, "
                f"max {np.max(np.abs(f)):.0f} N"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
