"""The bushing test rig's arguments over C coordinates, checked once for the single env and the
vector env (``bushrig.BushRigEnv``, ``vector.BushRigVectorEnv``).

One env serves every BushRig id; C is read from the spec's limits. BushRig-v0 names its one
coordinate with ``axis`` (axial or radial) and gives plain numbers (``max_displacement_m``,
``max_velocity_m_per_s``, ``force_limit_n``; ``force_scale_n`` a table by axis); BushRig3-v0
gives tables by coordinate (``stroke``, ``rate``, ``force_limit``, ``force_scale``: axial m,
radial m, rotation rad). Either way every limit becomes a (C,) array in the coordinates' order
(``coords``), and the step, the observation, the reward and the episode's end are the same
arithmetic over them.

The reference. Over one coordinate it judges through the one judging setup
(``common.resolve_reference``: vetted before it judges, ``trust_reference`` to judge with one
that failed); over C coordinates ``"default"`` is the built-in coupled rubber beside a
registered model and none beside a user's model (a warning says so), ``"none"`` none (the
reward is then the model's own force over ``force_scale``, and only a force that is not finite
or beyond ``force_limit`` ends an episode), and a ``force_scale`` left at the spec's with a
user's reference is that bushing's static stiffness times the stroke per coordinate.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from bushenv.models import MODELS, BushingModel
from bushenv.rigs.actions import check_profile, numeric_profile
from bushenv.rigs.common import (
    RigError,
    model_label,
    per_axis,
    positive,
    positive_int,
    resolve_model,
    resolve_reference,
)
from bushenv.rigs.specs import load_spec, spec_kwargs

ENV_ID = "BushRig-v0"
ENV_IDS = ("BushRig-v0", "BushRig3-v0")  # the specs of this env, the first the default
AXES = ("axial", "radial")  # BushRig-v0's axis
MAX_HISTORY = 10_000  # samples per channel in the observation (3 C x 10 000 float32)
TABLES = ("stroke", "rate", "force_limit", "force_scale")  # per coordinate, over C > 1


def spec_id(overrides: dict[str, Any]) -> str:
    """The spec ``overrides`` are for: the first of ``ENV_IDS`` whose ``[kwargs]`` name every
    key (``gym.make`` passes every key of its spec), else ``ENV_ID`` (whose check then names
    the unknown key)."""
    for env_id in ENV_IDS:
        if set(overrides) <= set(load_spec(env_id)["kwargs"]):
            return env_id
    return ENV_ID


def coordinates(kwargs: dict[str, Any], env_id: str) -> tuple[str, ...]:
    """The coordinates a spec's kwargs describe: ``axis`` alone, or the keys of its tables."""
    if "axis" in kwargs:
        if kwargs["axis"] not in AXES:
            raise RigError(f"{env_id}: axis must be one of {AXES}, got {kwargs['axis']!r}")
        return (kwargs["axis"],)
    coords = tuple(load_spec(env_id)["kwargs"]["stroke"])
    for name in TABLES:
        table = kwargs[name]
        if not isinstance(table, dict) or sorted(table) != sorted(coords):
            raise RigError(
                f"{env_id}: {name} must be a table with keys {list(coords)}, got {table!r}"
            )
    return coords


def per_coordinate(kwargs: dict[str, Any], coords: tuple[str, ...], name: str) -> np.ndarray:
    """Table ``name`` as a (C,) array in the order of ``coords``, each a positive number."""
    return np.array([positive(f"{name}.{c}", kwargs[name][c]) for c in coords])


def registered(spec: Any) -> bool:
    return isinstance(spec, str) and spec in MODELS


def is_none(spec: Any) -> bool:
    return spec is None or (isinstance(spec, str) and spec.strip().lower() == "none")


