"""Excitation signals for one bushing axis, and the test machine's limits.

Every generator is a pure function (no hidden state, deterministic given ``seed``) returning the
prescribed displacement ``x`` of shape (T,) in metres, sampled at ``dt`` seconds:
``x[i] = x(i * dt)`` for ``i = 0 .. T-1`` with ``T = n_samples(duration_s, dt)``
(``round(duration_s / dt)``; the end point ``duration_s`` itself is not a sample).

Velocity convention: generators return displacement only. Where the velocity is analytic there is
a companion ``<name>_velocity`` taking exactly the same arguments and returning (T,) in m/s
(``sine_velocity``, ``chirp_velocity``, ``bump_velocity``). Everything else, and every model by
default, uses the central difference ``np.gradient(x, dt)`` (``bushenv.models.base.velocity_of``).

Families (seed 001 §3 is the papers' test programme):

| function          | what                                                                 |
|-------------------|----------------------------------------------------------------------|
| ``sine``          | harmonic test, 1-20 Hz x 0.5-4 mm, 10 s each (seed 001 §3.2.1)       |
| ``chirp``         | swept sine, linear or logarithmic                                    |
| ``random_rpc``    | RPC-III-like durability drive with amplitude index n (seed 001 §3.2.2)|
| ``random_band``   | band-limited random, flat or durability spectrum, optional offset    |
| ``random_ood``    | ``random_band`` beyond the training band and off centre              |
| ``step_hold``     | step held (the papers' 4 mm step held 10 s, seed 000 §5.2)           |
| ``ramp``          | linear ramp then hold                                                |
| ``pulse``         | rectangular pulse with optional smooth edges                         |
| ``bump``          | (1 - cos) road bump of length L crossed at speed V (seed 001 Fig. 19)|
| ``pothole``       | flat-bottomed dip with (1 - cos) edges (seed 000 Fig. 20)            |
| ``sequence``      | concatenation of segments                                            |

Amplitude index n (our reading of the papers): the RPC III software scales one drive file by an
index n; seed 002 §2 says the peak amplitude is 2 mm, which we take to be the peak at n = 1. So
``random_rpc`` scales its drive to ``max |x| = n * 2 mm``: n = 1 (2 mm peak) identifies a model,
n = 1.5 (3 mm peak) verifies it (seed 001 Figs. 12-15).

Machine limits (seed 002 Table 1, the 3-axis elastomer tester):

| quantity                | value             | constant                     |
|-------------------------|-------------------|------------------------------|
| max dynamic force       | 25.0 kN           | ``MAX_DYNAMIC_FORCE_N``      |
| max static force        | 37.5 kN           | ``MAX_STATIC_FORCE_N``       |
| dynamic stroke          | 25.0 mm (+-12.5)  | ``STROKE_M``, ``MAX_DISPLACEMENT_M`` |
| frequency               | 0.1-80 Hz         | ``MIN_FREQUENCY_HZ``, ``MAX_FREQUENCY_HZ`` |
| data acquisition        | over 6 kHz        | ``ACQUISITION_RATE_HZ``      |
| velocity (ours, derived)| 1.257 m/s         | ``MAX_VELOCITY_M_PER_S``     |

The table gives no velocity limit; ``MAX_VELOCITY_M_PER_S`` is derived in its comment below.
``within_limits`` checks stroke and velocity (finite-difference speed between samples, which is
what the actuator must reach when it moves linearly from sample to sample); the frequency range
constrains arbitrary signals only through that velocity bound, and is checked explicitly by
``check_frequency`` for sine and chirp arguments.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from bushenv.errors import BadInput

# ----- machine limits (seed 002 Table 1) ---------------------------------------------------
MAX_DYNAMIC_FORCE_N = 25.0e3
MAX_STATIC_FORCE_N = 37.5e3
STROKE_M = 25.0e-3  # total dynamic length
MAX_DISPLACEMENT_M = STROKE_M / 2  # |x| <= 12.5 mm about the centre
MIN_FREQUENCY_HZ = 0.1
MAX_FREQUENCY_HZ = 80.0
ACQUISITION_RATE_HZ = 6.0e3
# Not in the table: a sine at the machine's top frequency (80 Hz) with a tenth of the stroke as
# amplitude (2.5 mm) peaks at 2 pi f A = 2 pi * 80 * 2.5e-3 = 1.2566 m/s. We take that as the
# fastest the actuator moves; it also admits the whole papers' programme (20 Hz x 4 mm: 0.50 m/s).
MAX_VELOCITY_M_PER_S = 2.0 * math.pi * MAX_FREQUENCY_HZ * (0.1 * STROKE_M)
_LIMIT_RTOL = 1e-9  # a signal exactly at a limit is within it despite rounding
MAX_SIGNAL_SAMPLES = 10_000_000  # 13.6 h at 204.8 Hz, 80 MB as float64: ample for any test

PEAK_M_AT_N1 = 2.0e-3  # seed 002 §2: random drive peak amplitude 2 mm (at n = 1)
DURABILITY_PEAK_HZ = (10.0, 15.0)  # seed 001 §3.2.1: proving-ground load PSD peaks here
PAPER_BUMP_LENGTHS_M = (0.4, 0.7, 1.0)  # seed 001 §4, Fig. 19
PAPER_VEHICLE_SPEED_M_PER_S = 30.0 / 3.6  # seed 000 §6: 30 km/h


class ExcitationError(BadInput):
    """An excitation argument is invalid; the message names the argument and the value."""


# ----- helpers -------------------------------------------------------------------------------
def _check_dt(dt: float) -> float:
    if not (np.isfinite(dt) and dt > 0):
        raise ExcitationError(f"dt must be a positive number of seconds, got {dt!r}")
    return float(dt)


def _check_nonneg(name: str, value: float) -> float:
    if not (np.isfinite(value) and value >= 0):
        raise ExcitationError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


def n_samples(duration_s: float, dt: float) -> int:
    """Number of samples T = round(duration_s / dt) of a signal lasting ``duration_s``.

    Refuses more than ``MAX_SIGNAL_SAMPLES`` (a typo such as ``--duration 1e9`` must be a clear
    error, not an attempt to allocate hundreds of GiB).
    """
    _check_dt(dt)
    _check_nonneg("duration_s", duration_s)
    count = duration_s / dt
    if count > MAX_SIGNAL_SAMPLES:
        raise ExcitationError(
            f"duration_s={duration_s!r} at dt={dt:.6g} s is {count:.4g} samples, more than the "
            f"{MAX_SIGNAL_SAMPLES:.0e} one signal may hold ({MAX_SIGNAL_SAMPLES * dt / 3600:.3g} h "
            "at this dt); split it into shorter runs"
        )
    return int(round(count))


def time_axis(duration_s: float, dt: float) -> np.ndarray:
    """Sample times (T,) in s: 0, dt, ..., (T-1) dt."""
    return np.arange(n_samples(duration_s, dt)) * dt


def _half_cosine(u: np.ndarray) -> np.ndarray:
    """0 -> 1 smoothly for u in [0, 1] (clipped outside): (1 - cos(pi u)) / 2."""
    return 0.5 * (1.0 - np.cos(np.pi * np.clip(u, 0.0, 1.0)))


def check_frequency(freq_hz: float, name: str = "freq_hz") -> float:
    """Refuse a frequency outside the machine's 0.1-80 Hz (seed 002 Table 1)."""
    if not (np.isfinite(freq_hz) and MIN_FREQUENCY_HZ <= freq_hz <= MAX_FREQUENCY_HZ):
        raise ExcitationError(
            f"{name}={freq_hz!r} Hz is outside the machine's range "
            f"{MIN_FREQUENCY_HZ}-{MAX_FREQUENCY_HZ} Hz"
        )
    return float(freq_hz)


