"""What every rig shares: spec files, model resolution, action clean-up, reward and divergence
verdicts, the fixed-rate split coupling of a bushing into pymunk, and drawing.

Spec files
    ``envs/<id>.toml`` (shipped in the wheel as the resource package ``bushenv.envs``; in a
    source checkout read from ``envs/`` beside the package). ``[kwargs]`` holds every default an
    environment takes; the constructors refuse keys the spec does not name.

Hooks (the same contract for every rig, single and vectorised)
    ``reward_fn(info) -> float`` and ``divergence_monitor(info) -> bool | str``: called once per
    step with the step's ``info`` dict (plain floats in a single env; (N,) arrays in a vector
    env, where they return (N,) arrays). A monitor's truthy answer ends the episode as a
    divergence; a string answer is used as the reason. If the callable has a ``reset()``
    method it is called at every ``reset``; a vector env calls ``reset_columns(mask)`` when it
    auto-resets some of its sub-environments (and ``reset()`` if that is absent).

Fixed-rate coupling (seed 001 §2: the network ran at 204.8 Hz beside ADAMS)
    The bushing model steps at its sample time ``dt``; pymunk sub-steps in between. Holding the
    sampled force over ``dt`` is an explicit scheme, unstable once omega * dt nears 1 (see
    ../shared/DESIGN-NOTES.md). ``SplitBushing`` therefore applies a linear spring-damper
    (``k_in``, ``c_in``) inside every pymunk sub-step and holds only the remainder::

        F(t) = k_in x(t) + c_in v(t) + [F_model(x_k, v_k) - k_in x_k - c_in v_k],  t_k <= t < t_k+1

    At the sample instants F equals the model's force exactly; for a linear model with k_in,
    c_in the held remainder is exactly zero and the coupling is the continuous system.
"""

from __future__ import annotations

import math
import numbers
import os
import reprlib
import tomllib
from collections.abc import Callable, Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.models import MODELS, BushingModel, get_model, get_reference

SPEC_PACKAGE = "bushenv.envs"
SOURCE_SPEC_DIR = Path(__file__).resolve().parents[2] / "envs"


class RigError(ValueError):
    """A rig argument, spec file or excitation is wrong; the message names it and the value."""


# What a model's step may raise that ends its episode as a divergence instead of escaping the
# env: a ValueError (ModelError: the model refusing to go on, e.g. Bouc-Wen's guard) or an
# ArithmeticError (ZeroDivisionError, FloatingPointError under np.seterr, OverflowError).
MODEL_ERRORS = (ValueError, ArithmeticError)


# ----- spec files --------------------------------------------------------------------------
def spec_directory() -> Any:
    """The folder holding the env specs: the installed ``bushenv.envs`` resource package, or
    ``envs/`` of a source checkout. Returns a ``Traversable`` (``Path`` in a checkout)."""
    try:
        root = resources.files(SPEC_PACKAGE)
        if any(p.name.endswith(".toml") for p in root.iterdir()):
            return root
    except (ModuleNotFoundError, FileNotFoundError, NotADirectoryError, TypeError):
        pass
    return SOURCE_SPEC_DIR


def spec_files() -> list[Any]:
    """Every ``*.toml`` spec, sorted by name."""
    root = spec_directory()
    return sorted((p for p in root.iterdir() if p.name.endswith(".toml")), key=lambda p: p.name)


