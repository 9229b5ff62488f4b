"""Pure neural-network (NARX) bushing: a feed-forward net fed with its own past forces.

    F_t = f_offset + f_scale * net(xs_t, xs_{t-1}, ..., xs_{t-5}, ys_{t-1}, ..., ys_{t-5})
    xs  = (x - x_offset) / x_scale,     ys = (F - f_offset) / f_scale

seed 000 §4.2 (eqs. 4-6): current displacement, past five displacements and past five forces,
one hidden layer of nine tanh neurons, linear output; inputs and output scaled to [-1, 1] over
the training record. ``hidden=(10, 9)`` gives seed 001 §2.2's two hidden layers. In simulation
the past forces are the network's OWN past outputs (free run, seed 000 Fig. 6), never measured
ones; the velocity argument is ignored (the papers' network sees displacement only).

| parameter  | shape                       | meaning                                      |
|------------|-----------------------------|----------------------------------------------|
| x_offset_m, x_scale_m | ()               | displacement scaling, m                      |
| f_offset_n, f_scale_n | ()               | force scaling, N (input past forces, output) |
| w1, b1     | (H1, 1 + n_past_x + n_past_f), (H1,) | first tanh layer                     |
| w2, b2     | (H2, H1), (H2,); (0, H1), (0,) if one layer | optional second tanh layer   |
| w_out, b_out | (H_last,), ()                | linear output (scaled force)                 |

The state holds a step counter and two ring buffers (past scaled displacements, past scaled
outputs), see ``kernels.narx_kernel``. At rest every past displacement and force is zero.
``_advance`` runs kernels generated for the network's shape (``narx_kernels.py``: straight-line
code per profile, vectorised over profiles; a register-only variant for one profile), which give
the same bits as ``kernels.narx_kernel``.

Whatever the input, tanh units lie in [-1, 1], so |F| <= ``nn_bound()`` (see hybrid.py): even
this pure network cannot blow up to infinity; what it can do on unfamiliar input is wander or
oscillate anywhere inside that band.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.models.base import PAPER_DT, BushingModel, ModelError
from bushenv.models.narx_kernels import (
    COLS_MAX_BATCH,
    DTYPES,
    NarxKernels,
    NarxShape,
    column_split,
    narx_kernels,
    thread_pool,
)

N_PAST_X = 5  # seed 000 §4.2
N_PAST_F = 5
HIDDEN = (9,)  # seed 000 §4.2; seed 001 §2.2 uses (10, 9)


def _scalar(name: str, value: Any, positive: bool = False) -> float:
    a = np.asarray(value, dtype=np.float64)
    if a.shape != ():
        raise ModelError(f"parameter {name!r} must be a scalar, got shape {list(a.shape)}")
    f = float(a)
    if not np.isfinite(f) or (positive and f <= 0):
        raise ModelError(f"parameter {name!r} must be {'positive and ' * positive}finite, got {f}")
    return f


def _array(name: str, value: Any, shape: tuple[int, ...]) -> np.ndarray:
    a = np.ascontiguousarray(np.asarray(value, dtype=np.float64))
    if a.shape != shape:
        raise ModelError(f"parameter {name!r} has shape {list(a.shape)}, expected {list(shape)}")
    if not np.all(np.isfinite(a)):
        raise ModelError(f"parameter {name!r} holds NaN or inf")
    return a


class NarxBushing(BushingModel):
    """seed 000 §4.2 NARX network bushing, free-running on its own past outputs."""

    name = "nn"
    param_names = (
        "x_offset_m",
        "x_scale_m",
        "f_offset_n",
        "f_scale_n",
        "w1",
        "b1",
        "w2",
        "b2",
        "w_out",
        "b_out",
    )

    def __init__(
        self,
        x_offset_m: float,
        x_scale_m: float,
        f_offset_n: float,
        f_scale_n: float,
        w1: np.ndarray,
        b1: np.ndarray,
        w2: np.ndarray,
        b2: np.ndarray,
        w_out: np.ndarray,
        b_out: float,
        n_past_x: int = N_PAST_X,
        n_past_f: int = N_PAST_F,
        dt: float = PAPER_DT,
    ) -> None:
        self.n_past_x = int(n_past_x)
        self.n_past_f = int(n_past_f)
        if self.n_past_x < 1 or self.n_past_f < 1:
            raise ModelError(
                f"{self.name}: need at least one past displacement and one past force, "
                f"got n_past_x={n_past_x}, n_past_f={n_past_f}"
            )
        self.x_offset_m = _scalar("x_offset_m", x_offset_m)
        self.x_scale_m = _scalar("x_scale_m", x_scale_m, positive=True)
        self.f_offset_n = _scalar("f_offset_n", f_offset_n)
        self.f_scale_n = _scalar("f_scale_n", f_scale_n, positive=True)
        w1 = np.asarray(w1, dtype=np.float64)
        if w1.ndim != 2:
            raise ModelError(f"parameter 'w1' must be 2-D, got shape {list(w1.shape)}")
        h1 = w1.shape[0]
        self.w1 = _array("w1", w1, (h1, self.n_inputs))
        self.b1 = _array("b1", b1, (h1,))
        w2 = np.asarray(w2, dtype=np.float64)
        if w2.ndim != 2:
            raise ModelError(f"parameter 'w2' must be 2-D, got shape {list(w2.shape)}")
        h2 = w2.shape[0]
        self.w2 = _array("w2", w2, (h2, h1))
        self.b2 = _array("b2", b2, (h2,))
        self.w_out = _array("w_out", w_out, (h2 if h2 else h1,))
        self.b_out = _scalar("b_out", b_out)
        self._kernels: NarxKernels | None = None  # compiled for this shape on first use
        self._threads = 1  # set by simulate(threads=...) for the duration of one call
        super().__init__(dt)

    # ----- structure -----------------------------------------------------------------------
    @property
    def n_inputs(self) -> int:
        return 1 + self.n_past_x + self.n_past_f

    @property
    def hidden(self) -> tuple[int, ...]:
        return (self.w1.shape[0],) + ((self.w2.shape[0],) if self.w2.shape[0] else ())

    @property
    def n_state(self) -> int:
        return 1 + self.n_past_x + self.n_past_f

    def extra_meta(self) -> dict[str, Any]:
        return {"n_past_x": self.n_past_x, "n_past_f": self.n_past_f}

    @classmethod
    def initialised(
        cls,
        x_range_m: tuple[float, float],
        f_range_n: tuple[float, float],
        hidden: tuple[int, ...] = HIDDEN,
        n_past_x: int = N_PAST_X,
        n_past_f: int = N_PAST_F,
        seed: int = 0,
        dt: float = PAPER_DT,
        **extra: Any,
    ) -> NarxBushing:
        """A network with seeded random weights and [-1, 1] scaling over the given ranges."""
        hidden = tuple(int(h) for h in hidden)
        if len(hidden) not in (1, 2) or min(hidden) < 1:
            raise ModelError(f"{cls.name}: hidden must be one or two positive sizes, got {hidden}")
        rng = np.random.default_rng(seed)
        n_in = 1 + n_past_x + n_past_f
        w1 = rng.uniform(-1, 1, (hidden[0], n_in)) / np.sqrt(n_in)
        b1 = rng.uniform(-1, 1, hidden[0]) / np.sqrt(n_in)
        if len(hidden) == 2:
            w2 = rng.uniform(-1, 1, (hidden[1], hidden[0])) / np.sqrt(hidden[0])
            b2 = rng.uniform(-1, 1, hidden[1]) / np.sqrt(hidden[0])
        else:
            w2, b2 = np.zeros((0, hidden[0])), np.zeros(0)
        w_out = rng.uniform(-1, 1, hidden[-1]) / np.sqrt(hidden[-1])
        x_off, x_sc = scaling_of(*x_range_m)
        f_off, f_sc = scaling_of(*f_range_n)
        return cls(
            x_offset_m=x_off,
            x_scale_m=x_sc,
            f_offset_n=f_off,
            f_scale_n=f_sc,
            w1=w1,
            b1=b1,
            w2=w2,
            b2=b2,
            w_out=w_out,
            b_out=0.0,
            n_past_x=n_past_x,
            n_past_f=n_past_f,
            dt=dt,
            **extra,
        )

    # ----- protocol ------------------------------------------------------------------------
    def initial_state(self, batch_size: int) -> np.ndarray:
        s = np.zeros((self.n_state, batch_size))
        s[1 : 1 + self.n_past_x] = (0.0 - self.x_offset_m) / self.x_scale_m
        s[1 + self.n_past_x :] = self._rest_output_scaled()
        return s

    def _rest_output_scaled(self) -> float:
        """Scaled network output that stands for zero force at rest."""
        return (0.0 - self.f_offset_n) / self.f_scale_n

    def _backbone(self) -> tuple[float, float]:
        return 0.0, 0.0

    def __getstate__(self) -> dict[str, Any]:
        # Pickles and deep copies carry parameters and state, not compiled code (the kernels'
        # module exists only in processes that generated or imported it).
        return {**self.__dict__, "_kernels": None}

    def _compiled(self) -> NarxKernels:
        kern = self._kernels
        if kern is None:
            kern = self._kernels = narx_kernels(self._shape())
        return kern

    def step(self, x: float | np.ndarray, v: float | np.ndarray) -> float | np.ndarray:
        # Fast path for the common call, floats on an unbatched model (the gym environments):
        # the same arithmetic as ``_advance`` on (1, 1) arrays, without filling and reading them.
        tx, tv = type(x), type(v)
        if (
            self.batch_size == 1
            and (tx is float or tx is np.float64)
            and (tv is float or tv is np.float64)
        ):
            k, c = self._backbone()
            return (self._kernels or self._compiled()).step_one(
                float(x),  # a np.float64 costs numba's dispatcher more than a float
                float(v),
                self.state,
                *self._weights(),
                k,
                c,
            )
        return super().step(x, v)

    def simulate(
        self,
        x: np.ndarray,
        v: np.ndarray | None = None,
        threads: int = 1,
        dtype: str = "float64",
    ) -> np.ndarray:
        """``BushingModel.simulate``; ``threads`` > 1 splits the profiles of a (T, B) run over
        that many threads (opt-in: callers that already run models in parallel threads should
        not). Every profile is computed as with one thread: the same bits.

        ``dtype="float32"`` runs the network in single precision (twice the vector lanes, about
        twice the steps/s) and returns float32 forces: within 3.5e-6 of the peak force of the
        float64 run on the shipped models' random records (``free_run.*.float32_error`` in
        docs/benchmarks.md). For batched free runs (searches); ``step`` stays float64, and the
        state kept afterwards is the float32 state in float64.
        """
        if isinstance(threads, bool) or not isinstance(threads, int | np.integer) or threads < 1:
            raise ModelError(f"{self.name}: threads must be a positive integer, got {threads!r}")
        if dtype not in DTYPES:
            raise ModelError(f"{self.name}: dtype must be one of {DTYPES}, got {dtype!r}")
        self._threads = int(threads)
        try:
            if dtype == "float64":
                return super().simulate(x, v)
            x2, v2, one_d = self._profiles(x, v, np.float32)
            self.reset(x2.shape[1])
            state = self.state.astype(np.float32)
            out = np.empty_like(x2)
            self._run(narx_kernels(self._shape(), dtype), x2, v2, state, np.float32, out)
            self.state[...] = state
            return out[:, 0] if one_d else out
        finally:
            self._threads = 1

    def _shape(self) -> NarxShape:
        return NarxShape(self.n_past_x, self.n_past_f, self.w1.shape[0], self.w2.shape[0])

    def _weights(self) -> tuple:
        """Scaling and network arrays in the order every NARX kernel takes them."""
        return (
            self.x_offset_m,
            self.x_scale_m,
            self.f_offset_n,
            self.f_scale_n,
            self.w1,
            self.b1,
            self.w2,
            self.b2,
            self.w_out,
            self.b_out,
        )

    def _advance(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        self._run(self._kernels or self._compiled(), x, v, self.state, float, out)

    def _run(self, kern: NarxKernels, x, v, state, scalar, out) -> None:
        """Advance ``state`` over x, v into ``out`` with ``kern``; ``scalar`` casts the scaling
        and backbone numbers to the kernel's precision (its arrays must match)."""
        k, c = self._backbone()
        w = self._weights()
        if scalar is not float:
            w = tuple(scalar(a) if isinstance(a, float) else a.astype(scalar) for a in w)
        args = (x, v, state, *w, scalar(k), scalar(c), out)
        B = x.shape[1]
        if B <= COLS_MAX_BATCH:
            # One profile: its ring buffers live in registers (no ring indexing per sample).
            kern.run_cols(*args)
        elif self._threads > 1 and B > 8:
            # Disjoint column ranges of the same arrays; the kernels release the GIL.
            pool = thread_pool()
            jobs = [
                pool.submit(kern.run_rows, *args, lo, hi)
                for lo, hi in column_split(B, self._threads)
            ]
            for job in jobs:
                job.result()
        else:
            kern.run_rows(*args, 0, B)  # the loop over profiles is vectorised

    def nn_bound(self) -> float:
        """Largest |network force| any input can produce, N.

        The output is f_offset + f_scale * (w_out . h + b_out) with every hidden unit
        h = tanh(...) in [-1, 1], so |F_nn| <= f_scale * (sum |w_out| + |b_out|) + |f_offset|.
        """
        return self.f_scale_n * (float(np.sum(np.abs(self.w_out))) + abs(self.b_out)) + abs(
            self.f_offset_n
        )

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(hidden={self.hidden}, n_past_x={self.n_past_x}, "
            f"n_past_f={self.n_past_f}, dt={self.dt:.6g})"
        )


def scaling_of(lo: float, hi: float) -> tuple[float, float]:
    """(offset, scale) mapping [lo, hi] onto [-1, 1]: s = (value - offset) / scale."""
    lo, hi = float(lo), float(hi)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise ModelError(f"scaling range must be finite, got [{lo}, {hi}]")
    if hi <= lo:
        hi, lo = max(hi, lo), min(hi, lo)
    half = 0.5 * (hi - lo)
    if half <= 0:
        half = max(abs(hi), 1.0)
    return 0.5 * (hi + lo), half