# ----- harmonic and swept ----------------------------------------------------------------------
def sine(
    freq_hz: float,
    amplitude_m: float,
    duration_s: float,
    dt: float,
    phase: float = 0.0,
    offset_m: float = 0.0,
) -> np.ndarray:
    """x(t) = offset_m + amplitude_m sin(2 pi freq_hz t + phase); (T,) in m.

    The papers' harmonic test: ``sine(10.0, 2e-3, 10.0, PAPER_DT)``. ``phase`` in radians.
    """
    t = time_axis(duration_s, dt)
    return offset_m + amplitude_m * np.sin(2.0 * np.pi * freq_hz * t + phase)


def sine_velocity(
    freq_hz: float,
    amplitude_m: float,
    duration_s: float,
    dt: float,
    phase: float = 0.0,
    offset_m: float = 0.0,
) -> np.ndarray:
    """Analytic velocity of ``sine`` with the same arguments; (T,) in m/s."""
    t = time_axis(duration_s, dt)
    w = 2.0 * np.pi * freq_hz
    return amplitude_m * w * np.cos(w * t + phase)


def _chirp_phase_and_freq(f0_hz, f1_hz, duration_s, dt, method):
    t = time_axis(duration_s, dt)
    T = float(duration_s)
    if T <= 0:
        return t, t.copy()
    if method == "linear":
        k = (f1_hz - f0_hz) / T
        return 2.0 * np.pi * (f0_hz * t + 0.5 * k * t * t), f0_hz + k * t
    if method in ("log", "logarithmic"):
        if not (f0_hz > 0 and f1_hz > 0):
            raise ExcitationError(
                f"logarithmic chirp needs f0_hz, f1_hz > 0, got {f0_hz!r}, {f1_hz!r}"
            )
        if f0_hz == f1_hz:
            return 2.0 * np.pi * f0_hz * t, np.full_like(t, f0_hz)
        ratio = f1_hz / f0_hz
        growth = ratio ** (t / T)
        return 2.0 * np.pi * f0_hz * T / np.log(ratio) * (growth - 1.0), f0_hz * growth
    raise ExcitationError(f"chirp method must be 'linear' or 'logarithmic', got {method!r}")


