"""Holds reached the way a search reaches them, and whether a model rings, departs or pulls there.

A certificate's free run steps to each hold from rest; a slow ramp barely excites a hold at all.
A search reaches a hold after any motion: a network whose hold fixed point is barely unstable
(spectral radius slightly above 1) stays quiet for seconds after a slow ramp and rings at once
after a sine. So a listed hold -- a deflection x, or over C coordinates a held vector q -- is
*confirmed* here from several histories, all inside the model's envelope (per coordinate the
largest |q| and |dq/dt|: of its card's records, else the judged stroke and rate): the step
with every coordinate at its own velocity limit (the attack's hold stage), and sines of
``AMPLITUDE_FRACTIONS`` of the envelope's displacement at ``FREQUENCIES_HZ`` (those within its
velocity and below a quarter of the sample rate) along each coordinate, and for a hold off the
coordinate axes along its own direction (scaled to touch the envelope's box), each from rest,
ending at rest position, then a move to the hold at the sine's peak speed (as a fraction of
each coordinate's limit), then ``HOLD_S`` held (longer for a departure the certificate
predicts later). One coordinate is the case C = 1.

Each hold is judged on its tail (the last ``TAIL_S``), per coordinate against one threshold
(:func:`ring_threshold`) tied to the model itself: ``NOISE_FACTOR`` times its own noise (the
median peak-to-peak of its detrended tails in holds from rest: a few ringing holds do not move
a median) and ``RING_FRACTION`` of its force scale (its largest settled force over the stroke),
whichever is larger -- not a fixed floor: a 200 N floor hid a kilonewton ring of a bushing
whose force scale is 5 kN. A passive bushing only relaxes in a hold, smoothly, so:

- *oscillating*: the tail, less a fitted parabola (a relaxation's curvature), still moves by
  more than the threshold, peak to peak;
- *departing*: from one second into the hold to its end the force grows by more than the
  threshold and by ``DEPART_FRACTION`` of its held value;
- *wrong sign*: the tail's mean opposes the deflection by more than the threshold;
- *not finite*.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bushenv.certify.fixed_points import fixed_points
from bushenv.certify.ghosts import ghosts
from bushenv.certify.holds import HOLD_S as CERTIFY_HOLD_S
from bushenv.certify.holds import free_runs, reference_static_force
from bushenv.certify.network import narx_net

HOLD_S = 4.0
TAIL_S = 2.0
SETTLE_S = 1.0
PRE_S = 0.1
MAX_HOLD_S = 20.0  # a departure the certificate predicts later than this is not simulated
SINE_S = 1.0  # at least this long, and at least two cycles
AMPLITUDE_FRACTIONS = (0.5, 0.25)
FREQUENCIES_HZ = (2.0, 5.0, 10.0, 20.0, 40.0)
NOISE_FACTOR = 3.0
RING_FRACTION = 0.01
DEPART_FRACTION = 0.25
MAX_LISTED = 16  # listed holds simulated, spread over the list


@dataclass(frozen=True)
class Threshold:
    """The force a ring, a departure or a wrong sign must exceed, N, and where it comes from."""

    force_n: float
    noise_n: float  # the model's own noise: median peak-to-peak of detrended hold tails, N
    force_scale_n: float  # its largest settled force over the stroke, N

    def describe(self) -> str:
        return (
            f"threshold {self.force_n:.4g} N: the larger of {NOISE_FACTOR:g} x its noise "
            f"{self.noise_n:.3g} N p-p and {RING_FRACTION:.0%} of its force scale "
            f"{self.force_scale_n:.4g} N"
        )


def tail_ripple(tail: np.ndarray) -> np.ndarray:
    """(B,) peak-to-peak of each column of (T, B) ``tail`` less its least-squares parabola."""
    t = np.linspace(-1.0, 1.0, tail.shape[0])
    q, _ = np.linalg.qr(np.stack([np.ones_like(t), t, t * t], axis=1))  # (T, 3) orthonormal
    return np.ptp(tail - q @ (q.T @ tail), axis=0)


def ring_threshold(f_rest: np.ndarray, dt: float) -> Threshold:
    """The threshold of a model from its forces (T, B) in holds reached from rest (the last
    ``TAIL_S`` of each column is its tail, the last sample its settled force)."""
    ok = np.all(np.isfinite(f_rest), axis=0)
    if not ok.any():
        return Threshold(float("inf"), float("nan"), float("nan"))
    tail = f_rest[-max(3, int(round(TAIL_S / dt))) :, ok]
    noise = float(np.median(tail_ripple(tail)))
    scale = float(np.max(np.abs(f_rest[-1, ok])))
    return Threshold(max(NOISE_FACTOR * noise, RING_FRACTION * scale), noise, scale)


def judge_holds(f: np.ndarray, q: np.ndarray, n_hold: int, threshold, dt: float) -> dict:
    """Flags (B,) per kind for forces (T, B), or (T, B, C) over C coordinates, whose last
    ``n_hold`` samples hold ``q`` (B,) or (B, C), each coordinate against its ``threshold``
    (a number, or (C,)): {"not finite", "oscillating", "departing", "wrong sign"}, and
    "ripple_n" (B,), the largest coordinate's ("worst_coordinate" (B,) which), and
    "coordinates" (B, C), those that show any kind (wrong sign there: the tail's mean
    opposing that coordinate's deflection by more than its threshold). Wrong sign: the work
    ``q . f`` of the tail's mean below ``-sum(threshold |q|)`` (one coordinate: the mean
    opposes x by more than the threshold); a coupled bushing may push sideways, never back
    into the deflection it holds."""
    g3 = f.reshape(f.shape[0], f.shape[1], -1)
    c = g3.shape[2]
    q2 = np.asarray(q, dtype=np.float64).reshape(-1, c)
    th = np.broadcast_to(np.asarray(threshold, dtype=np.float64), (c,))
    finite = np.all(np.isfinite(g3), axis=(0, 2))
    g = np.where(finite[None, :, None], g3, 0.0)
    tail = g[-max(3, int(round(TAIL_S / dt))) :]
    ripple = tail_ripple(tail.reshape(tail.shape[0], -1)).reshape(-1, c)
    f0 = g[-n_hold + int(round(SETTLE_S / dt))]
    f1 = g[-1]
    grows = np.abs(f1) - np.abs(f0) > np.maximum(th, DEPART_FRACTION * np.abs(f0))
    flips = (np.abs(f0) > th) & (np.abs(f1) > th) & (np.sign(f0) != np.sign(f1))
    work = np.sum(q2 * tail.mean(axis=0), axis=1)
    opposes = q2 * tail.mean(axis=0) < -th * np.abs(q2)
    shows = ~np.all(np.isfinite(g3), axis=0) | (ripple > th) | grows | flips | opposes
    return {
        "not finite": ~finite,
        "oscillating": finite & np.any(ripple > th, axis=1),
        "departing": finite & np.any(grows | flips, axis=1),
        "wrong sign": finite & (work < -np.sum(th * np.abs(q2), axis=1)),
        "ripple_n": np.where(finite, ripple.max(axis=1), np.inf),
        "coordinates": shows,
        "worst_coordinate": np.argmax(ripple, axis=1),
    }


def excitations(x_env_m: float, v_env_m_per_s: float, dt: float) -> list[tuple[float, float]]:
    """(amplitude, frequency Hz) of the sines inside one coordinate's envelope (see the module
    doc): |x| <= ``x_env_m`` and |dx/dt| <= ``v_env_m_per_s`` (m and m/s, or rad and rad/s)."""
    out = []
    for frac in AMPLITUDE_FRACTIONS:
        a = frac * x_env_m
        for f in FREQUENCIES_HZ:
            if 2 * np.pi * f * a <= v_env_m_per_s * (1 + 1e-9) and f <= 0.25 / dt:
                out.append((a, f))
    return out


def _move(x0: float, x1: float, speed: float, dt: float) -> np.ndarray:
    n = max(1, int(np.ceil(abs(x1 - x0) / (speed * dt))))
    return np.linspace(x0, x1, n + 1)[1:]


def _move_to(q: np.ndarray, speed: np.ndarray, dt: float) -> np.ndarray:
    """(n, C) from rest to ``q``, each coordinate at its own ``speed`` (then held there)."""
    moves = [_move(0.0, float(x), float(s), dt) for x, s in zip(q, speed, strict=True)]
    n = max(m.size for m in moves)
    return np.stack([np.r_[m, np.full(n - m.size, m[-1])] for m in moves], axis=1)


def _sine(a, f: float, dt: float) -> np.ndarray:
    """(n, C) two cycles at least of amplitude ``a`` (C,) at ``f``, ending at rest."""
    cycles = max(2, int(np.ceil(SINE_S * f)))
    t = np.arange(int(round(cycles / (f * dt))) + 1) * dt
    sine = np.outer(np.sin(2 * np.pi * f * t), a) if np.ndim(a) else a * np.sin(2 * np.pi * f * t)
    sine[-1] = 0.0
    return sine.reshape(t.size, -1)


def _label(a: float, unit: str) -> str:
    return f"{a * 1e3:.3g} {'mrad' if unit == 'rad' else 'mm'}"


def reach_profiles(
    q, x_env, v_env, hold_s: float, dt: float, coords=None, units=None
) -> tuple[list[np.ndarray], list[str]]:
    """Profiles that reach the hold ``q`` (each ends with ``hold_s`` at ``q``), and how: a
    step, every coordinate at its own velocity limit; from rest, sines inside the envelope
    (|q_i| <= ``x_env``, |dq_i/dt| <= ``v_env``, each a number or (C,)) along each
    coordinate, and for a hold off the coordinate axes along its own direction (scaled to
    touch the envelope's box), each then a move to the hold at the sine's peak speed as a
    fraction of each coordinate's limit. A number ``q`` (one coordinate) gives (T,) profiles,
    a (C,) vector (T, C); ``coords``, ``units`` name the coordinates in ``how``."""
    one = np.ndim(q) == 0
    q = np.atleast_1d(np.asarray(q, dtype=np.float64))
    c = q.size
    x_env = np.broadcast_to(np.asarray(x_env, dtype=np.float64), (c,))
    v_env = np.broadcast_to(np.asarray(v_env, dtype=np.float64), (c,))
    coords = coords or ("",) * c
    units = units or ("m",) * c
    n_hold = int(round(hold_s / dt))
    pre = np.zeros((max(1, int(round(PRE_S / dt))), c))
    held = np.repeat(q[None], n_hold, axis=0)
    profiles = [np.concatenate([pre, _move_to(q, v_env, dt), held])]
    how = ["a step at the velocity limit" if c == 1 else
           "a step, each coordinate at its velocity limit"]  # fmt: skip
    for j in range(c):
        for a, f in excitations(x_env[j], v_env[j], dt):
            path = np.zeros((_sine(a, f, dt).shape[0], c))
            path[:, j] = _sine(a, f, dt)[:, 0]
            speed = v_env * (2 * np.pi * f * a / v_env[j])
            speed[j] = min(2 * np.pi * f * a, v_env[j])
            move = _move_to(q, np.minimum(speed, v_env), dt)
            profiles.append(np.concatenate([pre, path, move, held]))
            along = "" if c == 1 else f" along {coords[j]}"
            how.append(f"a {_label(a, units[j])} {f:g} Hz sine{along}")
    if np.count_nonzero(q) >= 2:  # off the axes: along its own direction too
        e = q / np.max(np.abs(q) / x_env)
        for frac in AMPLITUDE_FRACTIONS:
            for f in FREQUENCIES_HZ:
                r = float(np.max(2 * np.pi * f * frac * np.abs(e) / v_env))
                if r > 1 + 1e-9 or f > 0.25 / dt:
                    continue
                move = _move_to(q, np.minimum(r * v_env, v_env), dt)
                profiles.append(np.concatenate([pre, _sine(frac * e, f, dt), move, held]))
                how.append(f"a {f:g} Hz sine along the hold's direction, {frac:g} x the envelope")
    if one:
        profiles = [p[:, 0] for p in profiles]
    return profiles, how


@dataclass(frozen=True)
class Confirmed:
    """A listed hold the simulation confirms: where (``q``, (C,)), as what, how large (the
    worst coordinate's ripple, in its force unit), on which coordinates, after what."""

    q: tuple[float, ...]
    kinds: tuple[str, ...]
    ripple_n: float
    after: str
    coords: tuple[int, ...] = (0,)  # the coordinates that show it
    worst_coord: int = 0  # the coordinate of ``ripple_n``

    @property
    def x_m(self) -> float:
        """The held deflection of a one-coordinate hold, m."""
        return self.q[0]


def _held(h: dict) -> np.ndarray:
    return np.atleast_1d(np.asarray(h["x_m"] if "x_m" in h else h["q"], dtype=np.float64))


def confirm_holds(
    model,
    listed: list[dict],
    envelope: tuple,
    threshold,
) -> tuple[list[Confirmed], int]:
    """The ``listed`` holds ([{"x_m" or "q", "departure_s"?}]) each simulated after every
    ``reach_profiles`` history inside ``envelope`` (the |q| and |dq/dt| limits, each a number
    or (C,)), judged per coordinate against ``threshold`` (a number or (C,)); the confirmed
    ones (any history shows a kind of the module doc) and the number of profiles simulated."""
    if not listed:
        return [], 0
    if len(listed) > MAX_LISTED:
        keep = np.unique(np.linspace(0, len(listed) - 1, MAX_LISTED).round().astype(int))
        listed = [listed[i] for i in keep]
    dt, c = model.dt, model.n_coords
    later = [h.get("departure_s") or 0.0 for h in listed]
    hold_s = float(min(MAX_HOLD_S, max(HOLD_S, max(later) + TAIL_S)))
    n_hold = int(round(hold_s / dt))
    names = (model.coords, model.units)
    profiles, owner, how = [], [], []
    for i, h in enumerate(listed):
        p, w = reach_profiles(_held(h), envelope[0], envelope[1], hold_s, dt, *names)
        profiles += p
        owner += [i] * len(p)
        how += w
    T = max(p.shape[0] for p in profiles)
    x = np.zeros((T, len(profiles), c))
    for b, p in enumerate(profiles):  # left-padded with rest: every hold ends the profile
        x[T - p.shape[0] :, b] = p
    x = x[..., 0] if c == 1 else x
    try:
        f = model.copy().simulate(x)
    except Exception:  # a model that cannot run its holds: every one confirmed, not finite
        f = np.full(x.shape, np.nan)
    flags = judge_holds(f, x[-1], n_hold, threshold, dt)
    kinds = ("not finite", "oscillating", "departing", "wrong sign")
    owner_a = np.array(owner)
    out = []
    for i, h in enumerate(listed):
        cols = np.flatnonzero(owner_a == i)
        found = tuple(k for k in kinds if flags[k][cols].any())
        if not found:
            continue
        hit = cols[np.any(np.stack([flags[k][cols] for k in kinds]), axis=0)]
        worst = int(hit[np.argmax(flags["ripple_n"][hit])])
        shows = np.flatnonzero(flags["coordinates"][hit].any(axis=0))
        if shows.size == 0:  # a wrong sign of the work alone: the coordinates held
            shows = np.flatnonzero(_held(h))
        out.append(Confirmed(
            tuple(_held(h).tolist()), found, float(flags["ripple_n"][worst]), how[worst],
            tuple(int(k) for k in shows), int(flags["worst_coordinate"][worst]),
        ))  # fmt: skip
    return out, len(profiles)


def ranges_of(x_m: list[float], step_m: float) -> list[tuple[float, float]]:
    """Runs of sorted ``x_m`` whose neighbours are at most 1.5 ``step_m`` apart: [(lo, hi)]."""
    xs = sorted(x_m)
    out: list[tuple[float, float]] = []
    for v in xs:
        if out and v - out[-1][1] <= 1.5 * step_m:
            out[-1] = (out[-1][0], v)
        else:
            out.append((v, v))
    return out


def boxes_of(q: np.ndarray, step) -> list[tuple[tuple[float, float], ...]]:
    """Boxes about held vectors ``q`` (M, C): the vectors chained by neighbours at most 1.5
    ``step`` (a number or (C,)) apart on every coordinate, each chain's per-coordinate (lo, hi)
    widened by one ``step`` (the holds were seen, not what lies between them); in the order
    of each chain's first vector."""
    q = np.asarray(q, dtype=np.float64).reshape(len(q), -1)
    step = np.broadcast_to(np.asarray(step, dtype=np.float64), (q.shape[1],))
    near = np.all(np.abs(q[:, None] - q[None]) <= 1.5 * step, axis=2)
    group = np.arange(len(q))
    for _ in range(len(q)):  # join each vector to its neighbours' lowest label until settled
        new = np.array([group[near[i]].min() for i in range(len(q))])
        if np.array_equal(new, group):
            break
        group = new
    out = []
    for g in dict.fromkeys(group.tolist()):
        members = q[group == g]
        lo, hi = members.min(axis=0) - step, members.max(axis=0) + step
        out.append(tuple((float(a), float(b)) for a, b in zip(lo, hi, strict=True)))
    return out


# ----- the certificate's listing of a model's failing holds -----------------------------------
FAILING_KINDS = ("oscillates", "departs", "wrong_sign")  # what a listed hold is listed as


def hold_entries(
    model,
    reference=None,
    stroke_m: float = 12.5e-3,
    holds: int = 201,
    hold_s: float = CERTIFY_HOLD_S,
    q: np.ndarray | None = None,
) -> list[dict]:
    """The certificate's ``holds`` entries (fixed points, free runs, static force) over a
    uniform grid of ``holds`` over -stroke..+stroke, or over the held vectors ``q`` (M, C) of a
    model of C coordinates, without the passivity and the energy scan; ``reference`` None:
    wrong sign against the deflection (``certificate.wrong_sign``). Raises ``CertifyError`` for
    a model that is not a NARX network."""
    from bushenv.certify.certificate import wrong_sign
    from bushenv.certify.document import hold_entry

    net = narx_net(model)
    x = np.linspace(-stroke_m, stroke_m, holds) if q is None else np.asarray(q, np.float64)
    fp = fixed_points(net, x)
    gh = ghosts(net, x)
    runs, _, _ = free_runs(model, net, fp, gh, hold_s)
    n = len(x)
    ref = np.full((n, net.n_coords), np.nan)
    if reference is not None:
        ref = reference_static_force(reference, x).reshape(n, net.n_coords)
    return [hold_entry(net, fp, gh, r, i, ref[i], [], wrong_sign) for i, r in enumerate(runs)]


def failing_holds(entries: list[dict]) -> list[dict]:
    """[{"q", "x_m", "kinds", "departure_s"}] of the entries listed as oscillating, departing or
    wrong-sign (``kinds`` among ``FAILING_KINDS``), in the entries' order; ``x_m`` only for one
    coordinate (its held x)."""
    out = []
    for h in entries:
        kinds = [k for k in FAILING_KINDS if h.get(k)]
        if kinds:
            hold = {"q": h["q"], "kinds": kinds, "departure_s": h.get("departure_s")}
            if "x_m" in h:
                hold["x_m"] = h["x_m"]
            out.append(hold)
    return out
