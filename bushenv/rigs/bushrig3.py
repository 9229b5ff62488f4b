"""BushRig3-v0: the three-axis test machine driving axial, radial and rotation at once.

``BushRig3Env`` and ``BushRig3VectorEnv`` share ``Rig3Core``: one batched step of (B, 3)
arrays for both, so N single envs and one vector env of N columns give the same numbers, and
the episode's end is decided by ``divergence.force_termination`` per coordinate.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from bushenv.divergence import force_termination
from bushenv.errors import BadInput, ModelRaised
from bushenv.models import MODELS, BushingModel, ModelError, get_model, names_for
from bushenv.models.base import DT_TOLERANCE
from bushenv.rigs.bushrig3_kernels import rig3_motion, rig3_outcome
from bushenv.rigs.common import RigError, positive, positive_int
from bushenv.rigs.specs import spec_kwargs
from bushenv.rigs.vector_base import ArrayVectorEnv

ENV_ID = "BushRig3-v0"
COORDS = ("axial", "radial", "rotation")
MODEL_ERRORS = (BadInput, ModelRaised, ArithmeticError)


def resolve_planar(
    value: Any, dt: float, what: str, env_id: str = ENV_ID, rate_setting: str = ""
) -> BushingModel:
    """A three-axis model from a registered name (its ``preset``), an ``.npz`` file or an
    object; errors name ``env_id`` and the argument ``what``; a file at another rate names
    ``rate_setting`` (the caller's argument that sets the step) with the value to give."""
    wanted = f"{env_id}'s {what}"
    if isinstance(value, BushingModel) or (isinstance(value, str) and value in MODELS):
        options = MODELS[value].reference_preset if isinstance(value, str) else None
        try:
            model = get_model(value, dt=dt, preset=options, coords=3, wanted_by=wanted)
        except ModelError as exc:
            raise RigError(f"{env_id}: {what}: {exc}") from None
        return model
    if isinstance(value, str | Path) and str(value).endswith(".npz"):
        try:
            own = get_model(str(value), coords=3, wanted_by=wanted)
        except ModelError as exc:
            raise RigError(f"{env_id}: {what}: {exc}") from None
        if abs(own.dt - dt) > DT_TOLERANCE * dt:  # a fit at its records' rate: say what to set
            fix = f"pass {rate_setting}={own.dt:.6g}" if rate_setting else "give both one rate"
            raise RigError(
                f"{env_id}: {what} {value}: model sampled at {1 / own.dt:.6g} Hz, "
                f"expected {1 / dt:.6g} Hz (dt={dt:.6g} s): {fix}"
            )
        return own
    raise RigError(
        f"{env_id}: {what} {value!r}: {MODELS.unknown_message(value)} (three-axis: "
        f"{', '.join(names_for(3))}), or a three-axis .npz model file"
    )


def _per_coord(name: str, table: Any) -> np.ndarray:
    if not isinstance(table, dict) or sorted(table) != sorted(COORDS):
        raise RigError(f"{ENV_ID}: {name} must be a table with keys {list(COORDS)}, got {table!r}")
    return np.array([positive(f"{name}.{c}", table[c]) for c in COORDS])


def _registered(spec: Any) -> bool:
    return isinstance(spec, str) and spec in MODELS


def _is_none(spec: Any) -> bool:
    return spec is None or (isinstance(spec, str) and spec.strip().lower() == "none")


def reference_of(model_spec: Any, reference_spec: Any) -> Any:
    """The reference a rig runs: ``"default"`` is the built-in coupled rubber beside a
    registered model and none beside a user's model (a file or an object), said as a warning;
    anything else as given."""
    if not (isinstance(reference_spec, str) and reference_spec == "default"):
        return reference_spec
    if _registered(model_spec):
        return "rubber"
    gym.logger.warn(
        f"{ENV_ID}: model {model_spec if isinstance(model_spec, str | Path) else 'object'} is "
        "your own bushing's and no reference was given, so the rig runs without one: the "
        "reward is the model's own force over force_scale and only a force that is not finite "
        "or beyond force_limit ends an episode; give reference=FILE (your bushing's reference "
        "model) to judge the model against it, or reference='rubber' for the built-in one"
    )
    return "none"


def scale_of(kwargs: dict[str, Any], judge: BushingModel, limit: np.ndarray) -> np.ndarray:
    """force_scale per coordinate: as given, or, where it is the spec's (the built-in rubber's
    Table-1 stiffness x stroke) and the judge is a user's bushing, that bushing's own static
    stiffness x the stroke."""
    given = _per_coord("force_scale", kwargs["force_scale"])
    builtin = _per_coord("force_scale", spec_kwargs(ENV_ID, {})["force_scale"])
    if not np.array_equal(given, builtin):
        return given
    from bushenv.planar.static_estimate import static_stiffness3

    k = np.abs(static_stiffness3(judge))
    if not np.all(np.isfinite(k) & (k > 0)):
        raise RigError(
            f"{ENV_ID}: the static stiffness of {judge.name} per coordinate is {k.tolist()} "
            "(not finite or zero), so no force scale can be drawn from it: give force_scale="
            "{'axial': N, 'radial': N, 'rotation': N m}"
        )
    return k * limit


class Rig3Core:
    """The spec's kwargs checked, the two models (the reference may be none), the step."""

    def __init__(self, kwargs: dict[str, Any], batch: int) -> None:
        self.dt = positive("dt_s", kwargs["dt_s"])
        self.history = positive_int("history", kwargs["history"])
        self.limit = _per_coord("stroke", kwargs["stroke"])
        self.rate = _per_coord("rate", kwargs["rate"])
        self._rate_dt = self.rate * self.dt
        self.force_limit = _per_coord("force_limit", kwargs["force_limit"])
        self.reward_cap = positive("reward_cap", kwargs["reward_cap"])
        self.model = resolve_planar(kwargs["model"], self.dt, "model", rate_setting="dt_s")
        reference = reference_of(kwargs["model"], kwargs["reference"])
        self.reference: BushingModel | None = (
            None
            if _is_none(reference)
            else resolve_planar(reference, self.dt, "reference", rate_setting="dt_s")
        )
        builtin = self.reference is not None and _registered(reference)
        judge = self.model if self.reference is None else self.reference
        self.force_scale = (
            _per_coord("force_scale", kwargs["force_scale"])
            if builtin or (self.reference is None and _registered(kwargs["model"]))
            else scale_of(kwargs, judge, self.limit)
        )
        self.batch = batch
        self.q = np.zeros((batch, 3))
        self.obs = np.zeros((batch, 3, 3, self.history), dtype=np.float32)
        # (1, B, 3) buffers the models' _advance runs on: the step skips the checks of
        # BushingModel.step (shapes are right by construction), a third of its cost
        self._q1, self._v1 = np.zeros((1, batch, 3)), np.zeros((1, batch, 3))
        self._fm1, self._fr1 = np.zeros((1, batch, 3)), np.zeros((1, batch, 3))
        self.model.reset(batch)
        if self.reference is not None:
            self.reference.reset(batch)

    def reset(self, mask: np.ndarray) -> None:
        for m in (self.model, self.reference):
            if m is not None:
                m.reset_columns(mask)  # a hybrid-bw's backbone too
        self.q[mask] = 0.0
        self.obs[mask] = 0.0

    def step(self, action: np.ndarray) -> dict[str, np.ndarray]:
        """action (B, 3) in [-1, 1] (NaN as 0) -> the step's arrays."""
        a = np.ascontiguousarray(action, dtype=np.float64)
        rig3_motion(a, self.q, self._rate_dt, self.limit, self.dt, self._q1, self._v1)
        try:
            self.model._guarded(self._q1, self._v1, self._fm1)
            f_model, raised = self._fm1[0], ""
        except MODEL_ERRORS as exc:
            f_model, raised = np.full((self.batch, 3), np.nan), str(exc)
        if self.reference is not None:
            self.reference._guarded(self._q1, self._v1, self._fr1)
        f_ref = self._fr1[0]  # stays zero without a reference: the reward is |F_model|
        reward = np.empty(self.batch)
        calm = rig3_outcome(
            self.q, f_model, f_ref, self.limit, self.force_limit, self.force_scale,
            self.reward_cap, self.obs, reward,
        )  # fmt: skip
        if calm:  # all finite and within every limit: force_termination cannot fire
            terminated = truncated = np.zeros(self.batch, dtype=bool)
        else:
            non_finite, model_over, ref_over = force_termination(f_model, f_ref, self.force_limit)
            terminated = non_finite.any(axis=1) | model_over.any(axis=1)
            truncated = ref_over.any(axis=1)
        return {
            "q": self.q.copy(),
            "v": self._v1[0].copy(),
            "f_model": f_model.copy(),
            "f_ref": None if self.reference is None else f_ref.copy(),
            "reward": reward,
            "terminated": terminated,
            "truncated": truncated,
            "raised": raised,
        }

    def spaces(self) -> tuple[spaces.Box, spaces.Box]:
        return (
            spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32),
            spaces.Box(-1.0, 1.0, shape=(9 * self.history,), dtype=np.float32),
        )