def chirp(
    f0_hz: float,
    f1_hz: float,
    amplitude_m: float,
    duration_s: float,
    dt: float,
    method: str = "linear",
    phase: float = 0.0,
) -> np.ndarray:
    """Swept sine from ``f0_hz`` at t = 0 to ``f1_hz`` at t = duration_s; (T,) in m.

    ``method``: "linear" (f = f0 + (f1 - f0) t / D) or "logarithmic" (f = f0 (f1/f0)^(t/D)).
    x = amplitude_m sin(phi(t) + phase), phi the integral of 2 pi f.
    """
    phi, _ = _chirp_phase_and_freq(f0_hz, f1_hz, duration_s, dt, method)
    return amplitude_m * np.sin(phi + phase)


def chirp_velocity(
    f0_hz: float,
    f1_hz: float,
    amplitude_m: float,
    duration_s: float,
    dt: float,
    method: str = "linear",
    phase: float = 0.0,
) -> np.ndarray:
    """Analytic velocity of ``chirp`` with the same arguments; (T,) in m/s."""
    phi, f = _chirp_phase_and_freq(f0_hz, f1_hz, duration_s, dt, method)
    return amplitude_m * 2.0 * np.pi * f * np.cos(phi + phase)


# ----- random ----------------------------------------------------------------------------------
def _edge_taper(T: int, taper_n: int) -> np.ndarray:
    """(T,) window: half-cosine rise over ``taper_n`` samples, 1, half-cosine fall."""
    w = np.ones(T)
    taper_n = min(taper_n, T // 2)
    if taper_n > 0:
        rise = _half_cosine(np.arange(taper_n) / taper_n)
        w[:taper_n] = rise
        w[T - taper_n :] = rise[::-1]
    return w


def random_band(
    duration_s: float,
    dt: float,
    seed: int,
    band_hz: tuple[float, float] = (0.5, 20.0),
    peak_m: float = PEAK_M_AT_N1,
    offset_m: float = 0.0,
    spectrum: str = "flat",
    taper_s: float | None = None,
) -> np.ndarray:
    """Band-limited Gaussian random displacement, (T,) in m, deterministic given ``seed``.

    Synthesised in the frequency domain: amplitude sqrt(S(f)) with random normal real and
    imaginary parts inside ``band_hz`` (the band edges rolled off by half-cosines over 10 % of
    the band), zero outside, then ``irfft``. ``spectrum``:

    - "flat": S(f) = 1 in the band;
    - "durability": S(f) = 0.15 + exp(-((f - 12.5) / 4)^2 / 2), a broad peak at 10-15 Hz like the
      proving-ground load spectra of seed 001 §3.2.1 on a floor that keeps the low frequencies.

    The zero-mean random part is faded in and out by half-cosine tapers of ``taper_s`` (default:
    the shorter of 1 s and 10 % of the duration), scaled so its peak |x| is exactly ``peak_m``,
    and added to ``offset_m``, which ramps in over the same start taper (no step at t = 0) and
    stays on to the end.
    """
    dt = _check_dt(dt)
    T = n_samples(duration_s, dt)
    lo, hi = (float(band_hz[0]), float(band_hz[1]))
    nyquist = 0.5 / dt
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        raise ExcitationError(f"band_hz must be (low, high) with 0 <= low < high, got {band_hz!r}")
    if lo >= nyquist:
        raise ExcitationError(
            f"band_hz={band_hz!r} starts above the Nyquist frequency "
            f"{nyquist:.6g} Hz of dt={dt:.6g}"
        )
    _check_nonneg("peak_m", peak_m)
    if T == 0:
        return np.zeros(0)
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(T, dt)
    if spectrum == "flat":
        psd = np.ones_like(f)
    elif spectrum == "durability":
        centre = 0.5 * sum(DURABILITY_PEAK_HZ)
        psd = 0.15 + np.exp(-0.5 * ((f - centre) / 4.0) ** 2)
    else:
        raise ExcitationError(f"spectrum must be 'flat' or 'durability', got {spectrum!r}")
    edge = 0.1 * (hi - lo)
    gain = _half_cosine((f - lo) / edge) * _half_cosine((hi - f) / edge)
    gain[f > nyquist] = 0.0
    coef = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) * np.sqrt(psd) * gain
    coef[0] = 0.0
    noise = np.fft.irfft(coef, n=T)
    if taper_s is None:
        taper_s = min(1.0, 0.1 * T * dt)
    taper_n = int(round(_check_nonneg("taper_s", taper_s) / dt))
    noise = (noise - noise.mean()) * _edge_taper(T, taper_n)
    peak = np.max(np.abs(noise))
    noise = noise * (peak_m / peak) if peak > 0 else noise
    if offset_m != 0.0:
        ramp_in = np.ones(T)
        n_in = min(taper_n, T)
        if n_in > 0:
            ramp_in[:n_in] = _half_cosine(np.arange(n_in) / n_in)
        noise = noise + offset_m * ramp_in
    return noise


