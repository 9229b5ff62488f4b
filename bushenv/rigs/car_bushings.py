"""The quarter car's bushing models, whatever their number of coordinates C: one model per
axis (``model``, ``reference``: radial and axial, C = 1 each) or one over the arm's three
coordinates (``arm_bushing``, ``arm_bushing_reference``: axial, radial and the arm's rotation,
C = 3); which coordinates each carries (``carried``) and the rotation's split inside the
sub-steps (``rotation_split``). ``car.CarParameters`` resolves them with these; the pymunk car
(``car.CarPair``) and the array integrator (``quartercar_batch``) step them alike.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from bushenv.models import BushingModel
from bushenv.rigs.car_verdict import CAR
from bushenv.rigs.common import (
    RigError,
    model_label,
    resolve_model,
    resolve_reference,
)

AXES = ("radial", "axial")  # radial: vertical at the arm's inner end; axial: along the arm
# What the arm's bushing can carry, in a three-coordinate model's order: the arm's inner end
# along the arm and vertically, and the arm's angle relative to the chassis.
ARM_COORDS = ("axial", "radial", "rotation")
ROTATION_K_IN_FLOOR = 1e-3  # N m/rad: a rotary spring needs a stiffness; this one is nil


def axis_models(
    spec: Any, dt: float, reference: bool, trust_reference: bool = False
) -> dict[str, BushingModel]:
    """One model per bushing axis: a name or path (the same for both axes, each axis' own
    preset or file), or a dict ``{"radial": ..., "axial": ...}`` of names, paths or objects.
    References go through the one judging setup (vetted, ``rigs.common.resolve_reference``)."""

    def resolve(s: Any, axis: str, dt: float) -> BushingModel:
        if reference:
            return resolve_reference(s, axis, dt, trust_reference=trust_reference, where=CAR)
        return resolve_model(s, axis, dt)

    if isinstance(spec, dict):
        missing = [a for a in AXES if a not in spec]
        if missing or set(spec) - set(AXES):
            raise RigError(f"a per-axis model needs exactly the keys {AXES}, got {sorted(spec)}")
        return {a: resolve(spec[a], a, dt) for a in AXES}
    if isinstance(spec, BushingModel):
        raise RigError(
            "a model object is for one axis; pass {'radial': obj_r, 'axial': obj_a} instead"
        )
    return {a: resolve(spec, a, dt) for a in AXES}


def carried(key: str, model: BushingModel) -> tuple[int, ...]:
    """Which of ``ARM_COORDS`` the car's bushing model ``key`` carries: all of them for a model
    over them (``arm_bushing``), else the one coordinate its key names (``radial``,
    ``axial``)."""
    if model.n_coords == len(ARM_COORDS):
        return tuple(range(len(ARM_COORDS)))
    if model.n_coords != 1 or key not in ARM_COORDS:
        raise RigError(
            f"{CAR.name}: bushing {key!r} has {model.n_coords} coordinates "
            f"({', '.join(model.coords)}); the arm takes one per axis or {len(ARM_COORDS)} "
            f"({', '.join(ARM_COORDS)}, arm_bushing=...)"
        )
    return (ARM_COORDS.index(key),)


def rotation_split(model: BushingModel) -> tuple[float, float]:
    """(k_in N m/rad, c_in N m s/rad) of an arm bushing's rotation inside the sub-steps: what
    the model states (a linear model's K_tt, C_tt; a hybrid's backbone), else the linear
    torsion preset's (52.0 N m/rad: the arm turns its pivot's bush about the bush's axis, as
    in HalfCar-v0). Matching the model makes
    its held remainder small: a linear model's is exactly zero, as in the one-axis split.
    Held explicitly, even 3000 N m/rad on the arm (about 1.1 kg m^2 about its centre of mass)
    is omega dt = 0.26: the rotation is not where the coupling trap lies; accuracy is."""
    from bushenv.models.planar_linear import PlanarLinear

    k = getattr(model, "k_matrix", None)
    if k is None:
        lin = PlanarLinear.preset(dt=model.dt, rotation="torsion")
        return float(lin.k_matrix[2, 2]), float(lin.c_matrix[2, 2])
    return max(float(k[2, 2]), ROTATION_K_IN_FLOOR), max(float(model.c_matrix[2, 2]), 0.0)


def arm_models(p, kwargs: dict[str, Any]) -> None:
    """Set ``p.models``, ``p.references`` ({"arm": model over ``ARM_COORDS``}), their labels
    and ``p.rotation_in`` (role -> rotation split) from ``arm_bushing`` and
    ``arm_bushing_reference``."""
    from bushenv.rigs.common import resolve_model

    arm = resolve_model(p.arm_bushing, dt=p.dt, coords=3, what="arm_bushing", env_id=CAR.name)
    twin_spec = kwargs.get("arm_bushing_reference", "rubber-torsion")
    twin = resolve_model(
        twin_spec, dt=p.dt, coords=3, what="arm_bushing_reference", env_id=CAR.name
    )
    p.models, p.references = {"arm": arm}, {"arm": twin}
    p.rotation_in = {"model": rotation_split(arm), "reference": rotation_split(twin)}
    label = p.arm_bushing if isinstance(p.arm_bushing, str | Path) else arm.name
    p.model_name = f"planar {Path(str(label)).name}"
    twin_label = twin_spec if isinstance(twin_spec, str | Path) else twin.name
    p.reference_name = f"planar {Path(str(twin_label)).name}"


def axis_label(models: dict[str, BushingModel], spec: Any) -> str:
    if isinstance(spec, str | os.PathLike):
        return model_label(models["radial"], spec)
    return "/".join(models[a].name for a in AXES)
