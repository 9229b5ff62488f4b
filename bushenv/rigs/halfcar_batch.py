"""HalfCarBatch: the HalfCar-v0 car for many manoeuvres at once, as arrays (searches over roads
and steering, the error-transfer map).

The car is the env's: ``halfcar_batch_layout`` reads the pymunk ``HalfCar``'s bodies, anchors,
rest lengths and element order into arrays, and ``halfcar_batch_kernels`` steps them with
chipmunk's own scheme (the kernel's docstring gives the one difference: every damper implicit
Euler at the current configuration). The coupling is the env's split: at every model step each
pivot's model gets (q, v) (axial m, radial m, rotation rad; the env's frames) of the arm's inner
end relative to the chassis and the remainder F - (k_in q + c_in v) is held over the sub-steps
(as a shifted rest length or rest angle) while k_in q + c_in v acts inside them. The bushing
models step as one batch: a model given once for all four pivots runs 4 B histories (car b,
pivot i is history 4 b + i), a table of four models B histories each.

Interface::

    batch = HalfCarBatch(B, model="linear", reference="rubber", threads=1)  # any env kwarg
    out = batch.step(road_left, road_right, lateral_accel)        # each (B,): m, m, m/s^2
    out = batch.simulate(road_left=(T,) or (T, B), road_right=..., lateral_accel=..., keys=...)

``step`` returns (B,) arrays under the env's ``info`` keys (``RESULT_KEYS``: inputs, each car's
body, wheel and geometry outputs, the twin's with ``reference_``, every pivot's forces and
deflections in both cars, ``error_n``, ``roll_error_rad``, ``diverged``, ``physical_limit``,
and ``reference_outside_range`` -- a bool here: a twin pivot beyond the rotation its law is
calibrated for, where the env says why).
``simulate`` runs whole manoeuvres from rest (checked against the env's limits, as
``reset(options=...)``) and returns (T, B) arrays of ``keys`` (default all) plus ``diverged``,
``divergence_step`` (-1 if none) and ``physical_limit`` (B,). A car that leaves its bounds stops
moving (its later samples repeat its last state); its verdict is the env's: the model car out
of bounds while its twin is not. ``threads=2`` steps the cars' physics in two threads (bit for
bit the same numbers); ``with_reference=False`` leaves the twins out. Agreement with the
pymunk env: docs/envs.md ("HalfCar-v0").
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from bushenv.errors import ModelRaised
from bushenv.rigs.common import MODEL_ERRORS, RigError, positive_int, reset_columns
from bushenv.rigs.coupling import LONG_ARM_M
from bushenv.rigs.halfcar_batch_kernels import PY, VY, bushing_motion_kernel, hold_kernel
from bushenv.rigs.halfcar_batch_lanes import lanes_kernel
from bushenv.rigs.halfcar_batch_layout import ROAD, layout
from bushenv.rigs.halfcar_batch_outputs import (
    MODEL_KEYS,
    RESULT_KEYS,
    car_outputs,
    out_of_bounds,
    result,
)
from bushenv.rigs.halfcar_inputs import replay_inputs
from bushenv.rigs.halfcar_params import ENV_ID, POSITIONS, SIDES, HalfCarParameters
from bushenv.rigs.specs import spec_kwargs

ITERATIONS = 10  # chipmunk's damper sweeps per sub-step: pymunk's default, as the env's space
MIN_THREAD_COLUMNS = 32  # a thread's fewest columns: below, a thread costs more than it saves


class HalfCarBatch:
    """B half cars and, with ``with_reference``, B twins on the reference bushings (columns:
    the model cars, then the twins). See the module docstring for the interface."""

    def __init__(
        self, num_cars: int, *, with_reference: bool = True, threads: int = 1, **spec_overrides: Any
    ):
        self.num_cars = n = positive_int("num_cars", num_cars)
        self.threads = positive_int("threads", threads)
        self._pool = None
        self.params = p = HalfCarParameters(spec_kwargs(ENV_ID, spec_overrides))
        self.groups = [("model", p.models)]
        if with_reference:
            self.groups.append(("reference", p.references))
        self.with_reference = with_reference
        cols = n * len(self.groups)
        tables = [layout(p, role) for role, _ in self.groups]
        t = self._table = tables[0]
        self._kernel = self._compiled()
        self._rest0 = np.repeat(np.stack([x.rest for x in tables]), n, axis=0).T.copy()
        self._stiff = np.repeat(np.stack([x.stiff for x in tables]), n, axis=0).T.copy()
        self._damp = np.repeat(np.stack([x.damp for x in tables]), n, axis=0).T.copy()
        self._split = np.repeat(np.stack([x.split for x in tables]), n, axis=0)  # (cols, 4, 2, 3)
        self._hold_rows = t.bushing_rows.reshape(-1)  # each pivot's axial, radial, rotary spring
        self._limits = np.array([p.force_limit, p.force_limit, p.moment_limit], dtype=np.float64)
        self._hold_base = np.array([LONG_ARM_M, LONG_ARM_M, 0.0])
        self._hold_sign = np.stack([-np.ones(len(POSITIONS)), -np.ones(len(POSITIONS)),
                                    t.pivot_sign], axis=1)  # fmt: skip
        self._state0 = np.repeat(t.state[:, :, None], cols, axis=2)
        self.state = self._state0.copy()
        self.rest = self._rest0.copy()
        self.contact = np.ones((2, cols))
        self.active = np.ones(cols, dtype=bool)
        self.diverged = np.zeros(n, dtype=bool)
        self.reference_out = np.zeros(n, dtype=bool)
        self.raised = {role: "" for role, _ in self.groups}
        # each twin pivot's calibrated rotation (rad; inf where its law states none)
        refs = (
            p.references
            if isinstance(p.references, dict)
            else dict.fromkeys(POSITIONS, p.references)
        )
        self.calibrated_rotation = np.array(
            [getattr(refs[k], "calibrated_rotation_rad", None) or np.inf for k in POSITIONS]
        )  # fmt: skip
        self._q = np.zeros((cols, 4, 3))
        self._v = np.zeros((cols, 4, 3))
        self._inputs = np.zeros((3, n))
        self._prev_v = np.zeros((2, cols))
        self._t = 0
        self.reset()

    # ----- episodes ---------------------------------------------------------------------------
    def reset(self) -> None:
        """Every car back to rest on flat roads, no lateral load; the models' histories too."""
        self.reset_columns(np.ones(self.num_cars, dtype=bool))
        self._t = 0

    def reset_columns(self, mask: np.ndarray) -> None:
        """Cars ``mask`` (B,) bool (and their twins) back to rest, their models' histories
        too; the other cars go on as they are."""
        n = self.num_cars
        mask = np.asarray(mask, dtype=bool).reshape(n)
        both = np.tile(mask, len(self.groups))
        self.state[:, :, both] = self._state0[:, :, both]
        self.rest[:, both] = self._rest0[:, both]
        self.contact[:, both] = 1.0
        self.active[both] = True
        self._prev_v[:, both] = 0.0
        self._inputs[:, mask] = 0.0
        self.diverged[mask] = False
        self.reference_out[mask] = False
        rows = np.repeat(mask, len(POSITIONS))
        for _, models in self.groups:
            if isinstance(models, dict):
                for m in models.values():
                    if mask.all():
                        m.reset(n)
                    else:
                        reset_columns(m, mask)
            elif mask.all():
                models.reset(n * len(POSITIONS))
            else:
                reset_columns(models, rows)

    # ----- one model step ---------------------------------------------------------------------
    def step(self, road_left, road_right, lateral_accel) -> dict[str, np.ndarray]:
        """One model step to the inputs (each (B,) or a scalar: m, m, m/s^2): the env's
        ``step`` for B cars. Returns (B,) arrays under ``RESULT_KEYS``."""
        return result(self, *self._step(road_left, road_right, lateral_accel))

    def _step(self, road_left, road_right, lateral_accel) -> tuple:
        """``step``'s work: the inputs (3, B), the columns' outputs, the pivots' deflections
        and forces (cols, 4, 3), for ``result``."""
        p, n = self.params, self.num_cars
        now = np.empty((3, n))
        for i, x in enumerate((road_left, road_right, lateral_accel)):
            now[i] = np.asarray(x, dtype=np.float64)  # a scalar or (B,), as broadcasting allows
        before, self._inputs = self._inputs, now
        bushing_motion_kernel(
            self.state, self._table.pivot_arm, self._table.pivot_sign,
            self._table.pivot_anchor_arm, self._table.pivot_anchor_chassis, self._q, self._v,
        )  # fmt: skip
        q, v = self._q.copy(), self._v.copy()
        forces, why = self._sample(q, v)
        g = len(self.groups)  # every column's inputs: a car's, then its twin's
        inputs = np.concatenate((now,) * g, axis=1)
        roads, ay = inputs[:2], inputs[2]
        road_v = np.concatenate(((now[:2] - before[:2]) / p.dt,) * g, axis=1)
        for k, side in enumerate(SIDES):
            self.state[VY, ROAD[side]] = road_v[k]
        gx = np.concatenate((-(before[2] + now[2]) / 2,) * g)
        self._integrate(gx, np.where(self.active, p.h, 0.0))
        for k, side in enumerate(SIDES):  # the road exactly where the step put it, at rest
            r = ROAD[side]
            self.state[PY, r] = np.where(self.active, roads[k], self.state[PY, r])
            self.state[VY, r] = 0.0
        self._t += 1
        out = car_outputs(p, self.state, self.contact, roads, road_v, self._prev_v, ay)
        bad = (why | out_of_bounds(p, out, q)) & self.active
        self.active &= ~bad
        if self.with_reference:
            self.reference_out |= bad[n:]
            self.diverged |= bad[:n] & ~self.reference_out
        else:
            self.diverged |= bad[:n]
        return now, out, q, forces

    def _integrate(self, gx: np.ndarray, h_car: np.ndarray) -> None:
        """The sub-steps of every column; with ``threads`` > 1 the columns split in as many
        ranges, each stepped in its own thread (the kernel releases the GIL)."""
        p, t = self.params, self._table
        if self._kernel is None:  # unpickled
            self._kernel = self._compiled()
        args = (
            self.state, self.rest, self._stiff, self._damp, self.contact, gx, h_car,
            int(p.substeps), t.anchors, t.m_inv, t.i_inv,
            *(float(x) for x in (p.k_t, -p.tyre_static_n, p.c_t, p.k_y, p.c_y)),
        )  # fmt: skip
        cols = self.state.shape[2]
        parts = min(self.threads, cols // MIN_THREAD_COLUMNS)
        if parts <= 1:
            self._kernel(*args, 0, cols)
            return
        if self._pool is None:
            self._pool = ThreadPoolExecutor(self.threads)
        edges = np.linspace(0, cols, parts + 1).astype(int)
        jobs = [self._pool.submit(self._kernel, *args, lo, hi)
                for lo, hi in zip(edges[:-1], edges[1:], strict=True)]  # fmt: skip
        for job in jobs:
            job.result()

    def _compiled(self):
        """The sub-step kernel compiled for this car's element table."""
        t = self._table
        return lanes_kernel(t.kind, t.ia, t.ib, t.side, t.m_inv != 0, ITERATIONS)

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "_pool": None, "_kernel": None}

    def _sample(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every car's (cols, 4, 3) pivot forces at t_k and why they cannot be applied ((cols,)
        bool: raised, not finite, beyond the limits); the others' remainders held."""
        n = self.num_cars
        forces = np.empty_like(q)
        for g, (role, models) in enumerate(self.groups):
            cols = slice(g * n, (g + 1) * n)
            self.raised[role] = ""
            try:
                if isinstance(models, dict):
                    for i, k in enumerate(POSITIONS):
                        forces[cols, i] = models[k].step(q[cols, i].copy(), v[cols, i].copy())
                else:
                    f = models.step(q[cols].reshape(-1, 3), v[cols].reshape(-1, 3))
                    forces[cols] = np.asarray(f).reshape(n, len(POSITIONS), 3)
            except MODEL_ERRORS as exc:  # a model refusing to go on, 1/0, overflow, ...
                forces[cols] = np.nan
                self.raised[role] = f"model raised {type(exc).__name__}: {exc}"
            except ModelRaised:
                raise
            except Exception as exc:  # the model's own bug: an error, never a verdict
                raise ModelRaised(f"{role} (half car pivots)", exc) from exc
        # the springs' rest lengths LONG_ARM_M - H / k_in, the rotary's rest angle s H / k_in
        # (chipmunk's own angle: the right side unmirrored), where the forces can be applied
        ok = np.empty(len(forces), dtype=bool)
        hold_kernel(forces, q, v, self._split, self._hold_base, self._hold_sign,
                    self._hold_rows, self._limits, self.rest, ok)  # fmt: skip
        return forces, ~ok

    # ----- whole manoeuvres -------------------------------------------------------------------
    def simulate(
        self, road_left=None, road_right=None, lateral_accel=None, keys=None
    ) -> dict[str, np.ndarray]:
        """Whole manoeuvres from rest: each input (T,) (every car) or (T, B), the absent ones
        zero; returns (T, B) arrays of ``keys`` (default every key ``step`` returns) plus
        ``diverged``, ``divergence_step`` and ``physical_limit`` (B,)."""
        n = self.num_cars
        given = {"road_left": road_left, "road_right": road_right, "lateral_accel": lateral_accel}
        cols = {k: np.asarray(x, dtype=np.float64) for k, x in given.items() if x is not None}
        if not cols:
            raise RigError(f"{ENV_ID}: simulate needs at least one of {list(given)}")
        for k, x in cols.items():
            if x.ndim not in (1, 2) or (x.ndim == 2 and x.shape[1] != n):
                raise RigError(f"{ENV_ID}: {k} must be (T,) or (T, {n}), got {x.shape}")
        length = {x.shape[0] for x in cols.values()}
        if len(length) > 1:
            raise RigError(f"{ENV_ID}: the inputs differ in length: {sorted(length)}")
        T = length.pop()
        full = {k: np.broadcast_to(x.reshape(T, -1), (T, n)) for k, x in cols.items()}
        for j in range(n):  # the env's limits on a replayed manoeuvre, column by column
            replay_inputs(self.params, {k: x[:, j] for k, x in full.items()})
        inputs = [full.get(k, np.zeros((T, n))) for k in given]
        known = RESULT_KEYS if self.with_reference else MODEL_KEYS
        keys = known if keys is None else tuple(keys)
        unknown = sorted(set(keys) - set(known))
        if unknown:
            raise RigError(f"{ENV_ID}: unknown output key(s) {unknown}; known: {known}")
        self.reset()
        rows = {k: np.empty((T, n)) for k in keys}
        first = np.full(n, -1)
        for t in range(T):
            out = result(self, *self._step(inputs[0][t], inputs[1][t], inputs[2][t]), keys)
            first[(first < 0) & self.diverged] = t
            for k in keys:
                rows[k][t] = out[k]
        rows["diverged"] = self.diverged.copy()
        rows["divergence_step"] = first
        rows["physical_limit"] = self.reference_out.copy()
        return rows
