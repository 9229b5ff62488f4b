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
The bushing models are the pymunk car's (``car_bushings``), sampled alike whatever their
number of coordinates: one model per axis, or one per car over axial, radial and the arm's
rotation (``arm_bushing``; the chassis does not rotate, so the rotation is the unsprung body's
angle), whose moment is split the same way about theta -- a rotary spring-damper
(``car_bushings.rotation_split``) inside the sub-steps (the compiled kernel's rotary term), the
remainder held, as ``coupling.SplitRotation`` does in the pymunk car. A bushing's forces are
applied all together or not at all: where one raised, is not finite or is beyond its limit,
that bushing holds nothing and its car is judged.

Its agreement with the pymunk env is stated and tested in docs/envs.md (axis models) and
docs/planar.md (a bushing that carries the arm's rotation).

Like the env the batch can carry a twin car with the reference bushing (``with_reference``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.errors import ModelRaised
from bushenv.rigs.car import CarParameters, check_road
from bushenv.rigs.car_bushings import AXES, axis_models
from bushenv.rigs.common import (
    MODEL_ERRORS,
    RigError,
    positive_int,
    reset_columns,
    shared_state_rows,
)
from bushenv.rigs.quartercar_kernels import (  # noqa: F401  (the state rows, for the vector env)
    F_AXIAL,
    F_MOMENT,
    F_RADIAL,
    OM,
    TH,
    VY_C,
    VY_U,
    X_AXIAL,
    X_RADIAL,
    X_U,
    Y_C,
    Y_U,
    bushing_motion_kernel,
    parameter_vector,
    substeps_kernel,
)
from bushenv.rigs.specs import spec_kwargs

ENV_ID = "QuarterCar-v0"
# per ARM_COORDS (axial, radial, rotation): its force's row in a step's forces, its held row
FORCE_ROWS = (F_AXIAL, F_RADIAL, F_MOMENT)
HELD_ROWS = (1, 0, 2)
# the info keys a bushing that carries the arm's rotation adds
ROTATION_KEYS = (
    "arm_rotation_rad",
    "moment_model_nm",
    "reference_arm_rotation_rad",
    "moment_reference_nm",
)


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
        self.params = p = CarParameters(kwargs)
        self.models = p.models
        self.references = p.references if with_reference else None
        self._prm = parameter_vector(p)
        cars = 2 if with_reference else 1
        n = self.num_cars
        self.groups = [("model", slice(0, n), self.models)]
        if with_reference:
            self.groups.append(("reference", slice(n, 2 * n), self.references))
        self.rotation = p.planar  # the bushing carries the arm's rotation (a moment)
        self._rotation = np.zeros((2, cars * n))  # the rotary split; none without rotation
        self._split = {}  # car role -> (k_in, c_in) per ARM_COORDS
        for role, cols, _ in self.groups:
            self._split[role] = p.split(role)
            if self.rotation:
                self._rotation[:, cols] = np.array(self._split[role][2])[:, None]
        self._rows = 5 if self.rotation else 4  # F_RADIAL .. X_AXIAL (, F_MOMENT)
        self._shared: dict[tuple[str, str], np.ndarray] = {}
        self.raised = {"model": "", "reference": ""}
        # the cars' arrays (columns: the model cars, then their twins); reset fills them
        self.state = np.zeros((8, cars * n))
        self.road = np.zeros(cars * n)
        self.held = np.zeros((3, cars * n))
        self.active = np.ones(cars * n, dtype=bool)
        self.diverged = np.zeros(n, dtype=bool)
        self.reference_out = np.zeros(n, dtype=bool)
        self._motion = np.zeros((4, cars * n))
        self._t = 0
        self.reset()

    def reset(self) -> None:
        n = self.num_cars
        self.state[:] = 0.0
        self.state[X_U] = self.params.x_cm
        self.road[:] = 0.0
        self.held[:] = 0.0
        self.active[:] = True
        self.diverged[:] = False
        self.reference_out[:] = False
        self._motion[:] = 0.0
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
        for group, _, models in self.groups:
            for key, m in models.items():
                if (group, key) not in self._shared:  # probed once, on the first autoreset
                    self._shared[group, key] = shared_state_rows(m)
                reset_columns(m, mask, self._shared[group, key])

    def step(self, road: np.ndarray) -> dict[str, np.ndarray]:
        p, n = self.params, self.num_cars
        road = np.asarray(road, dtype=np.float64).reshape(n)
        bushing_motion_kernel(self.state, self._prm, self._motion)
        xr, vr, xa, va = self._motion
        forces = np.empty((self._rows, self.state.shape[1]))
        self._sample(forces)
        road_all = np.concatenate([road] * (2 if self.references is not None else 1))
        road_v = (road_all - self.road) / p.dt
        substeps_kernel(
            self.state, self.road, road_v, self.held, self._rotation, self.active, p.substeps,
            self._prm,
        )  # fmt: skip
        self.road[:] = road_all  # exact, as the env sets the kinematic road body
        self._t += 1
        out, wheel_y = self._summary(forces, xr, xa)
        # bounds: a car out of bounds stops; the model car's verdict counts only while its
        # twin is within bounds
        bad = self._out_of_bounds(forces, wheel_y)
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

    def _sample(self, forces: np.ndarray) -> None:
        """Every car's bushing models at t_k: their forces and the deflections into ``forces``,
        the remainders F - (k_in x + c_in v) held (zero for a bushing whose forces cannot be
        applied: all of its coordinates, or none)."""
        p = self.params
        xr, vr, xa, va = self._motion
        th, om = self.state[TH], self.state[OM]
        q, w = (xa, xr, th), (va, vr, om)
        limits = (p.force_limit, p.force_limit, p.moment_limit)
        for group, cols, models in self.groups:
            self.raised[group] = ""
            split = self._split[group]
            for key, model in models.items():
                index = p.carried[key]
                f = self._forces(group, key, model, index, [q[i][cols] for i in index],
                                 [w[i][cols] for i in index])  # fmt: skip
                with np.errstate(invalid="ignore", over="ignore"):
                    rest = [
                        f[j] - (split[i][0] * q[i][cols] + split[i][1] * w[i][cols])
                        for j, i in enumerate(index)
                    ]
                    ok = np.isfinite(rest[0])
                    for j, i in enumerate(index):
                        ok = ok & np.isfinite(rest[j]) & (np.abs(f[j]) <= limits[i])
                for j, i in enumerate(index):
                    forces[FORCE_ROWS[i], cols] = f[j]
                    self.held[HELD_ROWS[i], cols] = np.where(ok, rest[j], 0.0)
            forces[X_RADIAL, cols], forces[X_AXIAL, cols] = xr[cols], xa[cols]

    def _forces(self, group: str, key: str, model, index, x: list, v: list) -> list:
        """The forces of bushing ``key`` of the ``group`` cars, one (B,) array per coordinate
        it carries (NaN where the model refused: ``raised[group]`` says why)."""
        try:
            if len(index) == 1:
                return [np.asarray(model.step(x[0].copy(), v[0].copy()))]
            f = model.step(np.stack(x, axis=1), np.stack(v, axis=1))
            return [f[:, j] for j in range(len(index))]
        except MODEL_ERRORS as exc:  # a model refusing to go on, 1/0, overflow, ...
            self.raised[group] = f"model raised {type(exc).__name__}: {exc}"
            return [np.full(x[0].shape, np.nan)] * len(index)
        except ModelRaised:  # the model's own bug, already named: an error, not a verdict
            raise
        except Exception as exc:  # the model's own bug: an error, never a divergence
            raise ModelRaised(f"{group} ({key})", exc) from exc

    def _summary(self, forces, xr, xa) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """The step's outputs (the env's info keys) and every car's wheel height (B or 2B,)."""
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
        if self.rotation:  # the arm's rotation after the step (as the pymunk env reports
            # it) and the moments sampled at its start
            out["arm_rotation_rad"] = s[TH, :n].copy()
            out["moment_model_nm"] = forces[F_MOMENT, :n].copy()
            if self.references is not None:
                out["reference_arm_rotation_rad"] = s[TH, n:].copy()
                out["moment_reference_nm"] = forces[F_MOMENT, n:].copy()
        return out, wheel_y

    def _out_of_bounds(self, forces, wheel_y) -> np.ndarray:
        p, s = self.params, self.state
        yc, yw = s[Y_C], wheel_y
        with np.errstate(invalid="ignore"):
            bad = ~np.isfinite(forces).all(axis=0) | ~np.isfinite(s).all(axis=0)
            bad |= (np.abs(forces[0]) > p.force_limit) | (np.abs(forces[1]) > p.force_limit)
            bad |= (np.abs(forces[2]) > p.max_deflection) | (np.abs(forces[3]) > p.max_deflection)
            if self.rotation:
                bad |= np.abs(forces[F_MOMENT]) > p.moment_limit
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