def reference_of(model_spec: Any, reference_spec: Any, env_id: str) -> Any:
    """The reference a rig over several coordinates runs: ``"default"`` is the built-in coupled
    rubber beside a registered model and none beside a user's model (a file or an object),
    said as a warning; anything else as given."""
    if not (isinstance(reference_spec, str) and reference_spec == "default"):
        return reference_spec
    if registered(model_spec):
        return "rubber"
    gym.logger.warn(
        f"{env_id}: model {model_spec if isinstance(model_spec, str | Path) else 'object'} is "
        "your own bushing's and no reference was given, so the rig runs without one: the "
        "reward is the model's own force over force_scale and only a force that is not finite "
        "or beyond force_limit ends an episode; give reference=FILE (your bushing's reference "
        "model) to judge the model against it, or reference='rubber' for the built-in one"
    )
    return "none"


def scale_of(given: np.ndarray, builtin: np.ndarray, judge: BushingModel, stroke, env_id: str):
    """force_scale per coordinate: as given, or, where it is the spec's (the built-in rubber's
    Table-1 stiffness x stroke) and the judge is a user's bushing, that bushing's own static
    stiffness x the stroke."""
    if not np.array_equal(given, builtin):
        return given
    from bushenv.identify.static_estimate import coordinate_stiffness

    k = np.abs(coordinate_stiffness(judge))
    if not np.all(np.isfinite(k) & (k > 0)):
        units = zip(judge.coords, judge.force_units, strict=True)
        table = ", ".join(f"'{c}': {u}" for c, u in units)
        raise RigError(
            f"{env_id}: the static stiffness of {judge.name} per coordinate is {k.tolist()} "
            f"(not finite or zero), so no force scale can be drawn from it: give "
            f"force_scale={{{table}}}"
        )
    return k * stroke