_INFO_KEYS = tuple(
    f"{kind}_{c}" for kind in ("q", "force_model", "force_reference") for c in COORDS
)


def _info(s: dict[str, Any], i: int, t: int, dt: float) -> dict[str, Any]:
    # tolist(): one call for three Python floats (float() per element costs 3x the step's
    # model time at B = 1); without a reference its forces are not in the info at all
    values = s["q"][i].tolist() + s["f_model"][i].tolist()
    if s["f_ref"] is not None:
        values += s["f_ref"][i].tolist()
    return {
        "time_s": t * dt,
        "step": t,
        **dict(zip(_INFO_KEYS, values, strict=False)),
        "diverged": bool(s["terminated"][i]),
        "machine_limit": bool(s["truncated"][i]),
        "model_error": s["raised"],
    }


class BushRig3Env(gym.Env):
    """
    ## Description
    The 3-axis elastomer tester (seed 000 §4.1, Fig. 8; seed 002 Table 1) in the bushing's
    plane: it drives axial and radial translation and the in-plane rotation at once, under
    displacement control (the motion is prescribed; no force feeds back into it). The planar
    model under test (``model``) and the planar reference (``reference``, the coupled rubber of
    ``bushenv.reference.planar`` without load-cell noise) see the same motion side by side.

    ## Action Space
    ``Box(-1, 1, (3,), float32)``: per coordinate the change of the commanded position as a
    fraction of the machine's rate limit, q_k = clip(q_{k-1} + a rate dt, -stroke, stroke).
    NaN counts as 0, beyond +-1 as +-1.

    ## Observation Space
    ``Box(-1, 1, (9 H,), float32)``, H = ``history``: q / stroke (3 x H), F_model / force_limit
    (3 x H), F_reference / force_limit (3 x H), newest first, clipped, NaN as 0.

    ## Rewards
    min(sum_i |F_model,i - F_ref,i| / force_scale_i, reward_cap); without a reference F_ref is
    0 (the model's own force: the search then looks for non-finite forces and forces beyond
    the limit, the verdicts that need no reference).

    ## Starting State
    At rest, both models reset; nothing is random.

    ## Episode End
    Terminated: the model's force is not finite, it raised, or it exceeds a force limit while
    the reference stays within (``divergence.force_termination`` per coordinate). Truncated:
    the reference exceeds a limit (the motion cannot run on the machine), or the spec's
    ``max_episode_steps`` (2048 = 10 s).

    ## Arguments
    Every key of ``envs/BushRig3-v0.toml`` ``[kwargs]``: ``model`` (a name in
    ``bushenv.models.MODELS`` whose three-axis form has a preset, a three-axis ``.npz`` model
    file, or a model) and ``reference`` (the same, ``"none"``, or ``"default"``: the built-in
    coupled rubber beside a registered model, none beside a user's model, with a warning
    saying so), ``dt_s``, ``history``, ``stroke``, ``rate``, ``force_limit``, ``force_scale``
    (left at the spec's values with a user's reference: that bushing's static stiffness x the
    stroke per coordinate), ``reward_cap``.

    ## Example
    >>> import gymnasium as gym
    >>> import numpy as np
    >>> import bushenv
    >>> env = gym.make("BushRig3-v0", model="linear")
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape
    (36,)
    >>> obs, reward, terminated, truncated, info = env.step(np.array([1, 0, -1], np.float32))
    >>> round(info["q_axial"] * 1e3, 3), round(info["q_rotation"], 4)
    (6.136, -0.0736)

    ## Version History
    - v0: first version. The reference ``"default"`` (none beside a user's model file, said)
      and ``"none"``, and the force scale of a user's reference, came later without a new id:
      with the built-in models nothing changed.
    """

    metadata = {"render_modes": [], "render_fps": 204.8}

    def __init__(self, **spec_overrides: Any) -> None:
        self.core = Rig3Core(spec_kwargs(ENV_ID, spec_overrides), 1)
        self.metadata = {**type(self).metadata, "render_fps": 1.0 / self.core.dt}
        self.action_space, self.observation_space = self.core.spaces()
        self._t = 0

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.core.reset(np.ones(1, dtype=bool))
        self._t = 0
        return self.core.obs[0].reshape(-1).copy(), {"time_s": 0.0, "step": 0}

    def step(self, action):
        a = np.asarray(action, dtype=np.float64)
        if a.shape != (3,):
            raise RigError(
                f"{ENV_ID}: action must have shape (3,) ({', '.join(COORDS)}), got {a.shape}"
            )
        s = self.core.step(a[None, :])
        self._t += 1
        return (
            self.core.obs[0].reshape(-1).copy(),
            float(s["reward"][0]),
            bool(s["terminated"][0]),
            bool(s["truncated"][0]),
            _info(s, 0, self._t, self.core.dt),
        )


