"""Road inputs for the two wheels of an axle: ISO 8608 random tracks, a pothole, a bump.

Every generator returns the road height under the left and the right wheel as a (T, 2) array in
metres (column 0 left, column 1 right), sampled at ``dt_s`` while the axle drives over the road
at a constant ``speed_m_per_s``: sample i lies at distance ``s = speed_m_per_s * i * dt_s``.

ISO 8608 random roads
---------------------
ISO 8608:2016 (and :1995), §5 and Table C.2 (Table 1 in the 1995 edition), fits a measured
displacement PSD with ``Gd(n) = Gd(n0) (n / n0)^-w``, n0 = 0.1 cycles/m, w = 2, and classes
roads A-H by ``Gd(n0)``; ``ISO8608_GD_N0_M3`` holds each class's geometric mean (in 1e-6 m^3:
A 16, B 64, C 256, D 1024, E 4096, F 16384, G 65536, H 262144; the class bounds are half and
twice that). Each class has 4 x the PSD of the one before it, so 2 x the RMS over any band.
``class_rms_m`` is the closed form of ``sqrt(integral Gd(n) dn)`` over a band.

``two_tracks`` generates both tracks by the inverse-FFT (harmonic sum) method of Cebon &
Newland (1983, Veh. Syst. Dyn. 12, 160-165): harmonics of the record length L at n_k = k / L,
each with the amplitude ``sqrt(2 * integral of Gd over its bin)`` and a random phase. The
harmonics are orthogonal over the record, so each track's mean square equals the integral of
``Gd`` over the generated band to rounding: that band (``generated_band_cycles_per_m``) is the
requested one (default ``ISO8608_BAND_CYCLES_PER_M``) clipped to what the record can hold
(from half a cycle per record up to below the Nyquist frequency).

The right track repeats the left's harmonics with phase offsets ``+-arccos(gamma(n_k))``
(random signs), so its own spectrum is the same and the expected cross-spectrum is
``gamma(n) Gd(n)``: magnitude-squared coherence ``gamma^2``. ``gamma`` is the coherence of an
isotropic surface (Kamash & Robson 1978, J. Sound Vib. 57(1), 89-100; Robson 1979, Int. J.
Vehicle Design 1(1), 25-35): for ``Gd ~ n^-w`` and tracks a width B apart,
``gamma(n) = 2^(1 - nu) / Gamma(nu) x^nu K_nu(x)``, ``nu = w / 2``, ``x = 2 pi n B``
(K the modified Bessel function of the second kind); for w = 2, ``gamma = x K_1(x)``.

Discrete obstacles
------------------
``bump_tracks``: the same bump under both wheels, a (1 - cos) bump (seed 001 Fig. 19 uses
bumps 400, 700 and 1000 mm long, ``bushenv.excitation.PAPER_BUMP_LENGTHS_M``; its heights are
in the missing figure) or a half-sine bump. ``pothole_tracks``: a pothole under one wheel (seed
000 §5.3.2, Fig. 20, at 30 km/h; the shape is in the missing figure), flat-bottomed with
half-cosine or linear edges. Both are geometric profiles under the wheel centre: no tyre
enveloping.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import gamma as gamma_function
from scipy.special import kv

from bushenv.excitation import PAPER_BUMP_LENGTHS_M, PAPER_VEHICLE_SPEED_M_PER_S
from bushenv.vehicle.checks import (
    VehicleInputError,
    finite,
    nonnegative,
    positive,
    sample_count,
)
from bushenv.vehicle.single_track import DEFAULT_VEHICLE

__all__ = [
    "ISO8608_BAND_CYCLES_PER_M",
    "ISO8608_CLASSES",
    "ISO8608_GD_N0_M3",
    "ISO8608_N0_CYCLES_PER_M",
    "ISO8608_WAVINESS",
    "PAPER_BUMP_LENGTHS_M",
    "PAPER_VEHICLE_SPEED_M_PER_S",
    "DEFAULT_TRACK_WIDTH_M",
    "bump_profile_m",
    "bump_tracks",
    "class_psd_m3",
    "class_rms_m",
    "generated_band_cycles_per_m",
    "isotropic_coherence",
    "pothole_profile_m",
    "pothole_tracks",
    "two_tracks",
]

ISO8608_N0_CYCLES_PER_M = 0.1  # ISO 8608 §5: reference spatial frequency n0
ISO8608_WAVINESS = 2.0  # ISO 8608 §5 / Annex C: the classes' fitted exponent w
# ISO 8608:2016 Table C.2 (1995: Table 1): Gd(n0) per class, the geometric mean of its bounds.
ISO8608_CLASSES = ("A", "B", "C", "D", "E", "F", "G", "H")
ISO8608_GD_N0_M3 = {c: 16e-6 * 4.0**i for i, c in enumerate(ISO8608_CLASSES)}
# The band the standard's classification table covers (wavelengths 91 m to 0.35 m).
ISO8608_BAND_CYCLES_PER_M = (0.011, 2.83)
# Default distance between the wheel tracks: the default car's track width
DEFAULT_TRACK_WIDTH_M = DEFAULT_VEHICLE.track_m


def _road_class(road_class: str) -> float:
    if road_class not in ISO8608_GD_N0_M3:
        raise VehicleInputError(
            f"road_class={road_class!r} is not an ISO 8608 class; "
            f"known: {', '.join(ISO8608_CLASSES)}"
        )
    return ISO8608_GD_N0_M3[road_class]


def _band(band_cycles_per_m: tuple[float, float]) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in band_cycles_per_m)
    except (TypeError, ValueError) as exc:
        raise VehicleInputError(
            f"band_cycles_per_m must be two numbers (low, high), got {band_cycles_per_m!r}"
        ) from exc
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise VehicleInputError(
            f"band_cycles_per_m must satisfy 0 < low < high, got {band_cycles_per_m!r}"
        )
    return lo, hi


def class_psd_m3(road_class: str, n_cycles_per_m: np.ndarray) -> np.ndarray:
    """ISO 8608 displacement PSD of a class, ``Gd(n) = Gd(n0) (n / n0)^-2``.

    Parameters
    ----------
    road_class : str
        "A" ... "H" (ISO 8608:2016 Table C.2).
    n_cycles_per_m : array_like
        Spatial frequencies > 0 in cycles/m.

    Returns
    -------
    ndarray
        One-sided PSD in m^3 (m^2 per cycle/m), the shape of ``n_cycles_per_m``.
    """
    gd0 = _road_class(road_class)
    n = np.asarray(n_cycles_per_m, dtype=float)
    if np.any(~np.isfinite(n)) or np.any(n <= 0):
        raise VehicleInputError("n_cycles_per_m must be finite and > 0")
    return gd0 * (n / ISO8608_N0_CYCLES_PER_M) ** -ISO8608_WAVINESS


def class_rms_m(road_class: str, band_cycles_per_m=ISO8608_BAND_CYCLES_PER_M) -> float:
    """RMS road height of a class over a band: ``sqrt(Gd(n0) n0^2 (1/n_lo - 1/n_hi))`` in m.

    The closed-form integral of ``class_psd_m3`` (w = 2) from ``n_lo`` to ``n_hi``.

    Examples
    --------
    >>> round(class_rms_m("A") * 1e3, 3), round(class_rms_m("B") / class_rms_m("A"), 12)
    (3.806, 2.0)
    """
    gd0 = _road_class(road_class)
    lo, hi = _band(band_cycles_per_m)
    return math.sqrt(gd0 * ISO8608_N0_CYCLES_PER_M**2 * (1.0 / lo - 1.0 / hi))


def isotropic_coherence(
    n_cycles_per_m: np.ndarray, track_m: float, waviness: float = ISO8608_WAVINESS
) -> np.ndarray:
    """Coherence function of two parallel tracks on an isotropic road (Kamash & Robson 1978).

    ``gamma(n) = 2^(1 - nu) / Gamma(nu) x^nu K_nu(x)``, ``nu = waviness / 2``,
    ``x = 2 pi n track_m``: the cross-spectrum of the tracks over either track's PSD, real
    for an isotropic surface. The magnitude-squared coherence (what Welch's estimate gives) is
    ``gamma^2``. gamma -> 1 as n -> 0 and falls below 0.1 at x ~ 4.5 (w = 2).

    Parameters
    ----------
    n_cycles_per_m : array_like
        Spatial frequencies >= 0 in cycles/m.
    track_m : float
        Distance between the two wheel tracks in m.
    waviness : float
        The PSD's exponent w (ISO 8608: 2).

    Returns
    -------
    ndarray
        gamma in [0, 1], the shape of ``n_cycles_per_m``.

    Examples
    --------
    >>> round(float(isotropic_coherence(0.1, 1.5)), 4)
    0.6264
    """
    track_m = positive("track_m", track_m)
    nu = positive("waviness", waviness) / 2.0
    n = np.asarray(n_cycles_per_m, dtype=float)
    if np.any(~np.isfinite(n)) or np.any(n < 0):
        raise VehicleInputError("n_cycles_per_m must be finite and >= 0")
    x = 2.0 * np.pi * n * track_m
    with np.errstate(invalid="ignore", over="ignore"):
        g = 2.0 ** (1.0 - nu) / gamma_function(nu) * x**nu * kv(nu, x)
    g = np.where(x == 0, 1.0, g)
    return np.where(np.isfinite(g), np.clip(g, 0.0, 1.0), 0.0)


def generated_band_cycles_per_m(
    speed_m_per_s: float,
    dt_s: float,
    duration_s: float,
    band_cycles_per_m=ISO8608_BAND_CYCLES_PER_M,
) -> tuple[float, float]:
    """The band ``two_tracks`` generates for these arguments, in cycles/m.

    The requested band clipped below at half a cycle per record (``0.5 / L``, L the distance
    driven) and above at the highest harmonic's bin below the Nyquist frequency
    (``speed_m_per_s / (2 dt_s)`` in Hz). The generated road's mean square is the integral of
    ``Gd`` over exactly this band.
    """
    lo, hi = _band(band_cycles_per_m)
    k_lo, k_hi, length_m = _harmonic_range(speed_m_per_s, dt_s, duration_s, lo, hi)
    return max(lo, (k_lo - 0.5) / length_m), min(hi, (k_hi + 0.5) / length_m)


def _harmonic_range(speed_m_per_s, dt_s, duration_s, lo, hi):
    speed_m_per_s = positive("speed_m_per_s", speed_m_per_s)
    count = sample_count(duration_s, dt_s)
    length_m = speed_m_per_s * count * dt_s
    k_lo = max(1, int(math.floor(lo * length_m + 0.5)))
    # the highest harmonic strictly below Nyquist (k < T/2) keeps every pair orthogonal
    k_hi = min(int(math.floor(hi * length_m + 0.5)), (count - 1) // 2)
    if k_hi < k_lo:
        raise VehicleInputError(
            f"the band {lo!r}-{hi!r} cycles/m holds no harmonic of a {length_m:.4g} m record "
            f"sampled every {speed_m_per_s * dt_s:.4g} m: drive longer or sample faster"
        )
    return k_lo, k_hi, length_m


def two_tracks(
    road_class: str,
    speed_m_per_s: float,
    dt_s: float,
    duration_s: float,
    rng: np.random.Generator,
    track_m: float = DEFAULT_TRACK_WIDTH_M,
    band_cycles_per_m=ISO8608_BAND_CYCLES_PER_M,
) -> np.ndarray:
    """Left and right ISO 8608 tracks with the isotropic two-track coherence; (T, 2) in m.

    Parameters
    ----------
    road_class : str
        ISO 8608 class "A" ... "H".
    speed_m_per_s : float
        Constant vehicle speed.
    dt_s : float
        Sample time; T = round(duration_s / dt_s).
    duration_s : float
        Length of the record in time; the road is ``speed_m_per_s * T * dt_s`` m long (and
        periodic with that length).
    rng : numpy.random.Generator
        The only source of randomness (phases, then coherence signs).
    track_m : float
        Distance between the wheel tracks, for the coherence.
    band_cycles_per_m : (float, float)
        Requested band; see ``generated_band_cycles_per_m`` for the one generated.

    Returns
    -------
    ndarray
        (T, 2): column 0 left, column 1 right, zero mean; each column's mean square equals
        ``class_rms_m(road_class, generated_band_cycles_per_m(...))**2`` to rounding.

    Examples
    --------
    >>> z = two_tracks("C", 20.0, 0.005, 20.0, np.random.default_rng(0))
    >>> z.shape, bool(abs(z[:, 0].std() / class_rms_m("C") - 1) < 1e-3)
    ((4000, 2), True)
    """
    gd0 = _road_class(road_class)
    track_m = positive("track_m", track_m)
    if not isinstance(rng, np.random.Generator):
        raise VehicleInputError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    lo, hi = _band(band_cycles_per_m)
    k_lo, k_hi, length_m = _harmonic_range(speed_m_per_s, dt_s, duration_s, lo, hi)
    count = sample_count(duration_s, dt_s)
    k = np.arange(k_lo, k_hi + 1)
    # bin edges (k -+ 1/2)/L clipped to the band; the PSD integral over each bin (w = 2)
    left_edge = np.maximum((k - 0.5) / length_m, lo)
    right_edge = np.minimum((k + 0.5) / length_m, hi)
    variance_m2 = gd0 * ISO8608_N0_CYCLES_PER_M**2 * (1.0 / left_edge - 1.0 / right_edge)
    amplitude_m = np.sqrt(2.0 * variance_m2)
    phase = rng.uniform(0.0, 2.0 * np.pi, k.size)
    signs = np.where(rng.random(k.size) < 0.5, -1.0, 1.0)
    offset = signs * np.arccos(isotropic_coherence(k / length_m, track_m))
    spectra = np.zeros((2, count // 2 + 1), dtype=complex)
    # irfft of X[k] = (T/2) A e^{i phi} gives A cos(2 pi k i / T + phi) at sample i
    spectra[0, k] = 0.5 * count * amplitude_m * np.exp(1j * phase)
    spectra[1, k] = 0.5 * count * amplitude_m * np.exp(1j * (phase + offset))
    return np.fft.irfft(spectra, n=count, axis=1).T.copy()


def bump_profile_m(
    s_m: np.ndarray, length_m: float, height_m: float, shape: str = "cosine"
) -> np.ndarray:
    """Height of a bump at distances ``s_m`` from its start, in m (zero outside [0, length_m]).

    ``shape="cosine"``: ``h/2 (1 - cos(2 pi s / L))`` (seed 001 Fig. 19's bump,
    ``bushenv.excitation.bump``); ``shape="half_sine"``: ``h sin(pi s / L)`` (steeper entry).
    """
    length_m = positive("length_m", length_m)
    height_m = finite("height_m", height_m)
    s = np.asarray(s_m, dtype=float)
    u = s / length_m
    inside = (u >= 0.0) & (u <= 1.0)
    if shape == "cosine":
        z = 0.5 * height_m * (1.0 - np.cos(2.0 * np.pi * u))
    elif shape == "half_sine":
        z = height_m * np.sin(np.pi * u)
    else:
        raise VehicleInputError(f"shape={shape!r}: use 'cosine' or 'half_sine'")
    return np.where(inside, z, 0.0)


def pothole_profile_m(
    s_m: np.ndarray, length_m: float, depth_m: float, edge_m: float, edge: str = "cosine"
) -> np.ndarray:
    """Height of a pothole at distances ``s_m`` from its start, in m (<= 0).

    The road falls to ``-depth_m`` over an edge ``edge_m`` long, stays flat, and climbs back
    over another ``edge_m``, all within ``length_m`` (so ``2 edge_m <= length_m``).
    ``edge="cosine"``: half-cosine edges (``bushenv.excitation.pothole``); ``edge="linear"``:
    straight ramps (a chamfered pothole; slope ``depth_m / edge_m``).
    """
    length_m = positive("length_m", length_m)
    depth_m = nonnegative("depth_m", depth_m)
    edge_m = positive("edge_m", edge_m)
    if 2.0 * edge_m > length_m:
        raise VehicleInputError(f"edge_m={edge_m!r} must be at most half of length_m={length_m!r}")
    s = np.asarray(s_m, dtype=float)
    down = np.clip(s / edge_m, 0.0, 1.0)
    up = np.clip((length_m - s) / edge_m, 0.0, 1.0)
    if edge == "cosine":
        down, up = 0.5 * (1.0 - np.cos(np.pi * down)), 0.5 * (1.0 - np.cos(np.pi * up))
    elif edge != "linear":
        raise VehicleInputError(f"edge={edge!r}: use 'cosine' or 'linear'")
    return -depth_m * np.minimum(down, up)


def _distance_m(speed_m_per_s, dt_s, duration_s, start_m):
    speed_m_per_s = positive("speed_m_per_s", speed_m_per_s)
    start_m = nonnegative("start_m", start_m)
    return speed_m_per_s * dt_s * np.arange(sample_count(duration_s, dt_s)) - start_m


def bump_tracks(
    speed_m_per_s: float,
    dt_s: float,
    duration_s: float,
    length_m: float = PAPER_BUMP_LENGTHS_M[0],
    height_m: float = 0.05,
    start_m: float = 5.0,
    shape: str = "cosine",
) -> np.ndarray:
    """The same bump under both wheels, reached ``start_m`` after t = 0; (T, 2) in m.

    Defaults: 400 mm long (seed 001 §5.1: 400, 700, 1000 mm); 50 mm high, our choice (the
    height is only in seed 001's missing Fig. 19).
    """
    s = _distance_m(speed_m_per_s, dt_s, duration_s, start_m)
    z = bump_profile_m(s, length_m, height_m, shape)
    return np.column_stack([z, z])


def pothole_tracks(
    speed_m_per_s: float,
    dt_s: float,
    duration_s: float,
    length_m: float = 0.6,
    depth_m: float = 0.05,
    edge_m: float = 0.05,
    start_m: float = 5.0,
    side: str = "left",
    edge: str = "cosine",
) -> np.ndarray:
    """A pothole under one wheel (``side`` "left" or "right"), flat road under the other.

    Reached ``start_m`` after t = 0; (T, 2) in m. Defaults (600 mm long, 50 mm deep, 50 mm
    edges) are our choice: seed 000's pothole (Fig. 20, at 30 km/h) is only in the figure.
    """
    if side not in ("left", "right"):
        raise VehicleInputError(f"side={side!r}: use 'left' or 'right'")
    s = _distance_m(speed_m_per_s, dt_s, duration_s, start_m)
    z = pothole_profile_m(s, length_m, depth_m, edge_m, edge)
    out = np.zeros((z.size, 2))
    out[:, 0 if side == "left" else 1] = z
    return out