def random_rpc(
    n_index: float,
    duration_s: float,
    dt: float,
    seed: int,
    band_hz: tuple[float, float] = (0.5, 20.0),
    peak_m_at_n1: float = PEAK_M_AT_N1,
) -> np.ndarray:
    """RPC-III-like random drive with amplitude index n; (T,) in m, peak |x| = n * peak_m_at_n1.

    A durability-spectrum ``random_band`` (peak 10-15 Hz, band 0.5-20 Hz, the papers' top test
    frequency) with smooth start and end. The index scales one drive shape: the same ``seed`` and
    ``duration_s`` at n = 1 and n = 1.5 give proportional signals. Papers: n = 1 identifies
    (2 mm peak), n = 1.5 verifies (3 mm peak).
    """
    if not (np.isfinite(n_index) and n_index >= 0):
        raise ExcitationError(f"n_index must be a finite number >= 0, got {n_index!r}")
    return random_band(
        duration_s,
        dt,
        seed,
        band_hz=band_hz,
        peak_m=n_index * peak_m_at_n1,
        spectrum="durability",
    )


def random_ood(
    duration_s: float,
    dt: float,
    seed: int,
    band_hz: tuple[float, float] = (20.0, 60.0),
    peak_m: float = PEAK_M_AT_N1,
    offset_m: float = 3.0e-3,
) -> np.ndarray:
    """Out-of-distribution random drive: flat spectrum above the training band, off centre.

    ``random_band`` with a band beyond ``random_rpc``'s 0.5-20 Hz (default 20-60 Hz; must stay
    below Nyquist, 102.4 Hz at the papers' rate) and a static ``offset_m`` (default 3 mm) that the
    identification data never held. (T,) in m.
    """
    return random_band(
        duration_s, dt, seed, band_hz=band_hz, peak_m=peak_m, offset_m=offset_m, spectrum="flat"
    )


