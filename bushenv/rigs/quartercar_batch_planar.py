"""``QuarterCarBatch``'s planar arm bushing (``arm_bushing``): one three-axis model per car
carrying the arm's axial and radial force and its moment, batched over the B cars.

The models are ``car_planar.resolve_arm``'s (the pymunk env's); at every model step each gets
(x_axial, x_radial, theta) and their rates of the arm's inner end relative to the chassis (the
chassis does not rotate, so theta is the unsprung body's angle, ``Car.bushing_rotation``). The
split is the pymunk car's: axial and radial as the one-axis car, the moment about theta with
the rotary (k_in, c_in) of ``car_planar.rotation_split`` inside the sub-steps (the compiled
kernel's rotary term) and the remainder held. A force or moment that raised, is not finite or
is beyond its limit is never applied (its car holds nothing and is judged).
"""

from __future__ import annotations

import numpy as np

from bushenv.errors import ModelRaised
from bushenv.rigs.common import MODEL_ERRORS
from bushenv.rigs.quartercar_kernels import (
    F_AXIAL,
    F_MOMENT,
    F_RADIAL,
    OM,
    TH,
    X_AXIAL,
    X_RADIAL,
)

PLANAR_KEYS = (
    "arm_rotation_rad",
    "moment_model_nm",
    "reference_arm_rotation_rad",
    "moment_reference_nm",
)


class PlanarArm:
    """The planar models of ``cars`` groups of ``n`` columns (the model cars, then their twins),
    and each column's rotary split ``rotation`` (2, cars n): k_in N m/rad, c_in N m s/rad."""

    def __init__(self, p, n: int, cars: int) -> None:
        self.p = p
        self.groups = [("model", slice(0, n), p.models["arm"])]
        if cars == 2:
            self.groups.append(("reference", slice(n, 2 * n), p.references["arm"]))
        self.rotation = np.zeros((2, cars * n))
        for role, cols, _ in self.groups:
            self.rotation[:, cols] = np.array(p.rotation_in[role])[:, None]
        self._q = np.empty((n, 3))
        self._v = np.empty((n, 3))

    def reset_columns(self, mask: np.ndarray) -> None:
        for _, _, model in self.groups:
            model.reset_columns(mask)

    def sample(self, state, motion, forces, held, raised) -> None:
        """Step every car's model at t_k: ``forces`` rows radial, axial N, the deflections m and
        the moment N m; ``held`` (3, B) the remainders radial, axial, moment (zero where they
        cannot be applied); ``raised[group]`` why a model refused ("" if it did not)."""
        p = self.p
        xr, vr, xa, va = motion
        th, om = state[TH], state[OM]
        q, v = self._q, self._v
        for group, cols, model in self.groups:
            raised[group] = ""
            q[:, 0], q[:, 1], q[:, 2] = xa[cols], xr[cols], th[cols]
            v[:, 0], v[:, 1], v[:, 2] = va[cols], vr[cols], om[cols]
            try:
                f = model.step(q, v)
            except MODEL_ERRORS as exc:  # a model refusing to go on, 1/0, overflow, ...
                f = np.full(q.shape, np.nan)
                raised[group] = f"model raised {type(exc).__name__}: {exc}"
            except ModelRaised:  # the model's own bug, already named: an error, not a verdict
                raise
            except Exception as exc:
                raise ModelRaised(f"{group} (arm)", exc) from exc
            forces[F_RADIAL, cols], forces[F_AXIAL, cols] = f[:, 1], f[:, 0]
            forces[F_MOMENT, cols] = f[:, 2]
            forces[X_RADIAL, cols], forces[X_AXIAL, cols] = xr[cols], xa[cols]
            k_th, c_th = p.rotation_in[group]
            with np.errstate(invalid="ignore", over="ignore"):
                rest = np.stack(
                    [
                        f[:, 1] - (p.k_in["radial"] * xr[cols] + p.c_in["radial"] * vr[cols]),
                        f[:, 0] - (p.k_in["axial"] * xa[cols] + p.c_in["axial"] * va[cols]),
                        f[:, 2] - (k_th * th[cols] + c_th * om[cols]),
                    ]
                )
                # as the pymunk car: all three applied, or none (the car is judged)
                ok = np.isfinite(rest).all(axis=0)
                ok &= (np.abs(f[:, :2]) <= p.force_limit).all(axis=1)
                ok &= np.abs(f[:, 2]) <= p.moment_limit
            held[:, cols] = np.where(ok, rest, 0.0)

    def summary(self, state, forces, n: int, twins: bool) -> dict[str, np.ndarray]:
        """The env's planar info keys: the arm's rotation after the step (as the pymunk env
        reports it) and the moments sampled at its start."""
        out = {
            "arm_rotation_rad": state[TH, :n].copy(),
            "moment_model_nm": forces[F_MOMENT, :n].copy(),
        }
        if twins:
            out["reference_arm_rotation_rad"] = state[TH, n:].copy()
            out["moment_reference_nm"] = forces[F_MOMENT, n:].copy()
        return out