class BushRig3VectorEnv(ArrayVectorEnv):
    """N rigs as arrays (next-step autoreset by default), the same ``Rig3Core`` step."""

    def __init__(
        self,
        num_envs: int = 1,
        max_episode_steps: int | None = None,
        episode_steps: int | None = None,
        autoreset_mode: Any = "NextStep",
        render_mode: str | None = None,
        **spec_overrides: Any,
    ) -> None:
        super().__init__(
            ENV_ID, num_envs, max_episode_steps, episode_steps, autoreset_mode, render_mode
        )
        self.core = Rig3Core(spec_kwargs(ENV_ID, spec_overrides), self.num_envs)
        self.reward_fn = self.divergence_monitor = None
        self.render_mode = render_mode
        self.single_action_space, self.single_observation_space = self.core.spaces()
        n = self.num_envs
        self.action_space = gym.vector.utils.batch_space(self.single_action_space, n)
        self.observation_space = gym.vector.utils.batch_space(self.single_observation_space, n)

    def _reset_columns(self, mask: np.ndarray) -> None:
        self.core.reset(mask)

    def _rest_info(self) -> dict[str, Any]:
        return {"time_s": 0.0, "step": 0}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        everyone = np.ones(self.num_envs, dtype=bool)
        self.core.reset(everyone)
        self._t[:] = 0
        self._prev_done[:] = False
        return self._obs(), self._masks(
            {"time_s": np.zeros(self.num_envs), "step": np.zeros(self.num_envs, np.int64)}
        )

    def _obs(self) -> np.ndarray:
        return self.core.obs.reshape(self.num_envs, -1).copy()

    def step(self, actions):
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != (self.num_envs, 3):
            raise RigError(f"{ENV_ID}: actions must have shape ({self.num_envs}, 3), got {a.shape}")
        waiting = self._prev_done.copy()
        a[waiting] = 0.0
        s = self.core.step(a)
        self._t += 1
        info = {"time_s": self._t * self.core.dt, "step": self._t.copy()}
        obs = self._obs()
        reward = s["reward"].astype(np.float64)
        obs, reward, terminated, truncated, info = self._end_step(
            obs, reward, s["terminated"].copy(), s["truncated"].copy(), info
        )
        return obs, reward, terminated, truncated, self._masks(info)


def rotation_rate_limit(rotation_stroke_rad: float) -> float:
    """The rotation's rate limit by the translation's rule (see excitation.py): a sine at 80 Hz
    with a tenth of the whole angle range as amplitude, 2 pi 80 (0.1 * 2 * stroke)."""
    return 2.0 * math.pi * 80.0 * 0.2 * rotation_stroke_rad
