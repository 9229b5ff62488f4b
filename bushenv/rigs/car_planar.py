"""QuarterCar-v0's planar arm bushing: one three-axis model carrying the control arm's axial and
radial force and its moment (``arm_bushing``; docs/planar.md).

The bushing frame is the one-axis car's (axial along the arm, radial vertical); the rotation is
the arm's angle relative to the chassis. ``car.py`` calls these when ``arm_bushing`` is set.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.rigs.car_verdict import CAR, MODEL_ERROR_PREFIX, force_reason
from bushenv.rigs.common import MODEL_ERRORS, model_error_text

ROTATION_K_IN_FLOOR = 1e-3  # N m/rad: a rotary spring needs a stiffness; this one is nil


def rotation_split(model) -> tuple[float, float]:
    """(k_in N m/rad, c_in N m s/rad) of a planar bushing's rotation inside the sub-steps: what
    the model states (a linear model's K_tt, C_tt; a hybrid's backbone), else the planar
    linear preset's (the reference's tangent at rest, 3000 N m/rad). Matching the model makes
    its held remainder small: a linear model's is exactly zero, as in the one-axis split.
    Held explicitly, even 3000 N m/rad on the arm (about 1.1 kg m^2 about its centre of mass)
    is omega dt = 0.26: the rotation is not where the coupling trap lies; accuracy is."""
    from bushenv.models.planar_linear import PlanarLinear

    k = getattr(model, "k_matrix", None)
    if k is None:
        lin = PlanarLinear.preset(dt=model.dt)
        return float(lin.k_matrix[2, 2]), float(lin.c_matrix[2, 2])
    return max(float(k[2, 2]), ROTATION_K_IN_FLOOR), max(float(model.c_matrix[2, 2]), 0.0)


def resolve_arm(p, kwargs: dict[str, Any]) -> None:
    """Set ``p.models``, ``p.references`` ({"arm": planar model}), their labels and
    ``p.rotation_in`` (role -> rotation split) from ``arm_bushing`` and
    ``arm_bushing_reference``."""
    from bushenv.rigs.bushrig3 import resolve_planar

    arm = resolve_planar(p.arm_bushing, p.dt, "arm_bushing", env_id=CAR.name)
    twin = resolve_planar(
        kwargs.get("arm_bushing_reference", "reference"), p.dt, "arm_bushing_reference",
        env_id=CAR.name,
    )  # fmt: skip
    p.models, p.references = {"arm": arm}, {"arm": twin}
    p.rotation_in = {"model": rotation_split(arm), "reference": rotation_split(twin)}
    label = p.arm_bushing if isinstance(p.arm_bushing, str | Path) else arm.name
    p.model_name = f"planar {Path(str(label)).name}"
    p.reference_name = f"planar {twin.name}"


def reference_range_reason(reference, theta: float) -> str:
    """Why the twin's arm bushing judges by extrapolation at rotation ``theta`` ("" if it does
    not): beyond the rotation its law is calibrated for (a reference's
    ``calibrated_rotation_rad``, when it states one)."""
    r = getattr(reference, "calibrated_rotation_rad", None)
    if r is not None and abs(theta) > r:
        return (
            f"the reference arm bushing's rotation {theta:+.3g} rad is beyond its calibrated "
            f"+-{r:g} rad: its forces there are an extrapolation"
        )
    return ""


def moment_reason(moment_nm: float, limit_nm: float) -> str:
    """Why a sampled bushing moment cannot be applied ("" if it can)."""
    if not math.isfinite(moment_nm):
        return f"bushing moment {moment_nm!r} N m is not finite"
    if abs(moment_nm) > limit_nm:
        return f"|bushing moment| = {abs(moment_nm):.6g} N m exceeds {limit_nm:.6g} N m"
    return ""


def sample_planar(p, car, model, motion):
    """(forces, why) of a planar arm bushing at t_k: (radial N, axial N, moment N m), judged and
    held as ``CarPair.sample`` does the one-axis forces, the moment by ``arm_moment_limit_nm``."""
    xr, vr, xa, va = motion
    theta, omega = car.bushing_rotation()
    try:
        f = model.step(np.array([xa, xr, theta]), np.array([va, vr, omega]))
        forces = (float(f[1]), float(f[0]), float(f[2]))
    except MODEL_ERRORS as exc:
        return (math.nan,) * 3, f"model raised {type(exc).__name__}: {exc}"
    except Exception as exc:
        return (math.nan,) * 3, MODEL_ERROR_PREFIX + model_error_text(exc)
    why = force_reason(*forces[:2], p.force_limit) or moment_reason(forces[2], p.moment_limit)
    if not why:
        car.radial.hold(forces[0], xr, vr)
        car.axial.hold(forces[1], xa, va)
        car.rotation.hold(forces[2], theta, omega)
    return forces, why
