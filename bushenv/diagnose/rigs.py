"""Gap diagnosis at the rig level: model car vs. reference car on the same excitation.

``diagnose_rig(env_id, model, reference, train_profile, test_profiles)`` replays each profile
through ``env.reset(options={"excitation": profile})`` on ``BushRig-v0`` (displacements) or
``QuarterCar-v0`` (road heights), reads the model's and the reference's channels from ``info``
per step, and answers two questions:

- **where** the gap shows: every channel both sides offer, ranked by its held-out gap
  ``rms(model - reference) / rms(reference)`` over the TEST profiles together (``rms_ratio``,
  seed 000 eq. 8), with each channel's share of the summed squared gaps;
- **which** effect: the REFERENCE side's bushing record on one axis (deflection as
  displacement, bushing force as force) from the TRAIN profile and the TEST profiles, given to
  ``bushenv.diagnose.fit.diagnose`` (linear baseline unless ``baseline`` says otherwise).

Channels. BushRig-v0: the load-cell force (``force``). QuarterCar-v0: chassis displacement,
velocity and acceleration (the acceleration is ``np.gradient`` of the velocity: ``info`` has no
acceleration), wheel displacement and velocity, suspension travel, tyre force, radial and axial
bushing deflection, radial and axial bushing force.

The axis diagnosed: BushRig-v0's own ``axis``. QuarterCar-v0: the axis of the top-ranked
channel if it is a bushing channel (``radial_...``/``axial_...``); otherwise the axis whose
bushing-force channel has the larger gap (a body channel carries both axes' effects).

``model="identify"`` runs the reference on the TRAIN profile first and fits ``F = k x + c v``
(least squares, per axis for the quarter car) on its bushing record, so the model side is the
linear baseline a bench engineer would identify from the measured TRAIN record.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np

import bushenv  # noqa: F401  (registers the envs)
from bushenv.diagnose.fit import DiagnoseError, diagnose
from bushenv.metrics import rms_ratio
from bushenv.models.linear import LinearBushing
from bushenv.progress import Progress
from bushenv.records import Record

RIG_IDS = ("BushRig-v0", "QuarterCar-v0")
QC_AXES = ("radial", "axial")
IDENTIFY = "identify"
# below this held-out gap on every channel the model side matches the reference: nothing to
# diagnose at the rig level, whatever the reference's own record would suggest
RIG_GAP_FLOOR = 0.01

# QuarterCar-v0 channels: name -> (model car's info key, reference car's info key)
QUARTERCAR_CHANNELS: dict[str, tuple[str, str]] = {
    "chassis_y_m": ("chassis_y_m", "reference_chassis_y_m"),
    "chassis_vy_m_per_s": ("chassis_vy_m_per_s", "reference_chassis_vy_m_per_s"),
    "wheel_y_m": ("wheel_y_m", "reference_wheel_y_m"),
    "wheel_vy_m_per_s": ("wheel_vy_m_per_s", "reference_wheel_vy_m_per_s"),
    "suspension_travel_m": ("suspension_travel_m", "reference_suspension_travel_m"),
    "tyre_force_n": ("tyre_force_n", "reference_tyre_force_n"),
    "radial_deflection_m": ("radial_deflection_m", "reference_radial_deflection_m"),
    "axial_deflection_m": ("axial_deflection_m", "reference_axial_deflection_m"),
    "radial_force_n": ("force_radial_model_n", "force_radial_reference_n"),
    "axial_force_n": ("force_axial_model_n", "force_axial_reference_n"),
}
DERIVED = "chassis_acceleration_m_per_s2"  # gradient of chassis_vy_m_per_s
BUSHRIG_CHANNELS: dict[str, tuple[str, str]] = {"force": ("force_model_n", "force_reference_n")}


class RigDiagnoseError(DiagnoseError):
    """The rig or its inputs cannot be diagnosed as given; the message names the input."""


def _make(env_id: str, model: Any, reference: Any, axis: str | None, extra: dict) -> gym.Env:
    kwargs: dict[str, Any] = {**extra, "model": model, "reference": reference}
    if env_id == "BushRig-v0":
        kwargs["axis"] = axis
    return gym.make(env_id, disable_env_checker=True, **kwargs).unwrapped


def run_profile(env: gym.Env, profile: np.ndarray, name: str = "profile") -> dict[str, np.ndarray]:
    """Replay ``profile`` (T,) on ``env``; every numeric ``info`` key as a (T,) array.

    A replay that ends early (the model diverged, or the reference left the rig's limits) is
    refused: its channels would not cover the profile."""
    profile = np.asarray(profile, dtype=np.float64)
    if profile.ndim != 1:
        raise RigDiagnoseError(f"{name}: a profile must have shape (T,), got {profile.shape}")
    env.reset(options={"excitation": profile})
    rows: list[dict[str, Any]] = []
    action = np.zeros(1, np.float32)
    twin = getattr(env, "twin", None)  # QuarterCar-v0: the reference car
    for _ in range(profile.size):
        # the bushing velocities the reference car's models get this step (not in info):
        # sampled exactly as QuarterCarEnv.step samples them, before it integrates
        motion = twin.bushing_motion() if twin is not None else None
        _, _, terminated, truncated, info = env.step(action)
        if motion is not None:
            info = {**info, "reference_radial_velocity_m_per_s": motion[1],
                    "reference_axial_velocity_m_per_s": motion[3]}  # fmt: skip
        rows.append(info)
        if terminated or (truncated and len(rows) < profile.size):
            why = info.get("divergence_reason") or "the reference left the rig's limits"
            raise RigDiagnoseError(
                f"{name}: the replay ended at step {len(rows)} of {profile.size} ({why}); "
                "use a gentler profile"
            )
    keys = [k for k, v in rows[0].items() if isinstance(v, int | float) and not isinstance(v, bool)]
    return {k: np.array([r[k] for r in rows], dtype=np.float64) for k in keys}


def channel_pairs(env_id: str, run: dict[str, np.ndarray], dt: float) -> dict[str, tuple]:
    """(model side, reference side) arrays per channel of one replay."""
    table = BUSHRIG_CHANNELS if env_id == "BushRig-v0" else QUARTERCAR_CHANNELS
    out = {name: (run[m], run[r]) for name, (m, r) in table.items()}
    if env_id == "QuarterCar-v0":
        out[DERIVED] = (
            np.gradient(run["chassis_vy_m_per_s"], dt),
            np.gradient(run["reference_chassis_vy_m_per_s"], dt),
        )
    return out


def bushing_record(
    env_id: str,
    run: dict[str, np.ndarray],
    axis: str,
    dt: float,
    name: str,
    midpoint: bool = True,
) -> Record:
    """The REFERENCE side's bushing on ``axis`` as a ``Record`` (deflection, force).

    BushRig-v0 with ``midpoint``: the displacement is the midpoint of each step (see below)."""
    if env_id == "BushRig-v0":
        # the rig gives its models the velocity over the step, (x_k - x_{k-1}) / dt, centred
        # half a sample before x_k; the diagnosis differentiates the record's displacement by
        # central differences. Recording the step's midpoint displacement puts both at the same
        # instant (F_k = k y_k + (c + k dt / 2) v_k exactly for a linear bushing): see
        # docs/diagnose.md "Rig level" for what the raw x_k gives instead.
        x_end = run["displacement_m"]
        x = x_end if not midpoint else 0.5 * (x_end + np.concatenate([[0.0], x_end[:-1]]))
        f = run["force_reference_n"]
    else:
        x = run[f"reference_{axis}_deflection_m"]
        f = run[f"force_{axis}_reference_n"]
    return Record.from_arrays(x, f, dt, name=name)


def identify_linear(x: np.ndarray, v: np.ndarray, f: np.ndarray, dt: float) -> LinearBushing:
    """``F = k x + c v`` by least squares on (T,) deflection, velocity and force."""
    (k, c), *_ = np.linalg.lstsq(np.column_stack([x, v]), f, rcond=None)
    return LinearBushing(float(k), float(c), dt=dt)


def _identify_from_run(env_id: str, run: dict[str, np.ndarray], axis: str, dt: float):
    """The linear model in the rig's own velocity convention: BushRig-v0's step velocity from
    ``info``; QuarterCar-v0's bushing velocity as its models get it (``run_profile``)."""
    if env_id == "BushRig-v0":
        x = run["displacement_m"]
        return identify_linear(x, run["velocity_m_per_s"], run["force_reference_n"], dt)
    x = run[f"reference_{axis}_deflection_m"]
    v = run[f"reference_{axis}_velocity_m_per_s"]
    return identify_linear(x, v, run[f"force_{axis}_reference_n"], dt)


def _axis_of(channel: str) -> str | None:
    for a in QC_AXES:
        if channel.startswith(a + "_"):
            return a
    return None


def diagnose_rig(
    env_id: str,
    model: Any,
    reference: Any,
    train_profile: np.ndarray,
    test_profiles: Sequence[np.ndarray],
    axis: str = "axial",
    seed: int = 0,
    progress: Progress | None = None,
    test_names: Sequence[str] | None = None,
    baseline: str = "linear",
    midpoint: bool = True,
    env_kwargs: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Where the model-vs-reference gap shows on a rig, and which effect closes it.

    ``model``: anything the env's ``model=`` takes (a name, a file, a model object; for
    QuarterCar-v0 also ``{"radial": ..., "axial": ...}``), or ``"identify"`` (a linear model
    fitted on the reference's TRAIN bushing record). ``reference``: anything ``reference=``
    takes. ``axis``: the BushRig-v0 axis (ignored for QuarterCar-v0, which chooses by channel).
    ``baseline``: passed to ``diagnose``. ``midpoint`` (BushRig-v0 only): record each step's
    midpoint displacement for the diagnosis (``bushing_record``); False gives the raw x_k.
    ``env_kwargs``: further spec overrides for ``gym.make`` (e.g. ``physics_substeps``).

    Returns ``{"env_id", "channel", "force_channel", "channels", "axis", "axis_reason",
    "rig_gap", "effect", "bushing_effect", "ranking", "top_two", "gap_before", "gap_after",
    "shrink", "model", "bushing_diagnosis"}``: ``channels`` ranked by ``gap`` (largest first),
    each ``{channel, gap, share, rms_reference, rms_difference}``, ``share`` = gap^2 / sum of
    gap^2; ``channel`` the first and ``rig_gap`` its gap; ``force_channel`` the bushing-force
    channel with the largest gap; ``bushing_diagnosis`` the full ``diagnose`` result without
    its prediction arrays, ``bushing_effect`` its answer; ``effect`` the same unless the rig
    shows no gap (``rig_gap < RIG_GAP_FLOOR``, 1 %), then ``"none"`` (``shrink`` 0);
    ``ranking``, ``top_two``, ``gap_before``, ``gap_after`` copied from ``diagnose``.
    """
    say = progress or (lambda msg: None)
    names = _check_rig_args(env_id, axis, test_profiles, test_names)
    extra = dict(env_kwargs or {})
    model, model_info = _resolve_model(env_id, model, reference, axis, train_profile, extra, say)
    env = _make(env_id, model, reference, axis, extra)
    dt = float(env.params.dt)
    say(f"{env_id}: replaying TRAIN ({np.size(train_profile)} steps)")
    train_run = run_profile(env, train_profile, "TRAIN")
    test_runs = []
    for i, (profile, name) in enumerate(zip(test_profiles, names, strict=True)):
        say(f"{env_id}: replaying TEST {i + 1}/{len(names)} {name} ({np.size(profile)} steps)")
        test_runs.append(run_profile(env, profile, f"TEST {name}"))
    channels = channel_gaps([channel_pairs(env_id, r, dt) for r in test_runs])
    top = channels[0]["channel"]
    say(f"gap shows most on {top}: {100 * channels[0]['gap']:.2f} % (RMS ratio)")
    chosen_axis, axis_reason = _choose_axis(env_id, axis, channels)
    say(f"which: diagnosing the reference's {chosen_axis} bushing record")
    train_rec = bushing_record(env_id, train_run, chosen_axis, dt, "train", midpoint)
    test_recs = [
        bushing_record(env_id, r, chosen_axis, dt, n, midpoint)
        for r, n in zip(test_runs, names, strict=True)
    ]
    result = diagnose(train_rec, test_recs, baseline=baseline, progress=say, seed=seed,
                      test_names=names)  # fmt: skip
    result.pop("predictions", None)
    rig_gap = channels[0]["gap"]
    effect, shrink = result["effect"], result["shrink"]
    if not rig_gap >= RIG_GAP_FLOOR:
        effect, shrink = "none", 0.0
        say(
            f"the rig shows no gap (largest {100 * rig_gap:.3g} % < {100 * RIG_GAP_FLOOR:g} %): "
            f"none (the reference's record alone says {result['effect']})"
        )
    return {
        "env_id": env_id,
        "channel": top,
        "force_channel": _force_channel(channels),
        "channels": channels,
        "axis": chosen_axis,
        "axis_reason": axis_reason,
        "rig_gap": rig_gap,
        "effect": effect,
        "bushing_effect": result["effect"],
        **{k: result[k] for k in ("top_two", "ranking", "gap_before", "gap_after")},
        "shrink": shrink,
        "model": model_info,
        "bushing_diagnosis": result,
    }


def _force_channel(channels: list[dict[str, Any]]) -> str:
    """The bushing-force channel with the largest gap (channels come ranked by gap)."""
    for c in channels:
        if c["channel"].endswith("force_n") and c["channel"] != "tyre_force_n":
            return c["channel"]
    return "force"


def _check_rig_args(env_id: str, axis: str, test_profiles, test_names) -> list[str]:
    """The TEST names; RigDiagnoseError for an unknown rig or axis, no TEST, clashing names."""
    if env_id not in RIG_IDS:
        raise RigDiagnoseError(f"unknown rig {env_id!r}; known: {list(RIG_IDS)}")
    if env_id == "BushRig-v0" and axis not in QC_AXES:
        raise RigDiagnoseError(f"axis must be one of {list(QC_AXES)}, got {axis!r}")
    if not test_profiles:
        raise RigDiagnoseError("no TEST profile given; the gap is judged on held-out profiles")
    names = list(test_names) if test_names is not None else []
    names += [f"test{i + 1}" for i in range(len(names), len(test_profiles))]
    if len(set(names)) != len(names) or "train" in names:
        raise RigDiagnoseError(f"TEST names must be distinct and not 'train', got {names}")
    return names


def _resolve_model(env_id, model, reference, axis, train_profile, extra, say):
    """(model for the env, what the report says of it); ``"identify"`` fits a linear model on
    the reference's TRAIN replay (per axis on the car)."""
    if not (isinstance(model, str) and model == IDENTIFY):
        return model, {"given": str(getattr(model, "name", model))}
    say(f"{env_id}: replaying TRAIN with the reference to identify the linear model")
    probe = _make(env_id, "linear", reference, axis, extra)
    dt = float(probe.params.dt)
    run = run_profile(probe, train_profile, "TRAIN")
    axes = (axis,) if env_id == "BushRig-v0" else QC_AXES
    fitted = {a: _identify_from_run(env_id, run, a, dt) for a in axes}
    info = {
        "identified": {
            a: {"k_n_per_m": m.k_n_per_m, "c_ns_per_m": m.c_ns_per_m} for a, m in fitted.items()
        }
    }
    return (fitted[axis] if env_id == "BushRig-v0" else fitted), info


def channel_gaps(per_test: list[dict]) -> list[dict[str, Any]]:
    """Held-out gap per channel over all TESTs together, ranked largest first, with shares."""
    channels = []
    for ch in per_test[0]:
        m = np.concatenate([p[ch][0] for p in per_test])
        r = np.concatenate([p[ch][1] for p in per_test])
        rms_r = float(np.sqrt(np.mean(r**2)))
        rms_d = float(np.sqrt(np.mean((m - r) ** 2)))
        gap = rms_ratio(r, m) if rms_r > 0 else (0.0 if rms_d == 0 else float("inf"))
        channels.append({"channel": ch, "gap": float(gap), "rms_reference": rms_r,
                         "rms_difference": rms_d})  # fmt: skip
    total = float(sum(c["gap"] ** 2 for c in channels if np.isfinite(c["gap"])))
    for c in channels:
        c["share"] = c["gap"] ** 2 / total if total > 0 and np.isfinite(c["gap"]) else 0.0
    channels.sort(key=lambda c: -c["gap"])
    return channels


def _choose_axis(env_id: str, axis: str, channels: list[dict]) -> tuple[str, str]:
    top = channels[0]["channel"]
    if env_id == "BushRig-v0":
        return axis, "the rig's axis"
    if _axis_of(top) is not None:
        return _axis_of(top), f"the top channel {top} is on this axis"
    gap_of = {c["channel"]: c["gap"] for c in channels}
    chosen = max(QC_AXES, key=lambda a: gap_of[f"{a}_force_n"])
    return chosen, f"the top channel {top} is a body channel; this axis' force gap is larger"
