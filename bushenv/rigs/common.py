"""What every rig shares: the error type, argument checks, model resolution, column resets of
batched models, the default reward, the hook contract and observation clipping.

Hooks (the same contract for every rig, single and vectorised)
    ``reward_fn(info) -> float`` and ``divergence_monitor(info) -> bool | str``: called once per
    step with the step's ``info`` dict (plain floats in a single env; (N,) arrays in a vector
    env, where they return (N,) arrays). A monitor's truthy answer ends the episode as a
    divergence; a string answer is used as the reason. If the callable has a ``reset()``
    method it is called at every ``reset``; a vector env calls ``reset_columns(mask)`` when it
    auto-resets some of its sub-environments (and ``reset()`` if that is absent).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.errors import DIVERGENCE_RAISES
from bushenv.models import MODELS, BushingModel, ModelError, get_model, names_for
from bushenv.models.base import DT_TOLERANCE, PAPER_DT
from bushenv.rigs.errors import RigError

# What a model's step may raise that ends its episode as a divergence: its own state ran away
# (Bouc-Wen's guard) or 1/0, overflow (``bushenv.errors``). Anything else the model raises is a
# model error: the episode ends with ``info["model_error"]``, never as a divergence.
MODEL_ERRORS = DIVERGENCE_RAISES


def model_error_text(exc: BaseException) -> str:
    """One line for ``info["model_error"]``: the exception's type and the model's message."""
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"


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
def resolve_model(
    spec: Any,
    axis: str = "axial",
    dt: float = PAPER_DT,
    coords: int = 1,
    what: str = "model",
    env_id: str = "BushRig-v0",
    rate_setting: str = "",
) -> BushingModel:
    """The model under test over ``coords`` coordinates: a registered name, a ``.npz`` path or a
    model object (copied, so two environments never share one model's state), at rest.

    One coordinate: ``axis``'s model (``get_model``'s errors). Several: a name builds its form
    over that many coordinates at its reference preset (without load-cell noise); errors name
    ``env_id`` and the argument ``what``; a file at another rate names ``rate_setting`` (the
    caller's argument that sets the step) with the value to give."""
    if coords == 1:
        model = get_model(spec, axis=axis, dt=dt)
        model.reset(1)
        return model
    wanted = f"{env_id}'s {what}"
    if isinstance(spec, BushingModel) or (isinstance(spec, str) and spec in MODELS):
        options = MODELS[spec].reference_preset if isinstance(spec, str) else None
        try:
            model = get_model(spec, dt=dt, preset=options, coords=coords, wanted_by=wanted)
        except ModelError as exc:
            raise RigError(f"{env_id}: {what}: {exc}") from None
    elif isinstance(spec, str | Path) and str(spec).endswith(".npz"):
        try:
            model = get_model(str(spec), coords=coords, wanted_by=wanted)
        except ModelError as exc:
            raise RigError(f"{env_id}: {what}: {exc}") from None
        if abs(model.dt - dt) > DT_TOLERANCE * dt:  # a fit at its records' rate: say what to set
            fix = f"pass {rate_setting}={model.dt:.6g}" if rate_setting else "give both one rate"
            raise RigError(
                f"{env_id}: {what} {spec}: model sampled at {1 / model.dt:.6g} Hz, "
                f"expected {1 / dt:.6g} Hz (dt={dt:.6g} s): {fix}"
            )
    else:
        kind = "three-axis" if coords == 3 else f"{coords}-coordinate"
        raise RigError(
            f"{env_id}: {what} {spec!r}: {MODELS.unknown_message(spec)} ({kind}: "
            f"{', '.join(names_for(coords))}), or a {kind} .npz model file"
        )
    model.reset(1)
    return model


def resolve_reference(
    spec: Any,
    axis: str,
    dt: float,
    model: Any = None,
    model_object: BushingModel | None = None,
    trust_reference: bool = False,
    where: Any = None,
) -> BushingModel:
    """The reference bushing, through the one judging setup (``bushenv.judge``): vetted
    before it judges (a ``JudgeError`` names what failed, unless ``trust_reference``). The
    envs' own verdicts (not finite, beyond the machine's force) do not compare the model with
    the reference, so they vet the reference alone (``model`` None: holds and its records, no
    compatibility check); the attack, which compares, passes the model too.
    ``"rubber"``: the calibrated specimen without the load cell's delay, inertia and noise."""
    from bushenv.judge import Where, build_judge

    where = where or Where("BushRig-v0", reference_free=False)

    if spec is None or (isinstance(spec, str) and spec.strip().lower() == "none"):
        raise RigError("reference: the rig runs a reference beside the model; give one")
    judge = build_judge(
        model, spec, axis=axis, dt=dt, target=where,
        trust_reference=trust_reference,
        model_object=model_object,
    )  # fmt: skip
    reference = judge.reference
    reference.reset(1)
    reference.judge = judge  # what judged: recorded by the env (``judge`` in its params)
    return reference


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
    if callable(getattr(model, "reset_columns", None)):  # it resets its own columns
        return mask
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
    except Exception:  # a model that cannot take this probe: every row its own
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


# ----- reward ---------------------------------------------------------------------------------
class ForceDeviationReward:
    """The adversarial objective: how far the model's force is from the reference's.

        r = min(sum_i |e_i| / force_scale_i, cap);   r = cap if not finite

    over the errors e_i (model minus reference force, N or N m) the rig writes into ``info``
    under ``keys`` (``"error_n"`` by default: one force), each over its ``force_scale`` (the
    reference-sized force of that coordinate, spec ``force_scale_n``), so r is a dimensionless
    deviation, 0 when the model is perfect. Works on a single env's info (floats) and a vector
    env's (arrays).
    """

    def __init__(self, force_scale_n: Any, cap: float, keys: tuple[str, ...] = ("error_n",)):
        scales = np.atleast_1d(np.asarray(force_scale_n, dtype=np.float64))
        if scales.shape != (len(keys),):
            raise RigError(f"force_scale_n: {len(keys)} scales for {keys}, got {scales.tolist()}")
        self.force_scales = tuple(positive("force_scale_n", s) for s in scales)
        self.keys = tuple(keys)
        self._pairs = tuple(zip(self.keys, self.force_scales, strict=True))
        self.cap = positive("reward_cap", cap)

    @property
    def force_scale_n(self) -> float:
        """The first (one-force rigs: the only) scale."""
        return self.force_scales[0]

    def __call__(self, info: dict[str, Any]) -> Any:
        first = info[self.keys[0]]
        if first.__class__ is float:  # a single env's step: plain floats
            r = abs(first) / self.force_scales[0]
            for key, scale in self._pairs[1:]:
                r = r + abs(info[key]) / scale
            return r if r <= self.cap else self.cap  # also catches NaN
        r = None
        for key, scale in self._pairs:
            e = info[key]
            term = (np.abs(e) if isinstance(e, np.ndarray) else abs(e)) / scale
            r = term if r is None else r + term
        if isinstance(r, np.ndarray):
            np.minimum(r, self.cap, out=r)
            r[~np.isfinite(r)] = self.cap
            return r
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


def ask_monitor(monitor: Callable, info: dict[str, Any]) -> bool:
    """A divergence monitor's verdict on one step's ``info``, written into it; True ends the
    episode (a string verdict is the reason)."""
    verdict = monitor(info)
    if not verdict:
        return False
    info["monitor_verdict"] = True
    info["divergence_reason"] = verdict if isinstance(verdict, str) else "divergence monitor"
    return True


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
