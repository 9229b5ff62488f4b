"""QuarterCarBatch: the QuarterCar-v0 car for many roads at once, as (B,) arrays (road searches,
the vector env).

The same car as ``car.Car`` (parameters from ``envs/QuarterCar-v0.toml``) written as its
own small ODE in generalised coordinates q = (y_c, X, Y, theta): chassis height, the unsprung
body's centre of mass and its angle (the chassis' horizontal motion is held by its groove, so
it is not a coordinate). One compiled kernel integrates ``physics_substeps`` sub-steps of B cars
with the scheme pymunk uses -- positions first, then the explicit spring forces, then the
dampers -- except that the three dampers are solved together as implicit Euler,
(M + h sum_j c_j J_j J_j^T) qdot+ = M qdot, where pymunk makes each damper implicit Euler on
its own (``implicit_euler_damping``). The bushing coupling is the env's: at every model step the
axis models get (x, v) of the arm's inner end relative to the chassis, and the remainder
F - (k_in x + c_in v) is held over the sub-steps while k_in x + c_in v acts inside them.

Its agreement with the pymunk env is stated and tested as in docs/envs.md.

Like the env the batch can carry a twin car with the reference bushing (``with_reference``).
"""

from __future__ import annotations

import math
from typing import Any

import numba as nb
import numpy as np

from bushenv.errors import ModelRaised
from bushenv.rigs.car import AXES, CarParameters, axis_models, check_road
from bushenv.rigs.common import (
    MODEL_ERRORS,
    RigError,
    positive_int,
    reset_columns,
    shared_state_rows,
)
from bushenv.rigs.coupling import LONG_ARM_M
from bushenv.rigs.specs import spec_kwargs

ENV_ID = "QuarterCar-v0"

# parameter vector layout for the kernel
P_M_S, P_M_U, P_I_U, P_XCM, P_L, P_MOUNT, P_H, P_KS, P_CS, P_KT, P_TSTAT = range(11)
P_KR, P_CR, P_KA, P_CA, P_STEP = range(11, 16)
N_PARAMS = 16
# state rows
Y_C, X_U, Y_U, TH, VY_C, VX_U, VY_U, OM = range(8)


def parameter_vector(p: CarParameters) -> np.ndarray:
    v = np.zeros(N_PARAMS)
    v[P_M_S], v[P_M_U], v[P_I_U], v[P_XCM] = p.m_s, p.m_u, p.i_u, p.x_cm
    v[P_L], v[P_MOUNT], v[P_H] = p.L, p.mount, p.H
    v[P_KS], v[P_CS], v[P_KT], v[P_TSTAT] = p.k_s, p.c_s, p.k_t, p.tyre_static_n
    v[P_KR], v[P_CR] = p.k_in["radial"], p.c_in["radial"]
    v[P_KA], v[P_CA] = p.k_in["axial"], p.c_in["axial"]
    v[P_STEP] = p.h
    return v


@nb.njit(cache=True, nogil=True)
def bushing_motion_kernel(state, prm, out):  # pragma: no cover - compiled
    """out (4, B): x_radial, v_radial, x_axial, v_axial of the arm's inner end."""
    x_cm = prm[P_XCM]
    for b in range(state.shape[1]):
        c, s = math.cos(state[TH, b]), math.sin(state[TH, b])
        rx, ry = -x_cm * c, -x_cm * s
        om = state[OM, b]
        out[0, b] = state[Y_U, b] + ry - state[Y_C, b]
        out[1, b] = state[VY_U, b] + om * rx - state[VY_C, b]
        out[2, b] = state[X_U, b] + rx
        out[3, b] = state[VX_U, b] - om * ry