class RigParameters:
    """The spec's kwargs checked and converted, the models resolved; shared by the single and
    the vector env. Limits are (C,) arrays in the order of ``coords``."""

    def __init__(self, kwargs: dict[str, Any], env_id: str = ENV_ID) -> None:
        self.env_id = env_id
        self.coords = coordinates(kwargs, env_id)
        one = len(self.coords) == 1
        self.axis = self.coords[0]  # the coordinate a render draws
        self.dt = positive("dt_s", kwargs["dt_s"])
        self.substeps = positive_int("physics_substeps", kwargs.get("physics_substeps", 1))
        self.history = positive_int("history", kwargs["history"])
        if self.history > MAX_HISTORY:
            raise RigError(
                f"history must be at most {MAX_HISTORY} samples, got {self.history} (the "
                f"observation holds 3 x history values per coordinate)"
            )
        if one:
            given = ("max_displacement_m", "max_velocity_m_per_s", "force_limit_n")
            self.max_x, self.max_v, self.force_limit = (
                np.array([positive(name, kwargs[name])]) for name in given
            )
        else:
            self.max_x = per_coordinate(kwargs, self.coords, "stroke")
            self.max_v = per_coordinate(kwargs, self.coords, "rate")
            self.force_limit = per_coordinate(kwargs, self.coords, "force_limit")
        self.reward_cap = positive("reward_cap", kwargs["reward_cap"])
        self.max_step = self.max_v * self.dt  # largest change of each coordinate per step
        (self.model, self.reference, self.reference_spec, self.judge, self.force_scale) = (
            self._models(kwargs, one)
        )
        self.model_name = model_label(self.model, kwargs["model"])
        self.reference_name = (
            "none" if self.reference is None else model_label(self.reference, self.reference_spec)
        )

    def _models(self, kwargs: dict[str, Any], one: bool) -> tuple:
        """(model, reference (None: judged without one), the reference's spec, what judged,
        the force scale)."""
        c, dt, env_id = len(self.coords), self.dt, self.env_id
        model = resolve_model(
            kwargs["model"], self.axis, dt, coords=c, env_id=env_id, rate_setting="dt_s"
        )
        if one:  # one coordinate: the one judging setup, vetted
            reference = resolve_reference(
                kwargs["reference"], self.axis, dt,
                trust_reference=bool(kwargs.get("trust_reference", False)),
            )  # fmt: skip
            scale = per_axis("force_scale_n", kwargs["force_scale_n"], self.axis)
            return model, reference, kwargs["reference"], reference.judge, np.array([scale])
        spec = reference_of(kwargs["model"], kwargs["reference"], env_id)
        reference = None
        if not is_none(spec):
            reference = resolve_model(
                spec, self.axis, dt, coords=c, what="reference", env_id=env_id,
                rate_setting="dt_s",
            )  # fmt: skip
        given = per_coordinate(kwargs, self.coords, "force_scale")
        builtin = per_coordinate(spec_kwargs(env_id, {}), self.coords, "force_scale")
        if (reference is not None and registered(spec)) or (
            reference is None and registered(kwargs["model"])
        ):
            return model, reference, spec, None, given
        judge = model if reference is None else reference
        return model, reference, spec, None, scale_of(given, builtin, judge, self.max_x, env_id)

    @property
    def n_coords(self) -> int:
        return len(self.coords)

    def spaces(self) -> tuple[spaces.Box, spaces.Box]:
        c = self.n_coords
        action = spaces.Box(-1.0, 1.0, shape=(c,), dtype=np.float32)
        observation = spaces.Box(-1.0, 1.0, shape=(3 * c * self.history,), dtype=np.float32)
        return action, observation

    def metadata(self, metadata: dict[str, Any]) -> dict[str, Any]:
        """``metadata`` with ``render_fps`` = 1 / dt: one frame per step shows real time."""
        return {**metadata, "render_fps": 1.0 / self.dt}

    def info_keys(self) -> dict[str, tuple[str, ...]]:
        """The info keys of each per-coordinate quantity: one coordinate keeps the plain names
        (``displacement_m``, ``force_model_n``, ...), several name theirs (``q_axial``,
        ``force_model_rotation``, ...; values in the coordinate's unit)."""
        if self.n_coords == 1:
            names = ("displacement_m", "velocity_m_per_s", "force_model_n", "force_reference_n")
            return {k: (n,) for k, n in zip(("q", "v", "f_m", "f_r"), names, strict=True)} | {
                "error": ("error_n",)
            }
        kinds = {"q": "q", "v": "velocity", "f_m": "force_model", "f_r": "force_reference"}
        out = {k: tuple(f"{n}_{c}" for c in self.coords) for k, n in kinds.items()}
        out["error"] = tuple(f"error_{c}" for c in self.coords)
        return out

    def check_excitation(self, profile: Any, vector: bool) -> np.ndarray:
        """A replayable profile within the stroke and rate of every coordinate, each sample (the
        rig starting at rest at 0) at most ``max_step`` from the previous one: (T,) or, for a
        vector env, (T, N) over one coordinate; (T, C) or (T, N, C) over C."""
        c = self.n_coords
        if c == 1:
            return check_excitation(profile, float(self.max_x[0]), float(self.max_step[0]))
        a = numeric_profile("excitation", profile)
        if a.ndim not in ((2, 3) if vector else (2,)) or a.shape[-1] != c:
            shapes = "(T, C) or (T, N, C)" if vector else "(T, C)"
            raise RigError(
                f"{self.env_id}: excitation must have shape {shapes} with C = {c} "
                f"({', '.join(self.coords)}), got {a.shape}"
            )
        for i, (name, unit) in enumerate(zip(self.coords, self.model.units, strict=True)):
            x, step = float(self.max_x[i]), float(self.max_step[i])
            check_profile(
                f"{name} excitation", a[..., i], f"{name} excitation",
                x, "|q| = {value:.6g} " + f"{unit} exceeds the stroke limit {x:.6g} {unit}",
                step, "a step of {value:.6g} " + f"{unit} exceeds the rate limit ({step:.6g} "
                f"{unit} per step; the rig starts at rest at 0)",
            )  # fmt: skip
        return a


def check_excitation(profile: Any, max_displacement_m: float, max_step_m: float) -> np.ndarray:
    """A replayable displacement profile of one coordinate: finite (T,) or (T, N), within the
    stroke, and each sample (the rig starting at rest at 0) at most ``max_step_m`` from the
    previous one."""
    return check_profile(
        "excitation",
        profile,
        "excitation",
        max_displacement_m,
        "|x| = {value:.6g} m exceeds the stroke limit " + f"{max_displacement_m:.6g} m",
        max_step_m,
        "a step of {value:.6g} m exceeds the velocity limit "
        + f"({max_step_m:.6g} m per step; the rig starts at rest at x = 0)",
    )
