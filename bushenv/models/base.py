"""The one protocol every bushing force model follows, and its file format (written by ``save``).

A model is a small stateful object over C coordinates (``coords``: one deflection, or e.g.
axial, radial and rotation) in SI units (m or rad; N or N m) at a fixed sample time ``dt``
(the papers' 204.8 Hz by default). Its memory (past inputs, past outputs, internal states)
lives in ``self.state``, an array of shape (n_state, B) for B independent histories.

Every model implements ``_advance(x, v, out)``: it runs its compiled kernel over T samples,
updating ``self.state`` in place. The arrays are (T, B) when C = 1 and (T, B, C) otherwise.
``step`` (one sample: a scalar or (B,) when C = 1, (C,) or (B, C) otherwise) and ``simulate``
(a whole profile, (T,) / (T, B) or (T, C) / (T, B, C), free run from reset) both call it, so
looped and batched results agree to the last bit. A model registered without shipped files
also gives ``preset(axis, dt)``: the parameters ``get_model(name)`` builds it with.

Model files are ``.npz`` archives read with ``allow_pickle=False`` (loading never runs code):
one array per parameter plus ``__meta__``, a JSON string with the registry name, the format
version, dt, and each parameter's shape.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from bushenv.errors import BadInput, BushenvError, ModelRaised
from bushenv.persist import atomic_write

FORMAT_VERSION = 1
PAPER_DT = 1.0 / 204.8  # s; RPC III at 204.8 Hz (seed 000 §4.1, seed 001 §3.2.2)
DT_TOLERANCE = 1e-9  # relative; two dt values closer than this are the same rate
AXES = ("axial", "radial")  # the bushing directions of seed 000 Table 1
ONE_COORD = ("deflection",)  # a one-coordinate bushing: the deflection along its axis


class ModelError(BadInput):
    """A model file or a model argument is wrong; the message names the file and the problem."""


class BushingModel:
    """Base class: state handling, step/simulate over one kernel, parameters, save/load.

    Subclasses set ``name``, ``param_names`` (the arrays that define the model; floats are
    stored as 0-d arrays), ``n_state`` (rows of the state array, may depend on parameters) and
    implement ``_advance``. They keep their constructor arguments in ``params`` (a dict of
    numpy arrays / floats) so ``save``/``load`` need nothing else.
    """

    name: ClassVar[str] = ""
    param_names: ClassVar[tuple[str, ...]] = ()
    optional_params: ClassVar[tuple[str, ...]] = ()  # may be absent from older files
    coords: ClassVar[tuple[str, ...]] = ONE_COORD  # the coordinates, in array order
    units: ClassVar[tuple[str, ...]] = ("m",)  # of each coordinate
    force_units: ClassVar[tuple[str, ...]] = ("N",)  # of each force (N m for a rotation)

    def __init__(self, dt: float = PAPER_DT) -> None:
        if not (np.isfinite(dt) and dt > 0):
            raise ModelError(f"dt must be a positive number of seconds, got {dt!r}")
        self.dt = float(dt)
        self.batch_size = 1
        self.state = np.zeros((self.n_state, 1))
        lane = (1, 1) if self.n_coords == 1 else (1, 1, self.n_coords)
        self._x1 = np.zeros(lane)
        self._v1 = np.zeros(lane)
        self._f1 = np.zeros(lane)

    @classmethod
    def coordinate_count(cls) -> int:
        """C, the number of coordinates the model takes and forces it returns."""
        return len(cls.coords)

    @property
    def n_coords(self) -> int:
        return len(self.coords)

    # ----- what subclasses provide -----------------------------------------------------
    @property
    def n_state(self) -> int:
        return 0

    def initial_state(self, batch_size: int) -> np.ndarray:
        """State at rest (zero deflection, zero force) for ``batch_size`` histories."""
        return np.zeros((self.n_state, batch_size))

    def _advance(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        """Run T samples of (T, B) C-contiguous float64 ``x``, ``v`` into ``out``; update state."""
        raise NotImplementedError

    @property
    def params(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in self.param_names}

    @classmethod
    def preset(cls, axis: str = "axial", dt: float = PAPER_DT, **options: Any) -> BushingModel:
        """A ready model of this kind for ``axis`` at ``dt``: what ``get_model(name)`` builds for
        a registered model that ships no trained files (``ModelEntry.shipped``); ``options``
        are the entry's ``reference_preset`` keywords. Kinds that ship files need none."""
        raise ModelError(
            f"model {cls.name or cls.__name__!r} has no preset: give it a preset(axis, dt) "
            "classmethod or register it with shipped=True and its trained files"
        )

    # ----- the protocol ------------------------------------------------------------------
    def reset(self, batch_size: int = 1) -> None:
        """Forget all history; prepare ``batch_size`` independent histories at rest."""
        if int(batch_size) < 1:
            raise ModelError(f"batch_size must be >= 1, got {batch_size}")
        self.batch_size = int(batch_size)
        self.state = np.ascontiguousarray(self.initial_state(self.batch_size), dtype=np.float64)
        lane = (1, self.batch_size) if self.n_coords == 1 else (1, self.batch_size, self.n_coords)
        self._x1 = np.zeros(lane)
        self._v1 = np.zeros(lane)
        self._f1 = np.zeros(lane)

    def step(self, x: float | np.ndarray, v: float | np.ndarray) -> float | np.ndarray:
        """Advance one sample. C = 1: scalars in -> float out (B == 1), (B,) in -> (B,) out.
        C > 1: (C,) in -> (C,) out (B == 1), (B, C) in -> (B, C) out."""
        if self.n_coords != 1:
            return self._step_coords(x, v)
        if np.ndim(x) == 0:
            if self.batch_size != 1:
                raise ModelError(
                    f"{self.name}: scalar step on a batch of {self.batch_size}; pass (B,) arrays"
                )
            self._x1[0, 0] = x
            self._v1[0, 0] = v
            self._guarded(self._x1, self._v1, self._f1)
            return float(self._f1[0, 0])
        x = np.asarray(x, dtype=np.float64)
        if x.shape != (self.batch_size,):
            raise ModelError(
                f"{self.name}: step got x of shape {x.shape}, expected ({self.batch_size},)"
            )
        self._x1[0] = x
        self._v1[0] = v
        self._guarded(self._x1, self._v1, self._f1)
        return self._f1[0].copy()

    def _step_coords(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``step`` over C > 1 coordinates."""
        q = np.asarray(q, dtype=np.float64)
        c = self.n_coords
        one = q.shape == (c,)
        want = (c,) if one and self.batch_size == 1 else (self.batch_size, c)
        if q.shape != want or np.shape(v) != want:
            raise ModelError(
                f"{self.name}: step got q {q.shape} and v {np.shape(v)}, expected {want} "
                f"(batch of {self.batch_size}; order {', '.join(self.coords)})"
            )
        self._x1[0] = q
        self._v1[0] = v
        self._guarded(self._x1, self._v1, self._f1)
        return self._f1[0, 0].copy() if one else self._f1[0].copy()

    def backbone_alone(self) -> BushingModel | None:
        """A hybrid's backbone as a model of its own (a fresh one, at rest), for judging what
        its network adds; None for a model without one."""
        return None

    def _guarded(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        """``_advance``, with anything the model's own code raises that is not a bushenv error
        (``ModelRefused``: a divergence; ``BadInput``) nor arithmetic turned into
        ``ModelRaised``: the model's bug, reported with its message, never a verdict."""
        try:
            self._advance(x, v, out)
        except (BushenvError, ArithmeticError):
            raise
        except Exception as exc:
            raise ModelRaised(self.name, exc) from exc

    @property
    def last_force_n(self) -> np.ndarray:
        """(B,) the force of each history at the last ``step``, N ((B, C) over C > 1
        coordinates; a copy of the output buffer).

        Also after a batched ``step`` that raised part-way: what the kernel had written by then
        (a kernel that refuses a non-finite force leaves it there for its history)."""
        return self._f1[0].copy()

    def simulate(self, x: np.ndarray, v: np.ndarray | None = None) -> np.ndarray:
        """Free run from rest over a whole profile: (T,) -> (T,) or (T, B) -> (T, B).

        Over C > 1 coordinates: (T, C) -> (T, C) or (T, B, C) -> (T, B, C).
        ``v`` defaults to the central-difference velocity of ``x`` (``np.gradient``). The model
        is reset to ``B`` histories first and keeps its final state afterwards.
        """
        if self.n_coords != 1:
            return self._simulate_coords(x, v)
        x2, v2, one_d = self._profiles(x, v)
        self.reset(x2.shape[1])
        out = np.empty_like(x2)
        self._guarded(x2, v2, out)
        return out[:, 0] if one_d else out

    def _simulate_coords(self, q: np.ndarray, v: np.ndarray | None) -> np.ndarray:
        """``simulate`` over C > 1 coordinates."""
        q = np.asarray(q, dtype=np.float64)
        c = self.n_coords
        two_d = q.ndim == 2
        q3 = q[:, None, :] if two_d else q
        if q3.ndim != 3 or q3.shape[0] < 1 or q3.shape[2] != c:
            raise ModelError(
                f"{self.name}: simulate expects (T, {c}) or (T, B, {c}) "
                f"({', '.join(self.coords)}), got {q.shape}"
            )
        if v is None:
            v3 = velocity_of(q3, self.dt)
        else:
            v3 = np.asarray(v, dtype=np.float64)
            v3 = v3[:, None, :] if v3.ndim == 2 else v3
            if v3.shape != q3.shape:
                raise ModelError(f"{self.name}: v shape {v3.shape} differs from q {q.shape}")
        q3 = np.ascontiguousarray(q3)
        v3 = np.ascontiguousarray(v3)
        self.reset(q3.shape[1])
        out = np.empty_like(q3)
        self._guarded(q3, v3, out)
        return out[:, 0, :] if two_d else out

    def _profiles(self, x, v, dtype=np.float64) -> tuple[np.ndarray, np.ndarray, bool]:
        """``simulate``'s inputs as C-contiguous (T, B) arrays of ``dtype``, and whether x was
        1-D. ``v`` defaults to the central-difference velocity of x."""

        def as_array(a):
            # float32 in, float32 wanted: no round trip through float64 (two passes over memory)
            if isinstance(a, np.ndarray) and a.dtype == dtype == np.float32:
                return a
            return np.asarray(a, dtype=np.float64)

        x = as_array(x)
        one_d = x.ndim == 1
        x2 = x[:, None] if one_d else x
        if x2.ndim != 2 or x2.shape[0] < 1:
            raise ModelError(f"{self.name}: simulate expects (T,) or (T, B), got {x.shape}")
        if v is None:
            v2 = velocity_of(x2, self.dt)
        else:
            v2 = as_array(v)
            v2 = v2[:, None] if v2.ndim == 1 else v2
            if v2.shape != x2.shape:
                raise ModelError(f"{self.name}: v shape {v2.shape} differs from x {x2.shape}")
        return np.ascontiguousarray(x2, dtype), np.ascontiguousarray(v2, dtype), one_d

    # ----- files -------------------------------------------------------------------------
    FILE_FORMAT: ClassVar[str] = "bushenv-model"

    def save(self, path: str | os.PathLike) -> Path:
        """Write the model to one ``.npz`` file atomically (temp file, then rename)."""
        path = Path(path)
        arrays = {k: np.asarray(v, dtype=np.float64) for k, v in self.params.items()}
        meta = {
            "format": self.FILE_FORMAT,
            "version": FORMAT_VERSION,
            "model": self.name,
            "dt": self.dt,
            "shapes": {k: list(a.shape) for k, a in arrays.items()},
            "extra": self.extra_meta(),
        }
        if self.n_coords != 1:  # one-coordinate files stay as they always were
            meta["coords"] = list(self.coords)
        payload = {"__meta__": np.array(json.dumps(meta)), **arrays}
        atomic_write(path, lambda fh: np.savez(fh, **payload))
        return path

    def extra_meta(self) -> dict[str, Any]:
        """Non-array settings a subclass needs to rebuild itself (plain JSON values)."""
        return {}

    @classmethod
    def from_params(cls, params: dict[str, np.ndarray], dt: float, extra: dict[str, Any]):
        return cls(dt=dt, **{k: params[k] for k in cls.param_names if k in params}, **extra)

    def copy(self):
        """A fresh model with the same parameters (own state, at rest)."""
        return type(self).from_params(
            {k: np.array(v, dtype=np.float64) for k, v in self.params.items()},
            self.dt,
            self.extra_meta(),
        )

    def __repr__(self) -> str:
        return f"{type(self).__name__}(dt={self.dt:.6g})"


def velocity_of(x: np.ndarray, dt: float) -> np.ndarray:
    """Central-difference velocity of prescribed displacement, (T, ...) -> (T, ...)."""
    if x.shape[0] < 2:
        return np.zeros_like(x)
    return np.gradient(x, dt, axis=0)


def has_preset(cls: type) -> bool:
    """Whether a model class builds itself without files (its own ``preset``)."""
    return getattr(cls.preset, "__func__", None) is not BushingModel.preset.__func__