@nb.njit(cache=True, nogil=True)
def substeps_kernel(state, road, road_v, held, active, n_sub, prm):  # pragma: no cover
    """Advance B cars by n_sub sub-steps of h = prm[P_STEP]; road (B,) is updated in place."""
    h = prm[P_STEP]
    m_s, m_u, i_u, x_cm = prm[P_M_S], prm[P_M_U], prm[P_I_U], prm[P_XCM]
    L, H = prm[P_L], prm[P_H]
    a_m = prm[P_MOUNT] * L - x_cm
    a_w = L - x_cm
    k_s, c_s, k_t, lift = prm[P_KS], prm[P_CS], prm[P_KT], -prm[P_TSTAT]
    k_r, c_r, k_a, c_a = prm[P_KR], prm[P_CR], prm[P_KA], prm[P_CA]
    mass = np.empty(4)
    mass[0], mass[1], mass[2], mass[3] = m_s, m_u, m_u, i_u
    J = np.empty((3, 4))
    A = np.empty((4, 4))
    rhs = np.empty(4)
    q = np.empty(4)
    for b in range(state.shape[1]):
        if not active[b]:
            continue
        for _ in range(n_sub):
            # 1. positions (and the kinematic road) with the current velocities
            state[Y_C, b] += h * state[VY_C, b]
            state[X_U, b] += h * state[VX_U, b]
            state[Y_U, b] += h * state[VY_U, b]
            state[TH, b] += h * state[OM, b]
            road[b] += h * road_v[b]
            c, s = math.cos(state[TH, b]), math.sin(state[TH, b])
            yc, X, Y = state[Y_C, b], state[X_U, b], state[Y_U, b]
            rix, riy = -x_cm * c, -x_cm * s
            rmx, rmy = a_m * c, a_m * s
            rwx, rwy = a_w * c, a_w * s
            # 2. explicit spring forces -> generalised forces Q over (y_c, X, Y, theta)
            Q0 = 0.0
            Q1 = 0.0
            Q2 = 0.0
            Q3 = 0.0
            # bushing radial (vertical at the inner end) and axial (horizontal)
            f = -(k_r * (Y + riy - yc) + held[0, b])
            Q0 -= f
            Q2 += f
            Q3 += rix * f
            f = -(k_a * (X + rix) + held[1, b])
            Q1 += f
            Q3 -= riy * f
            # coil-over from the chassis top mount to the arm mount
            dx = X + rmx - prm[P_MOUNT] * L
            dy = Y + rmy - (yc + H)
            ell = math.sqrt(dx * dx + dy * dy)
            ux, uy = dx / ell, dy / ell
            f = -k_s * (ell - H)
            jc3 = -ux * rmy + uy * rmx
            Q0 -= uy * f
            Q1 += ux * f
            Q2 += uy * f
            Q3 += jc3 * f
            # tyre: long-arm spring from (L, road - D) to the wheel centre, unilateral
            tx = X + rwx - L
            ty = Y + rwy - road[b] + LONG_ARM_M
            dist = math.sqrt(tx * tx + ty * ty)
            f = k_t * (LONG_ARM_M - dist)
            if f < lift:
                f = lift
            nx, ny = tx / dist, ty / dist
            Q1 += nx * f
            Q2 += ny * f
            Q3 += (-nx * rwy + ny * rwx) * f
            # 3. explicit velocity update
            q[0] = state[VY_C, b] + h * Q0 / m_s
            q[1] = state[VX_U, b] + h * Q1 / m_u
            q[2] = state[VY_U, b] + h * Q2 / m_u
            q[3] = state[OM, b] + h * Q3 / i_u
            # 4. the three dampers together, implicit Euler: (M + h sum c J J^T) q+ = M q
            J[0, 0], J[0, 1], J[0, 2], J[0, 3] = -1.0, 0.0, 1.0, rix
            J[1, 0], J[1, 1], J[1, 2], J[1, 3] = 0.0, 1.0, 0.0, -riy
            J[2, 0], J[2, 1], J[2, 2], J[2, 3] = -uy, ux, uy, jc3
            for i in range(4):
                rhs[i] = mass[i] * q[i]
                for j in range(4):
                    A[i, j] = h * (
                        c_r * J[0, i] * J[0, j] + c_a * J[1, i] * J[1, j] + c_s * J[2, i] * J[2, j]
                    )
                A[i, i] += mass[i]
            # Gaussian elimination (A is symmetric positive definite, no pivoting needed)
            for k in range(4):
                for i in range(k + 1, 4):
                    r = A[i, k] / A[k, k]
                    for j in range(k, 4):
                        A[i, j] -= r * A[k, j]
                    rhs[i] -= r * rhs[k]
            for i in range(3, -1, -1):
                acc = rhs[i]
                for j in range(i + 1, 4):
                    acc -= A[i, j] * q[j]
                q[i] = acc / A[i, i]
            state[VY_C, b] = q[0]
            state[VX_U, b] = q[1]
            state[VY_U, b] = q[2]
            state[OM, b] = q[3]