# ----- transients ------------------------------------------------------------------------------
def step_hold(
    size_m: float,
    hold_s: float,
    dt: float,
    pre_s: float = 0.5,
    rise_s: float = 0.0,
) -> np.ndarray:
    """Rest for ``pre_s``, rise to ``size_m``, hold it for ``hold_s``; (T,) in m.

    The step starts at t = pre_s. ``rise_s = 0``: an ideal step, 0 at the last pre sample and
    ``size_m`` from the next one on (a 4 mm step at 204.8 Hz then moves at 0.82 m/s between two
    samples, within ``MAX_VELOCITY_M_PER_S``); ``rise_s > 0``: a half-cosine rise of that length.
    T = n_samples(pre_s + rise_s + hold_s, dt). The papers: ``step_hold(4e-3, 10.0, PAPER_DT)``.
    """
    dt = _check_dt(dt)
    pre_s = _check_nonneg("pre_s", pre_s)
    rise_s = _check_nonneg("rise_s", rise_s)
    hold_s = _check_nonneg("hold_s", hold_s)
    t = time_axis(pre_s + rise_s + hold_s, dt)
    if rise_s == 0.0:
        return np.where(t >= pre_s - 1e-9 * dt, size_m, 0.0)
    return size_m * _half_cosine((t - pre_s) / rise_s)


def ramp(
    end_m: float,
    ramp_s: float,
    dt: float,
    pre_s: float = 0.0,
    hold_s: float = 0.0,
    start_m: float = 0.0,
) -> np.ndarray:
    """Hold ``start_m`` for ``pre_s``, move linearly to ``end_m`` over ``ramp_s``, hold ``hold_s``.

    (T,) in m with T = n_samples(pre_s + ramp_s + hold_s, dt); speed (end_m - start_m) / ramp_s.
    """
    dt = _check_dt(dt)
    pre_s = _check_nonneg("pre_s", pre_s)
    hold_s = _check_nonneg("hold_s", hold_s)
    if not (np.isfinite(ramp_s) and ramp_s > 0):
        raise ExcitationError(f"ramp_s must be > 0 s, got {ramp_s!r}")
    t = time_axis(pre_s + ramp_s + hold_s, dt)
    return start_m + (end_m - start_m) * np.clip((t - pre_s) / ramp_s, 0.0, 1.0)


def pulse(
    size_m: float,
    width_s: float,
    dt: float,
    pre_s: float = 0.5,
    post_s: float = 1.0,
    edge_s: float = 0.0,
) -> np.ndarray:
    """Rest ``pre_s``, go to ``size_m`` for ``width_s``, back to 0, rest ``post_s``; (T,) in m.

    ``edge_s = 0``: sharp edges (one-sample jumps); ``edge_s > 0``: half-cosine rise and fall of
    that length (inside ``width_s``, so ``width_s >= 2 edge_s``). T = n_samples(pre+width+post).
    """
    dt = _check_dt(dt)
    pre_s, post_s = _check_nonneg("pre_s", pre_s), _check_nonneg("post_s", post_s)
    edge_s = _check_nonneg("edge_s", edge_s)
    if not (np.isfinite(width_s) and width_s > 0 and width_s >= 2 * edge_s):
        raise ExcitationError(
            f"width_s must be > 0 and at least 2 * edge_s ({2 * edge_s!r}), got {width_s!r}"
        )
    t = time_axis(pre_s + width_s + post_s, dt) - pre_s
    eps = 1e-9 * dt
    if edge_s == 0.0:
        return np.where((t >= -eps) & (t < width_s - eps), size_m, 0.0)
    up = _half_cosine(t / edge_s)
    down = _half_cosine((width_s - t) / edge_s)
    return size_m * np.minimum(up, down)