def read_spec(source: Any) -> dict[str, Any]:
    """Parse one spec file (a path or ``Traversable``) and check its required keys."""
    name = getattr(source, "name", str(source))
    try:
        spec = tomllib.loads(source.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise RigError(f"{name}: not valid TOML: {exc}") from None
    for key in ("id", "entry_point", "kwargs"):
        if key not in spec:
            raise RigError(f"{name}: spec lacks the required key {key!r}")
    if name != f"{spec['id']}.toml":
        raise RigError(f"{name}: file name does not match its id {spec['id']!r}")
    return spec


def load_spec(env_id: str) -> dict[str, Any]:
    """The parsed spec of ``env_id`` (e.g. ``"BushRig-v0"``)."""
    for f in spec_files():
        if f.name == f"{env_id}.toml":
            return read_spec(f)
    raise RigError(f"no spec file {env_id}.toml in {spec_directory()}")


def spec_kwargs(env_id: str, overrides: dict[str, Any]) -> dict[str, Any]:
    """The spec's ``[kwargs]`` updated by ``overrides``; an unknown key is refused."""
    kwargs = dict(load_spec(env_id)["kwargs"])
    unknown = sorted(set(overrides) - set(kwargs))
    if unknown:
        raise RigError(f"{env_id}: unknown argument(s) {unknown}; the spec knows {sorted(kwargs)}")
    kwargs.update(overrides)
    return kwargs


def positive(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise RigError(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise RigError(f"{name} must be a positive finite number, got {value!r}")
    return v


def positive_int(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise RigError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def per_axis(name: str, value: Any, axis: str) -> float:
    """A number, or a table ``{axial = ..., radial = ...}`` indexed by ``axis``."""
    if isinstance(value, dict):
        if axis not in value:
            raise RigError(f"{name} has no entry for axis {axis!r}: {value!r}")
        value = value[axis]
    return positive(f"{name}[{axis}]", value)


# ----- models --------------------------------------------------------------------------------
def resolve_model(spec: Any, axis: str, dt: float) -> BushingModel:
    """The model under test: a registered name, a ``.npz`` path or a model object (copied, so
    two environments never share one model's state)."""
    model = get_model(spec, axis=axis, dt=dt)
    model.reset(1)
    return model


def resolve_reference(spec: Any, axis: str, dt: float) -> BushingModel:
    """The reference bushing (``bushenv.models.get_reference``; ``"rubber"``: the calibrated
    specimen without the load cell's delay, fixture inertia and noise)."""
    model = get_reference(spec, axis=axis, dt=dt)
    model.reset(1)
    return model


def model_label(model: BushingModel, spec: Any) -> str:
    if isinstance(spec, str | os.PathLike) and not isinstance(spec, BushingModel):
        text = os.fspath(spec)
        return text if text in MODELS else Path(text).name
    return model.name


def shared_state_rows(model: BushingModel, probe_steps: int = 24) -> np.ndarray:
    """Rows of ``model.state`` that are shared by all histories, not one per history.

    Some kernels keep a ring-buffer position in ``state[0, 0]`` and read it for every column;
    returning one column to rest must not touch such a row. Found by probing a copy: two
    histories driven by different random inputs (seeded) keep their private rows apart, so the
    rows still equal across them are shared. A model may state them itself as an attribute
    ``shared_state_rows`` (a sequence of row indices).
    """
    declared = getattr(model, "shared_state_rows", None)
    n = model.n_state
    mask = np.zeros(n, dtype=bool)
    if declared is not None:
        mask[list(declared)] = True
        return mask
    probe = model.copy()
    probe.reset(2)
    rng = np.random.default_rng(0)
    x = rng.uniform(-2e-3, 2e-3, (probe_steps, 2))
    v = rng.uniform(-0.1, 0.1, (probe_steps, 2))
    try:
        for t in range(probe_steps):
            probe.step(x[t], v[t])
    except MODEL_ERRORS:
        return mask
    st = probe.state
    if st.shape[0] == n:
        mask = st[:, 0] == st[:, 1]
    return mask


def reset_columns(model: BushingModel, mask: np.ndarray, shared: np.ndarray | None = None) -> None:
    """Return the histories ``mask`` of a batched model to rest, leaving the others (and the
    rows ``shared`` by all histories, see ``shared_state_rows``). A model with its own
    ``reset_columns(mask)`` method is asked to do it."""
    own = getattr(model, "reset_columns", None)
    if callable(own):
        own(mask)
        return
    n = int(mask.sum())
    if not n:
        return
    rest = model.initial_state(n)
    if shared is None or not shared.any():
        model.state[:, mask] = rest
    else:
        rows = np.flatnonzero(~shared)
        model.state[np.ix_(rows, np.flatnonzero(mask))] = rest[rows]


# ----- actions ------------------------------------------------------------------------------
ACTION_SPACE_TEXT = "Box(-1.0, 1.0, (1,), float32)"
REAL_KINDS = "fiu"  # numpy dtype kinds taken as numbers: float, signed and unsigned int
_F32 = np.dtype(np.float32)  # the action space's dtype: ``unit_action``'s fast path


def describe(value: Any) -> str:
    """A short, one-line description of a value for an error message."""
    if isinstance(value, np.ndarray):
        return f"<array of shape {value.shape}, dtype {value.dtype}>"
    if value is None:
        return "None"
    text = reprlib.repr(value).replace("\n", " ")
    return f"<{type(value).__name__} {text}>"


def _real(value: Any) -> float | None:
    """``value`` as a float if it is one real number (not bool, not text), else None."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        return None
    try:
        return float(value)
    except OverflowError:  # an int beyond float range
        return math.inf if value > 0 else -math.inf
    except (TypeError, ValueError):
        return None


def _array(value: Any) -> np.ndarray | None:
    """``value`` as a real-valued array (object arrays of real numbers converted), else None."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError, OverflowError):  # ragged lists, odd __array__s
        return None
    if arr.dtype.kind in REAL_KINDS:
        return arr
    if arr.dtype.kind == "O":
        flat = [_real(v) for v in arr.reshape(-1)]
        if all(v is not None for v in flat):
            return np.array(flat, dtype=np.float64).reshape(arr.shape)
    return None


def _checked_action(action: Any, env_id: str) -> float:
    """The slow path of ``unit_action``: anything but a real (1,) ndarray."""
    a = _real(action)
    if a is not None:
        return a
    arr = _array(action)
    if arr is None or arr.shape not in ((), (1,)):
        raise RigError(
            f"{env_id}: action {describe(action)} does not fit the action space "
            f"{ACTION_SPACE_TEXT}: expected a real number or an array of shape (1,)"
        )
    return float(arr.reshape(1)[0])


def unit_action(action: Any, env_id: str = "env") -> float:
    """A normalised scalar action as a float in [-1, 1]: NaN -> 0, +-inf and beyond -> +-1.

    Takes a real number or anything of shape (1,) holding one (an ndarray of any float or int
    dtype, a list); anything else -- text, None, complex, dicts, empty or longer arrays -- is
    refused with a ``RigError`` naming ``env_id``, the action space and the expected shape. A
    float32 ndarray of shape (1,) (what agents send) takes a fast path of three cheap checks;
    everything else goes through ``_checked_action``."""
    if action.__class__ is np.ndarray and action.dtype is _F32 and action.shape == (1,):
        a = action.item()
    else:
        a = _checked_action(action, env_id)
    if a != a:
        return 0.0
    if a > 1.0:
        return 1.0
    if a < -1.0:
        return -1.0
    return a


def unit_actions(actions: Any, n: int, env_id: str = "vector env") -> np.ndarray:
    """(N, 1) or (N,) normalised actions as float64 (N,), cleaned like ``unit_action``; any
    other shape or a non-numeric action is refused with a ``RigError`` naming (N, 1)."""
    if actions.__class__ is np.ndarray and actions.dtype.kind in REAL_KINDS:
        arr = actions
    else:
        arr = _array(actions)
    if arr is None or arr.shape not in ((n, 1), (n,)):
        raise RigError(
            f"{env_id}: actions {describe(actions)} do not fit the action space "
            f"Box(-1.0, 1.0, ({n}, 1), float32): expected real numbers in an array of shape "
            f"({n}, 1)"
        )
    a = arr.astype(np.float64).reshape(n)
    a[np.isnan(a)] = 0.0
    np.clip(a, -1.0, 1.0, out=a)
    return a


def check_options(env_id: str, options: Any) -> dict[str, Any]:
    """``reset(options=...)``: None or a dict (mapping); returns a dict."""
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise RigError(
            f"{env_id}: reset options must be a dict such as {{'excitation': profile}} or None, "
            f"got {describe(options)}"
        )
    return options


def numeric_profile(name: str, profile: Any) -> np.ndarray:
    """A profile (excitation, road) as a float64 array; text or other non-numbers refused."""
    arr = _array(profile)
    if arr is None:
        raise RigError(f"{name} must be numbers in a (T,) or (T, N) array, got {describe(profile)}")
    return np.array(arr, dtype=np.float64)


def check_profile(
    name: str,
    profile: Any,
    sample: str,
    max_abs: float,
    abs_text: str,
    max_step: float,
    step_text: str,
) -> np.ndarray:
    """A replayable profile for both rigs: finite (T,) or (T, N), |value| <= ``max_abs`` and each
    sample (starting from 0) at most ``max_step`` from the previous one. ``sample`` names a
    sample in messages ("excitation", "road"); ``abs_text``/``step_text`` format the limits."""
    a = numeric_profile(name, profile)
    if a.ndim not in (1, 2) or a.shape[0] < 1:
        raise RigError(f"excitation must have shape (T,) or (T, N) with T >= 1, got {a.shape}")
    bad = ~np.isfinite(a)
    if bad.any():
        i = np.argwhere(bad)[0]
        raise RigError(f"{sample} sample {int(i[0])} is {a[tuple(i)]!r}, not finite")
    tol = 1 + 1e-9
    over = np.abs(a) > max_abs * tol
    if over.any():
        i = tuple(np.argwhere(over)[0])
        raise RigError(f"{sample} sample {i[0]}: " + abs_text.format(value=abs(a[i])))
    steps = np.abs(np.diff(a, axis=0, prepend=np.zeros((1,) + a.shape[1:])))
    fast = steps > max_step * tol
    if fast.any():
        i = tuple(np.argwhere(fast)[0])
        raise RigError(f"{sample} sample {i[0]}: " + step_text.format(value=steps[i]))
    return a


# ----- reward ---------------------------------------------------------------------------------
class ForceDeviationReward:
    """The adversarial objective: how far the model's force is from the reference's.

        r = min(|F_model - F_reference| / force_scale_n, cap);   r = cap if not finite

    ``force_scale_n`` is the reference-sized force of the rig (spec ``force_scale_n``), so r is
    a dimensionless deviation, 0 when the model is perfect. Works on a single env's info
    (floats) and a vector env's (arrays). Reads ``info["error_n"]``.
    """

    def __init__(self, force_scale_n: float, cap: float) -> None:
        self.force_scale_n = positive("force_scale_n", force_scale_n)
        self.cap = positive("reward_cap", cap)

    def __call__(self, info: dict[str, Any]) -> Any:
        e = info["error_n"]
        if isinstance(e, np.ndarray):
            r = np.abs(e) / self.force_scale_n
            np.minimum(r, self.cap, out=r)
            r[~np.isfinite(r)] = self.cap
            return r
        r = abs(e) / self.force_scale_n
        if not (r <= self.cap):  # also catches NaN
            return self.cap
        return r


def call_reset(hook: Any) -> None:
    reset = getattr(hook, "reset", None)
    if callable(reset):
        reset()


def call_reset_columns(hook: Any, mask: np.ndarray) -> None:
    fn = getattr(hook, "reset_columns", None)
    if callable(fn):
        fn(mask)
    else:
        call_reset(hook)


def check_hook(name: str, hook: Callable | None) -> Callable | None:
    if hook is not None and not callable(hook):
        raise RigError(f"{name} must be callable(info) or None, got {hook!r}")
    return hook


def force_observation(f: float, limit: float) -> float:
    """F / limit clipped to [-1, 1]; NaN -> 0 (the episode ends on it anyway)."""
    r = f / limit
    if r != r:
        return 0.0
    if r > 1.0:
        return 1.0
    if r < -1.0:
        return -1.0
    return r


def force_observations(f: np.ndarray, limit: float) -> np.ndarray:
    r = f / limit
    r[np.isnan(r)] = 0.0
    np.clip(r, -1.0, 1.0, out=r)
    return r


# ----- split coupling --------------------------------------------------------------------------
# A pymunk DampedSpring acts along the line between its anchors. Anchoring one end LONG_ARM_M
# away along the bushing direction makes it a one-direction spring: a perpendicular offset d
# changes its length by d^2 / (2 LONG_ARM_M) (1e-8 m for d = 1 mm).
LONG_ARM_M = 50.0


def inverse_mass_along(a, b, anchor_a, anchor_b, direction) -> float:
    """Chipmunk's k = 1/m_a + 1/m_b + (r_a x n)^2 / I_a + (r_b x n)^2 / I_b at the anchors
    (local points), n a world direction: the inverse mass a force along n meets."""
    n0, n1 = direction
    k = 0.0
    for body, anchor in ((a, anchor_a), (b, anchor_b)):
        if body.body_type != body.DYNAMIC:
            continue
        r = _rotate(body.angle, anchor)
        cross = r[0] * n1 - r[1] * n0
        k += 1.0 / body.mass
        if math.isfinite(body.moment):
            k += cross * cross / body.moment
    return k


def _rotate(angle: float, p) -> tuple[float, float]:
    c, s = math.cos(angle), math.sin(angle)
    return c * p[0] - s * p[1], s * p[0] + c * p[1]


def implicit_euler_damping(c: float, h: float, k_inv_mass: float) -> float:
    """The chipmunk damping coefficient that makes a DampedSpring's damper act as implicit Euler.

    Chipmunk damps the relative velocity exactly, v <- v exp(-d h k), as if the damper were
    alone. With forces applied explicitly in the same step that over-damps badly once
    c h k >~ 0.1: a spring-damper loaded by F then creeps at F / (c_eff), c_eff ~ (e^{chk} - 1) /
    (h k), five times too slowly at c h k = 2.7 (the radial bushing on the control arm at 16
    sub-steps). Choosing d = ln(1 + c h k) / (h k) gives v <- v / (1 + c h k): implicit Euler,
    whose creep rate F / c is exact and which stays stable for any c h k.
    """
    x = c * h * k_inv_mass
    if x <= 0.0:
        return c
    return math.log1p(x) / (h * k_inv_mass)


class SplitBushing:
    """One axis of a bushing between pymunk bodies ``a`` (holds the bushing frame) and ``b``.

    ``direction`` is a unit vector fixed in ``a``'s frame (``a`` must not rotate); ``anchor_a``,
    ``anchor_b`` are the coincident bushing centres in each body's local frame at rest.

    The linear part k_in x + c_in v is a pymunk DampedSpring, evaluated in C inside every
    sub-step (its damper made implicit Euler by ``implicit_euler_damping``; call
    ``update_damping`` when the configuration has changed). ``hold(F, x, v)`` holds the
    remainder H = F - (k_in x + c_in v) of the sampled model force for the coming model step by
    shifting the spring's rest length by -H / k_in: the spring then pushes b with
    -(k_in x(t) + c_in v(t) + H), so no Python runs per sub-step.
    """

    def __init__(self, space, a, b, anchor_a, anchor_b, direction, k_in, c_in, h) -> None:
        import pymunk

        self.a, self.b = a, b
        self.h = positive("sub-step", h)
        self.k_in = positive("k_in", k_in)
        self.c_in = float(c_in)
        self.direction = (float(direction[0]), float(direction[1]))
        self.anchor_a = (float(anchor_a[0]), float(anchor_a[1]))
        self.anchor_b = (float(anchor_b[0]), float(anchor_b[1]))
        far = (
            self.anchor_a[0] - LONG_ARM_M * self.direction[0],
            self.anchor_a[1] - LONG_ARM_M * self.direction[1],
        )
        self.spring = pymunk.DampedSpring(a, b, far, self.anchor_b, LONG_ARM_M, k_in, c_in)
        space.add(self.spring)
        self.held_n = 0.0
        self.update_damping()

    def update_damping(self) -> None:
        """Set the chipmunk damping for implicit-Euler c_in at the current configuration."""
        k = inverse_mass_along(self.a, self.b, self.anchor_a, self.anchor_b, self.direction)
        self.spring.damping = implicit_euler_damping(self.c_in, self.h, k)

    def project(self, dx: float, dy: float) -> float:
        return dx * self.direction[0] + dy * self.direction[1]

    def hold(self, force_n: float, x: float, v: float) -> float:
        """Hold the remainder of the sampled model force ``force_n`` at deflection (x, v)."""
        held = force_n - (self.k_in * x + self.c_in * v)
        self.held_n = held
        self.spring.rest_length = LONG_ARM_M - held / self.k_in
        return held

    def release(self) -> None:
        self.held_n = 0.0
        self.spring.rest_length = LONG_ARM_M


def space_stepper(space):
    """``space.step`` without pymunk's per-call Python bookkeeping (it re-checks masses and
    processes deferred additions; our spaces add nothing while stepping): calls chipmunk's
    cpSpaceStep directly, 3-5 us less per sub-step. Falls back to ``space.step``."""
    try:
        from pymunk._chipmunk import lib

        space.step(0.0)  # pymunk's one-off checks of the bodies, no motion
        handle = space._space
        cp_step = lib.cpSpaceStep

        def step(dt: float) -> None:
            cp_step(handle, dt)

        return step
    except (ImportError, AttributeError):  # another pymunk layout
        return space.step


def velocity_setter(body):
    """``body.velocity = (vx, vy)`` through chipmunk directly (pymunk's attribute machinery
    costs ~1 us a call); falls back to the attribute."""
    try:
        from pymunk._chipmunk import lib

        handle = body._body
        cp_set = lib.cpBodySetVelocity
        cp_set(handle, (0.0, 0.0))

        def set_velocity(vx: float, vy: float) -> None:
            cp_set(handle, (vx, vy))

        return set_velocity
    except (ImportError, AttributeError, TypeError):

        def set_velocity(vx: float, vy: float) -> None:
            body.velocity = (vx, vy)

        return set_velocity


# ----- drawing -------------------------------------------------------------------------------
class Canvas:
    """A pygame surface for ``rgb_array`` frames, or a window for ``human``."""

    def __init__(self, width: int, height: int, render_mode: str, fps: int, title: str) -> None:
        import pygame

        self.pygame = pygame
        self.width, self.height = width, height
        self.render_mode = render_mode
        self.fps = fps
        pygame.font.init()
        self.font = pygame.font.Font(None, 20)
        self.small = pygame.font.Font(None, 16)
        if render_mode == "human":
            pygame.display.init()
            pygame.display.set_caption(title)
            self.window = pygame.display.set_mode((width, height))
            self.clock = pygame.time.Clock()
        else:
            self.window = None
            self.clock = None
        self.surface = pygame.Surface((width, height))

    def clear(self) -> None:
        self.surface.fill((250, 250, 247))

    def line(self, p, q, color, width=2) -> None:
        self.pygame.draw.line(self.surface, color, _ipt(p), _ipt(q), width)

    def lines(self, points, color, width=1) -> None:
        if len(points) > 1:
            self.pygame.draw.lines(self.surface, color, False, [_ipt(p) for p in points], width)

    def rect(self, x, y, w, h, color, width=0) -> None:
        self.pygame.draw.rect(self.surface, color, (int(x), int(y), int(w), int(h)), width)

    def circle(self, c, r, color, width=0) -> None:
        self.pygame.draw.circle(self.surface, color, _ipt(c), int(r), width)

    def polygon(self, points, color, width=0) -> None:
        self.pygame.draw.polygon(self.surface, color, [_ipt(p) for p in points], width)

    def text(self, s, p, color=(30, 30, 30), small=False) -> None:
        font = self.small if small else self.font
        self.surface.blit(font.render(s, True, color), _ipt(p))

    def arrow(self, p, q, color, width=3) -> None:
        """An arrow from p to q (pixels); nothing if shorter than 2 px."""
        dx, dy = q[0] - p[0], q[1] - p[1]
        n = math.hypot(dx, dy)
        if n < 2:
            return
        ux, uy = dx / n, dy / n
        head = min(10.0, 0.5 * n)
        self.line(p, q, color, width)
        left = (q[0] - head * ux + 0.5 * head * uy, q[1] - head * uy - 0.5 * head * ux)
        right = (q[0] - head * ux - 0.5 * head * uy, q[1] - head * uy + 0.5 * head * ux)
        self.polygon([q, left, right], color)

    def force_bar(self, x, y, w, h, value, limit, color, label) -> None:
        """A horizontal bar centred at x + w/2: value / limit of the half width, clipped."""
        self.rect(x, y, w, h, (225, 225, 222))
        mid = x + w / 2
        frac = value / limit if math.isfinite(value) else (1.0 if value > 0 else -1.0)
        frac = max(-1.0, min(1.0, frac)) if math.isfinite(frac) else 0.0
        length = frac * w / 2
        self.rect(min(mid, mid + length), y, abs(length), h, color)
        self.line((mid, y - 2), (mid, y + h + 2), (90, 90, 90), 1)
        self.text(label, (x, y - 16), small=True)

    def frame(self) -> np.ndarray | None:
        pygame = self.pygame
        if self.render_mode == "human":
            pygame.event.pump()
            self.window.blit(self.surface, (0, 0))
            pygame.display.flip()
            self.clock.tick(self.fps)
            return None
        return np.transpose(np.array(pygame.surfarray.pixels3d(self.surface)), (1, 0, 2)).copy()

    def close(self) -> None:
        if self.window is not None:
            self.pygame.display.quit()
            self.window = None


def _ipt(p) -> tuple[int, int]:
    return int(round(p[0])), int(round(p[1]))


class Trace:
    """A fixed-size ring of the last ``n`` samples of a few channels (for drawing only), so a
    long rollout keeps memory flat."""

    def __init__(self, channels: int, n: int = 256) -> None:
        self.buf = np.zeros((channels, n))
        self.n = n
        self.count = 0

    def clear(self) -> None:
        self.buf[:] = 0.0
        self.count = 0

    def push(self, *values: float) -> None:
        i = self.count % self.n
        for c, v in enumerate(values):
            self.buf[c, i] = v
        self.count += 1

    def ordered(self) -> np.ndarray:
        """(channels, m) oldest first, m = min(count, n)."""
        m = min(self.count, self.n)
        if self.count <= self.n:
            return self.buf[:, :m]
        i = self.count % self.n
        return np.concatenate([self.buf[:, i:], self.buf[:, :i]], axis=1)


def plot_traces(canvas: Canvas, box, trace: Trace, scales, colors, labels) -> None:
    """Draw trace channels in a box (x, y, w, h), each scaled to +-scale of the half height."""
    x0, y0, w, h = box
    canvas.rect(x0, y0, w, h, (238, 238, 234))
    canvas.line((x0, y0 + h / 2), (x0 + w, y0 + h / 2), (180, 180, 180), 1)
    data = trace.ordered()
    m = data.shape[1]
    if m >= 2:
        xs = x0 + np.arange(m) * (w / (trace.n - 1))
        for c in range(data.shape[0]):
            ys = y0 + h / 2 - np.clip(np.nan_to_num(data[c] / scales[c]), -1, 1) * (h / 2 - 2)
            canvas.lines(list(zip(xs, ys, strict=True)), colors[c], 2)
    for i, (lab, col) in enumerate(zip(labels, colors, strict=True)):
        canvas.text(lab, (x0 + 6 + (w / len(labels)) * i, y0 + 4), col, small=True)