class QuarterCarBatch:
    """B quarter cars (and, with ``with_reference``, B twins with the reference bushing).

    ``step(road (B,))`` advances one model step and returns a dict of (B,) arrays under the
    env's info keys; ``simulate(road (T,) or (T, B))`` runs whole roads from rest and returns
    (T, B) arrays plus ``diverged`` (B,) and ``divergence_step`` (B,) (-1 if none). A car that
    leaves its bounds stops moving (its later samples repeat the last state).
    """

    def __init__(
        self,
        num_cars: int,
        *,
        with_reference: bool = True,
        episode_steps: int | None = None,
        **spec_overrides: Any,
    ):
        self.num_cars = positive_int("num_cars", num_cars)
        if episode_steps is not None:  # taken for the callers that pass it; a road sets length
            positive_int("episode_steps", episode_steps)
        kwargs = spec_kwargs(ENV_ID, spec_overrides)
        if kwargs.get("arm_bushing", "") != "":
            raise RigError(
                f"{ENV_ID}: arm_bushing (a planar arm bushing) runs in the pymunk env only, not in "
                "this array integrator: use gym.make(...) or make_vec(..., "
                "vectorization_mode='sync')"
            )
        self.params = p = CarParameters(kwargs)
        self.models = p.models
        self.references = p.references if with_reference else None
        self._prm = parameter_vector(p)
        self._shared: dict[tuple[str, str], np.ndarray] = {}
        self.raised = {"model": "", "reference": ""}
        self.reset()

    def reset(self) -> None:
        n = self.num_cars
        cars = 2 if self.references is not None else 1
        self.state = np.zeros((8, cars * n))
        self.state[X_U] = self.params.x_cm
        self.road = np.zeros(cars * n)
        self.held = np.zeros((2, cars * n))
        self.active = np.ones(cars * n, dtype=bool)
        self.diverged = np.zeros(n, dtype=bool)
        self.reference_out = np.zeros(n, dtype=bool)
        self._motion = np.zeros((4, cars * n))
        self._t = 0
        for m in self.models.values():
            m.reset(n)
        if self.references is not None:
            for m in self.references.values():
                m.reset(n)

    def reset_columns(self, mask: np.ndarray) -> None:
        """Cars ``mask`` (B,) (and their twins) back to rest on a flat road, their models'
        histories too; the other cars are left as they are."""
        n = self.num_cars
        mask = np.asarray(mask, dtype=bool).reshape(n)
        both = np.concatenate([mask] * (self.state.shape[1] // n))
        self.state[:, both] = 0.0
        self.state[X_U, both] = self.params.x_cm
        self.road[both] = 0.0
        self.held[:, both] = 0.0
        self.active[both] = True
        self.diverged[mask] = False
        self.reference_out[mask] = False
        for group, models in (("model", self.models), ("reference", self.references)):
            for axis, m in (models or {}).items():
                if (group, axis) not in self._shared:  # probed once, on the first autoreset
                    self._shared[group, axis] = shared_state_rows(m)
                reset_columns(m, mask, self._shared[group, axis])

    def step(self, road: np.ndarray) -> dict[str, np.ndarray]:
        p, n = self.params, self.num_cars
        road = np.asarray(road, dtype=np.float64).reshape(n)
        bushing_motion_kernel(self.state, self._prm, self._motion)
        xr, vr, xa, va = self._motion
        forces = np.empty((4, self.state.shape[1]))
        groups = [("model", slice(0, n), self.models)]
        if self.references is not None:
            groups.append(("reference", slice(n, 2 * n), self.references))
        for group, cols, models in groups:
            self.raised[group] = ""
            for row, axis, x, v in ((0, "radial", xr, vr), (1, "axial", xa, va)):
                try:
                    f = np.asarray(models[axis].step(x[cols].copy(), v[cols].copy()))
                except MODEL_ERRORS as exc:  # a model refusing to go on, 1/0, overflow, ...
                    f = np.full(n, np.nan)
                    self.raised[group] = f"model raised {type(exc).__name__}: {exc}"
                except Exception as exc:  # the model's own bug: an error, never a divergence
                    raise ModelRaised(f"{group} ({axis})", exc) from exc
                forces[row, cols] = f
                forces[row + 2, cols] = x[cols]
                held = f - (p.k_in[axis] * x[cols] + p.c_in[axis] * v[cols])
                # a force beyond the limit (or not finite) is the verdict, never applied
                with np.errstate(invalid="ignore", over="ignore"):
                    ok = np.isfinite(held) & (np.abs(f) <= p.force_limit)
                self.held[row, cols] = np.where(ok, held, 0.0)
        road_all = np.concatenate([road] * (2 if self.references is not None else 1))
        road_v = (road_all - self.road) / p.dt
        substeps_kernel(
            self.state, self.road, road_v, self.held, self.active, p.substeps, self._prm
        )
        self.road[:] = road_all  # exact, as the env sets the kinematic road body
        self._t += 1
        out = self._summary(forces, xr, xa)
        # bounds: a car out of bounds stops; the model car's verdict counts only while its
        # twin is within bounds
        bad = self._out_of_bounds(forces, out)
        self.active &= ~bad
        if self.references is not None:
            self.reference_out |= bad[n:]
            newly = bad[:n] & ~self.reference_out & ~self.diverged
        else:
            newly = bad[:n] & ~self.diverged
        self.diverged |= newly
        out["diverged"] = self.diverged.copy()
        out["physical_limit"] = self.reference_out.copy()
        return out

    def _summary(self, forces, xr, xa) -> dict[str, np.ndarray]:
        n, s, p = self.num_cars, self.state, self.params
        c = np.cos(s[TH])
        wheel_y = s[Y_U] + (p.L - p.x_cm) * np.sin(s[TH])
        wheel_vy = s[VY_U] + s[OM] * (p.L - p.x_cm) * c
        out = {
            "road_height_m": self.road[:n].copy(),
            "chassis_y_m": s[Y_C, :n].copy(),
            "chassis_vy_m_per_s": s[VY_C, :n].copy(),
            "wheel_y_m": wheel_y[:n].copy(),
            "wheel_vy_m_per_s": wheel_vy[:n].copy(),
            "radial_deflection_m": xr[:n].copy(),
            "axial_deflection_m": xa[:n].copy(),
            "force_radial_model_n": forces[0, :n].copy(),
            "force_axial_model_n": forces[1, :n].copy(),
        }
        if self.references is not None:
            out.update(
                {
                    "reference_chassis_y_m": s[Y_C, n:].copy(),
                    "reference_chassis_vy_m_per_s": s[VY_C, n:].copy(),
                    "reference_wheel_y_m": wheel_y[n:].copy(),
                    "reference_wheel_vy_m_per_s": wheel_vy[n:].copy(),
                    "reference_radial_deflection_m": xr[n:].copy(),
                    "reference_axial_deflection_m": xa[n:].copy(),
                    "force_radial_reference_n": forces[0, n:].copy(),
                    "force_axial_reference_n": forces[1, n:].copy(),
                }
            )
            out["error_n"] = np.hypot(
                out["force_radial_model_n"] - out["force_radial_reference_n"],
                out["force_axial_model_n"] - out["force_axial_reference_n"],
            )
        self._wheel_y = wheel_y
        return out

    def _out_of_bounds(self, forces, out) -> np.ndarray:
        p, s = self.params, self.state
        yc, yw = s[Y_C], self._wheel_y
        with np.errstate(invalid="ignore"):
            bad = ~np.isfinite(forces).all(axis=0) | ~np.isfinite(s).all(axis=0)
            bad |= (np.abs(forces[0]) > p.force_limit) | (np.abs(forces[1]) > p.force_limit)
            bad |= (np.abs(forces[2]) > p.max_deflection) | (np.abs(forces[3]) > p.max_deflection)
            bad |= np.abs(yw - yc) > p.max_travel
            bad |= (np.abs(yc) > p.max_body) | (np.abs(yw) > p.max_body)
        return bad & self.active

    def simulate(self, road: np.ndarray) -> dict[str, np.ndarray]:
        """Whole roads from rest: (T,) (every car) or (T, B) m -> dict of (T, B) arrays."""
        p, n = self.params, self.num_cars
        h = check_road(road, p.max_road, p.max_road_step)
        if h.ndim == 1:
            h = np.repeat(h[:, None], n, axis=1)
        if h.shape[1] != n:
            raise RigError(f"road has {h.shape[1]} columns, expected num_cars={n}")
        self.reset()
        first = np.full(n, -1)
        rows: dict[str, np.ndarray] = {}
        for t in range(h.shape[0]):
            out = self.step(h[t])
            newly = out.pop("diverged") & (first < 0)
            first[newly] = t
            out.pop("physical_limit")
            for k, v in out.items():
                if k not in rows:
                    rows[k] = np.empty((h.shape[0], n))
                rows[k][t] = v
        rows["diverged"] = self.diverged.copy()
        rows["divergence_step"] = first
        rows["physical_limit"] = self.reference_out.copy()
        return rows


__all__ = ["AXES", "QuarterCarBatch", "axis_models"]