def _road_time(length_m, speed_m_per_s, dt, pre_s, post_s):
    dt = _check_dt(dt)
    if not (np.isfinite(length_m) and length_m > 0):
        raise ExcitationError(f"length_m must be > 0 m, got {length_m!r}")
    if not (np.isfinite(speed_m_per_s) and speed_m_per_s > 0):
        raise ExcitationError(f"speed_m_per_s must be > 0 m/s, got {speed_m_per_s!r}")
    pre_s, post_s = _check_nonneg("pre_s", pre_s), _check_nonneg("post_s", post_s)
    crossing_s = length_m / speed_m_per_s
    return time_axis(pre_s + crossing_s + post_s, dt) - pre_s, crossing_s


def bump(
    length_m: float,
    height_m: float,
    speed_m_per_s: float,
    dt: float,
    pre_s: float = 0.5,
    post_s: float = 1.0,
) -> np.ndarray:
    """A (1 - cos) road bump of ``length_m`` crossed at ``speed_m_per_s``: height vs time, (T,) m.

    x(t) = height_m / 2 (1 - cos(2 pi V t / L)) while 0 <= V t <= L, zero before (``pre_s``) and
    after (``post_s``). Seed 001 Fig. 19 used bumps 400, 700 and 1000 mm long
    (``PAPER_BUMP_LENGTHS_M``); seed 000 drove at 30 km/h (``PAPER_VEHICLE_SPEED_M_PER_S``).
    The height is not in the text (the figure is missing), so it is an argument. Applied to a
    bushing directly this is its deflection; a rig maps road height to bushing motion itself.
    """
    t, crossing_s = _road_time(length_m, speed_m_per_s, dt, pre_s, post_s)
    inside = (t >= 0) & (t <= crossing_s)
    return np.where(inside, 0.5 * height_m * (1.0 - np.cos(2.0 * np.pi * t / crossing_s)), 0.0)


def bump_velocity(
    length_m: float,
    height_m: float,
    speed_m_per_s: float,
    dt: float,
    pre_s: float = 0.5,
    post_s: float = 1.0,
) -> np.ndarray:
    """Analytic velocity of ``bump`` with the same arguments; (T,) in m/s."""
    t, crossing_s = _road_time(length_m, speed_m_per_s, dt, pre_s, post_s)
    inside = (t >= 0) & (t <= crossing_s)
    w = 2.0 * np.pi / crossing_s
    return np.where(inside, 0.5 * height_m * w * np.sin(w * t), 0.0)


def pothole(
    length_m: float,
    depth_m: float,
    speed_m_per_s: float,
    dt: float,
    edge_m: float = 0.05,
    pre_s: float = 0.5,
    post_s: float = 1.0,
) -> np.ndarray:
    """A pothole ``length_m`` long and ``depth_m`` deep crossed at ``speed_m_per_s``; (T,) in m.

    The road drops to -depth_m over a half-cosine edge ``edge_m`` long, stays flat, and climbs
    back over another ``edge_m`` (both edges inside ``length_m``). Seed 000 Fig. 20 (shape only
    in the missing figure; 30 km/h).
    """
    if not (np.isfinite(edge_m) and edge_m > 0 and 2 * edge_m <= length_m):
        raise ExcitationError(
            f"edge_m must be > 0 and at most half of length_m={length_m!r}, got {edge_m!r}"
        )
    t, crossing_s = _road_time(length_m, speed_m_per_s, dt, pre_s, post_s)
    s = t * speed_m_per_s  # distance along the road from the pothole's start
    down = _half_cosine(s / edge_m)
    up = _half_cosine((length_m - s) / edge_m)
    return -depth_m * np.minimum(down, up)


def sequence(*segments: np.ndarray) -> np.ndarray:
    """Concatenate 1-D segments in time order: (T1,), (T2,), ... -> (T1 + T2 + ...,).

    Segments are joined as they are (no shifting); put a ``ramp`` between two that do not meet
    if the jump would exceed the machine's velocity limit.
    """
    if not segments:
        return np.zeros(0)
    arrays = [np.asarray(s, dtype=np.float64) for s in segments]
    for i, a in enumerate(arrays):
        if a.ndim != 1:
            raise ExcitationError(f"sequence: segment {i} has shape {a.shape}, expected (T,)")
    return np.concatenate(arrays)


