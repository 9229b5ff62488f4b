"""Actions, reset options and replayed profiles: cleaned where a number can be, refused with a
``RigError`` naming the value where it cannot (the same rules in every rig, single and vector)."""

from __future__ import annotations

import math
import numbers
import reprlib
from collections.abc import Mapping
from typing import Any

import numpy as np

from bushenv.rigs.common import RigError

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


def unit_vector(action: Any, c: int, env_id: str = "env") -> list[float]:
    """A normalised action of ``c`` coordinates as ``c`` floats in [-1, 1], each cleaned like
    ``unit_action`` (one coordinate: ``unit_action`` itself, with its fast path); anything but
    real numbers of shape (c,) is refused with a ``RigError`` naming the shape."""
    if c == 1:
        return [unit_action(action, env_id)]
    if action.__class__ is np.ndarray and action.dtype is _F32 and action.shape == (c,):
        arr = action  # what agents send: no conversion to check
    else:
        arr = _array(action)
    if arr is None or arr.shape != (c,):
        raise RigError(
            f"{env_id}: action {describe(action)} does not fit the action space "
            f"Box(-1.0, 1.0, ({c},), float32): expected real numbers in an array of shape ({c},)"
        )
    out = []
    for a in arr.tolist():
        a = float(a)
        out.append(0.0 if a != a else (1.0 if a > 1.0 else (-1.0 if a < -1.0 else a)))
    return out


def unit_actions(actions: Any, n: int, env_id: str = "vector env", c: int = 1) -> np.ndarray:
    """(N, c) normalised actions as float64, cleaned like ``unit_action``: (N, c) or, for one
    coordinate, also (N,) taken, and (N,) returned; any other shape or a non-numeric action is
    refused with a ``RigError`` naming (N, c)."""
    if actions.__class__ is np.ndarray and actions.dtype.kind in REAL_KINDS:
        arr = actions
    else:
        arr = _array(actions)
    if arr is None or arr.shape not in (((n, 1), (n,)) if c == 1 else ((n, c),)):
        raise RigError(
            f"{env_id}: actions {describe(actions)} do not fit the action space "
            f"Box(-1.0, 1.0, ({n}, {c}), float32): expected real numbers in an array of shape "
            f"({n}, {c})"
        )
    a = arr.astype(np.float64).reshape((n,) if c == 1 else (n, c))
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