# ----- machine limits --------------------------------------------------------------------------
def machine_velocity(x: np.ndarray, dt: float) -> np.ndarray:
    """Speed between samples the actuator must reach: diff(x) / dt, (T-1,) in m/s."""
    return np.diff(np.asarray(x, dtype=np.float64), axis=0) / _check_dt(dt)


def within_limits(x: np.ndarray, dt: float) -> tuple[bool, str]:
    """Whether the test machine can drive displacement ``x`` ((T,) or (T, B), m) at ``dt``.

    Returns (True, "") or (False, reason) with the first failing sample and value. Checks:
    finite values, |x| <= ``MAX_DISPLACEMENT_M`` (12.5 mm), |diff(x)| / dt <=
    ``MAX_VELOCITY_M_PER_S`` (1.257 m/s).
    """
    dt = _check_dt(dt)
    a = np.asarray(x, dtype=np.float64)
    if a.ndim not in (1, 2):
        return False, f"displacement has shape {a.shape}, expected (T,) or (T, B)"
    bad = ~np.isfinite(a)
    if bad.any():
        i = np.argwhere(bad)[0]
        return False, f"sample {int(i[0])} is {a[tuple(i)]!r}, not a finite displacement"
    if a.size == 0:
        return True, ""
    over = np.abs(a) > MAX_DISPLACEMENT_M * (1 + _LIMIT_RTOL)
    if over.any():
        i = tuple(np.argwhere(over)[0])
        return False, (
            f"sample {int(i[0])} at t={i[0] * dt:.4f} s: |x| = {abs(a[i]) * 1e3:.4g} mm exceeds "
            f"the stroke limit {MAX_DISPLACEMENT_M * 1e3:.4g} mm (+-half of 25 mm)"
        )
    if a.shape[0] >= 2:
        vel = np.abs(machine_velocity(a, dt))
        fast = vel > MAX_VELOCITY_M_PER_S * (1 + _LIMIT_RTOL)
        if fast.any():
            i = tuple(np.argwhere(fast)[0])
            return False, (
                f"sample {int(i[0]) + 1} at t={(i[0] + 1) * dt:.4f} s: speed {vel[i]:.4g} m/s "
                f"exceeds the velocity limit {MAX_VELOCITY_M_PER_S:.4g} m/s"
            )
    return True, ""


@nb.njit(cache=True, nogil=True)
def _slew_limit(x, max_step, out):  # pragma: no cover - compiled
    T, B = x.shape
    for b in range(B):
        out[0, b] = x[0, b]
    for t in range(1, T):
        for b in range(B):
            d = x[t, b] - out[t - 1, b]
            if d > max_step:
                out[t, b] = out[t - 1, b] + max_step
            elif d < -max_step:
                out[t, b] = out[t - 1, b] - max_step
            else:
                out[t, b] = x[t, b]


def clip_to_limits(
    x: np.ndarray,
    dt: float,
    max_displacement_m: float = MAX_DISPLACEMENT_M,
    max_velocity_m_per_s: float = MAX_VELOCITY_M_PER_S,
) -> np.ndarray:
    """The nearest drivable version of ``x``: (T,) or (T, B) -> same shape, m.

    Clips to +-``max_displacement_m``, then limits the rate: each sample moves at most
    ``max_velocity_m_per_s * dt`` from the previous output (a slew-rate limiter, like a servo's
    rate limit). With the default (the machine's) limits the result passes ``within_limits``;
    non-finite input is refused.
    """
    dt = _check_dt(dt)
    a = np.asarray(x, dtype=np.float64)
    if a.ndim not in (1, 2):
        raise ExcitationError(f"clip_to_limits: x has shape {a.shape}, expected (T,) or (T, B)")
    if not np.all(np.isfinite(a)):
        raise ExcitationError("clip_to_limits: x holds NaN or inf")
    one_d = a.ndim == 1
    a2 = np.ascontiguousarray(
        np.clip(a[:, None] if one_d else a, -max_displacement_m, max_displacement_m)
    )
    out = np.empty_like(a2)
    if a2.shape[0] > 0:
        # 1e-12 relative margin so the clipped signal never fails within_limits by a rounding.
        _slew_limit(a2, max_velocity_m_per_s * dt * (1 - 1e-12), out)
    return out[:, 0] if one_d else out
