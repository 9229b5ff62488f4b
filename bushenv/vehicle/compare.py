"""Vehicle-level differences: HalfCar-v0 with a bushing model in all four pivots against its twin
with the reference bushing, under one manoeuvre, and the component-level error beside them.

``run_car`` replays a ``Manoeuvre`` and keeps both cars' outputs (``OUTPUTS``) and the model
car's pivot deflections; ``vehicle_differences`` gives, per output, the peak and RMS of the
difference relative to the baseline car's own peak and RMS; ``component_errors`` drives the
model and the reference bushing law open loop with the same deflection history (the model
car's four pivots) and gives their force difference the same way, per coordinate.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from bushenv.errors import BushenvError
from bushenv.models.planar_base import COORDS
from bushenv.rigs.halfcar import HalfCarEnv
from bushenv.rigs.halfcar_params import POSITIONS, REFERENCE, resolve_bushings
from bushenv.vehicle.comfort import weighted_rms
from bushenv.vehicle.manoeuvres import Manoeuvre


class Output(NamedTuple):
    """A vehicle output: info keys (the model car's; the twin's carry ``reference_``), its unit
    and the baseline RMS below which a relative difference is not stated (the output is nil
    there, as the roll on a bump under both wheels)."""

    name: str
    title: str
    unit: str
    keys: tuple[str, ...]
    floor: float


# floors: a reference RMS below which an output is negligible for a car (0.1 mm of track,
# 0.006 deg of roll, 0.05 m/s^2): its relative difference is not stated (a pulse steer's
# track change, 0.03 mm RMS, would otherwise judge a model)
OUTPUTS = (
    Output("wheel_load", "wheel load (dynamic)", "N", ("wheel_load_left_n", "wheel_load_right_n"),
           10.0),
    Output("roll", "body roll", "rad", ("roll_rad",), 1e-4),
    Output("roll_rate", "roll rate", "rad/s", ("roll_rate_rad_per_s",), 1e-3),
    Output("camber", "camber", "rad", ("camber_left_rad", "camber_right_rad"), 1e-4),
    Output("track_change", "track change", "m", ("track_change_m",), 1e-4),
    Output("vertical_accel", "body vertical acceleration", "m/s^2",
           ("body_vertical_accel_m_per_s2",), 0.05),
    Output("lateral_accel", "body lateral acceleration", "m/s^2",
           ("body_lateral_accel_m_per_s2",), 0.05),
)  # fmt: skip
AW_FLOOR_M_PER_S2 = 0.015  # ISO 2631-1 Annex C: half of alert people perceive this a_w
OUTPUT_NAMES = tuple(o.name for o in OUTPUTS)
FORCE_KEYS = tuple(
    tuple(
        (f"force_{k}_{c}_{{role}}_n" if c != "moment" else f"moment_{k}_{{role}}_nm")
        for c in ("axial", "radial", "moment")
    )
    for k in POSITIONS
)
DEFLECTION_KEYS = tuple(
    (f"deflection_{k}_axial_m", f"deflection_{k}_radial_m", f"rotation_{k}_rad") for k in POSITIONS
)
PROGRESS_EVERY = 128  # steps between two progress calls


@dataclass
class CarRun:
    """One manoeuvre driven by a model car beside its reference twin.

    ``model``, ``reference``: output name -> (n, k) arrays over the ``steps`` completed before
    the episode ended (wheel loads less the static load); ``deflection`` (n, 4, 3) the model
    car's pivots (axial m, radial m, rotation rad; pivots in ``POSITIONS`` order); ``force_model``
    and ``force_reference`` (n, 4, 3) the two cars' pivot forces (N, N, N m). ``end``: why the
    episode stopped before the manoeuvre's end, if it did.
    """

    manoeuvre: str
    label: str
    dt_s: float
    steps: int
    model: dict[str, np.ndarray]
    reference: dict[str, np.ndarray]
    deflection: np.ndarray
    force_model: np.ndarray
    force_reference: np.ndarray
    end: dict[str, Any]
    reference_outside_steps: int
    seconds: float

    @property
    def time_s(self) -> np.ndarray:
        return self.dt_s * np.arange(1, self.steps + 1)


def _columns() -> list[str]:
    keys = [k for o in OUTPUTS for k in o.keys]
    keys += ["reference_" + k for k in keys]
    roles = ("model", "reference")
    keys += [f.format(role=r) for pivot in FORCE_KEYS for f in pivot for r in roles]
    keys += [k for pivot in DEFLECTION_KEYS for k in pivot]
    return keys


COLUMNS = _columns()


def run_car(
    manoeuvre: Manoeuvre,
    model: Any,
    reference: Any = REFERENCE,
    label: str = "",
    env_kwargs: dict[str, Any] | None = None,
    tick: Callable[[int], None] | None = None,
) -> CarRun:
    """Replay ``manoeuvre`` in HalfCar-v0 with ``model`` in the four pivots of one car and
    ``reference`` in its twin's; ``env_kwargs`` override the spec's (the run's lateral-load
    step limit, for one); ``tick(steps)`` is called every ``PROGRESS_EVERY`` steps."""
    t0 = time.perf_counter()
    env = HalfCarEnv(model=model, reference=reference, **(env_kwargs or {}))
    static = env.params.tyre_static_n
    env.reset(options=manoeuvre.reset_options())
    rows, outside = [], 0
    end = {"diverged": False, "model_error": "", "reference_left_bounds": False, "reason": ""}
    zero = np.zeros(3, dtype=np.float32)
    for k in range(manoeuvre.samples):
        _, _, terminated, truncated, info = env.step(zero)
        outside += bool(info["reference_outside_range"])
        if terminated or info["physical_limit"]:
            end.update(
                diverged=bool(info["diverged"]), model_error=info["model_error"],
                reference_left_bounds=bool(info["physical_limit"]),
                reason=info["divergence_reason"] or info["model_out_of_bounds"]
                or info["reference_out_of_bounds"], step=k + 1, time_s=(k + 1) * manoeuvre.dt_s,
            )  # fmt: skip
            break
        rows.append([info[c] for c in COLUMNS])
        if tick is not None and (k + 1) % PROGRESS_EVERY == 0:
            tick(k + 1)
        if truncated:
            break
    env.close()
    data = np.array(rows, dtype=np.float64).reshape(len(rows), len(COLUMNS))
    col = {c: i for i, c in enumerate(COLUMNS)}
    n_out = sum(len(o.keys) for o in OUTPUTS)
    model_out, ref_out = {}, {}
    for o in OUTPUTS:
        shift = static if o.name == "wheel_load" else 0.0
        cols = [col[k] for k in o.keys]
        model_out[o.name] = data[:, cols] - shift
        ref_out[o.name] = data[:, [c + n_out for c in cols]] - shift
    forces = {
        role: data[:, [col[f.format(role=role)] for pivot in FORCE_KEYS for f in pivot]].reshape(
            -1, len(POSITIONS), 3
        )
        for role in ("model", "reference")
    }
    q = data[:, [col[k] for pivot in DEFLECTION_KEYS for k in pivot]].reshape(-1, len(POSITIONS), 3)
    return CarRun(manoeuvre.name, label, manoeuvre.dt_s, len(rows), model_out, ref_out, q,
                  forces["model"], forces["reference"], end, outside,
                  time.perf_counter() - t0)  # fmt: skip


def relative(diff: np.ndarray, base: np.ndarray, floor: float) -> dict[str, float | None]:
    """Peak and RMS of ``diff`` over those of ``base`` (both (n, ...)), in %; None where the
    baseline's RMS is below ``floor`` or nothing was compared."""
    if diff.size == 0 or not np.all(np.isfinite(diff)):
        return {"peak_pct": None, "rms_pct": None}
    base_rms = float(np.sqrt(np.mean(base**2)))
    if base_rms < floor:
        return {"peak_pct": None, "rms_pct": None}
    return {
        "peak_pct": 100 * float(np.abs(diff).max()) / float(np.abs(base).max()),
        "rms_pct": 100 * float(np.sqrt(np.mean(diff**2))) / base_rms,
    }


def vehicle_differences(
    outputs: dict[str, np.ndarray], baseline: dict[str, np.ndarray], dt_s: float
) -> dict[str, Any]:
    """Per output: the difference's peak and RMS relative to the baseline car's own (%), the
    baseline's peak and RMS (SI), over the steps both hold; and the ISO 2631-1 Wk-weighted RMS
    a_w of both cars' vertical acceleration with its relative difference."""
    n = min(len(outputs["roll"]), len(baseline["roll"]))
    out: dict[str, Any] = {}
    for o in OUTPUTS:
        a, b = outputs[o.name][:n], baseline[o.name][:n]
        out[o.name] = {
            **relative(a - b, b, o.floor),
            "baseline_peak": float(np.abs(b).max()) if n else None,
            "baseline_rms": float(np.sqrt(np.mean(b**2))) if n else None,
        }
    aw = {"model": None, "baseline": None, "difference_pct": None}
    if n >= 16 and np.all(np.isfinite(outputs["vertical_accel"][:n])):
        a_m = weighted_rms(outputs["vertical_accel"][:n, 0], dt_s, "Wk")
        a_b = weighted_rms(baseline["vertical_accel"][:n, 0], dt_s, "Wk")
        diff = 100 * abs(a_m - a_b) / a_b if a_b >= AW_FLOOR_M_PER_S2 else None
        aw = {"model": float(a_m), "baseline": float(a_b), "difference_pct": diff}
    out["a_w_Wk"] = aw
    return out


def _pivot_forces(models: Any, q: np.ndarray) -> np.ndarray:
    """(n, 4, 3) forces of a car's resolved pivot models driven open loop by ``q``."""
    if isinstance(models, dict):
        return np.stack([models[k].simulate(q[:, i, :]) for i, k in enumerate(POSITIONS)], axis=1)
    return models.simulate(q)


def force_errors(error: np.ndarray, base: np.ndarray) -> dict[str, Any]:
    """Per coordinate (axial, radial, rotation's moment) over the four pivots: the error's peak
    and RMS relative to the base forces' (%)."""
    return {c: relative(error[:, :, i], base[:, :, i], 1e-9) for i, c in enumerate(COORDS)}


def component_errors(run: CarRun, model: Any, reference: Any = REFERENCE) -> dict[str, Any]:
    """The bushing's error as a component: the model's and the reference's laws driven open loop
    (from rest) by the model car's four pivot deflection histories, their force difference per
    coordinate relative to the reference law's force; and, beside it, the in-car difference
    (the model car's pivot forces against the twin's, each on its own motion)."""
    out: dict[str, Any] = {"in_car": force_errors(run.force_model - run.force_reference,
                                                  run.force_reference)}  # fmt: skip
    if run.steps < 2:
        out["open_loop"] = {c: relative(np.zeros(0), np.zeros(0), 1.0) for c in COORDS}
        return out
    m, _ = resolve_bushings(model, run.dt_s, "model")
    r, _ = resolve_bushings(reference, run.dt_s, "reference")
    f_ref = _pivot_forces(r, run.deflection)
    try:
        with np.errstate(all="ignore"):
            f_model = _pivot_forces(m, run.deflection)
    except (BushenvError, ArithmeticError) as exc:
        out["open_loop"] = {c: relative(np.zeros(0), np.zeros(0), 1.0) for c in COORDS}
        out["open_loop_failed"] = f"{type(exc).__name__}: {exc}"
        return out
    out["open_loop"] = force_errors(f_model - f_ref, f_ref)
    if not np.all(np.isfinite(f_model)):
        out["open_loop_failed"] = "the model's open-loop force is not finite (it diverged)"
    return out


def worst(values: dict[str, Any], key: str) -> float | None:
    """The largest ``key`` ("peak_pct" or "rms_pct") among ``values``' entries that state it."""
    found = [v[key] for v in values.values() if isinstance(v, dict) and v.get(key) is not None]
    return max(found) if found else None


def transfer(vehicle: float | None, component: float | None) -> float | None:
    """How much of a component error reaches the car: vehicle % over component %."""
    if vehicle is None or component is None or not component > 0 or math.isnan(vehicle):
        return None
    return vehicle / component


def at_rest(run: CarRun, manoeuvre: Manoeuvre) -> dict[str, Any]:
    """What the model car does before the manoeuvre's first input, standing on a flat road
    (its twin stays at rest there): the RMS of its dynamic wheel loads (N) and roll (rad) and
    the wheel load's dominant frequency (Hz; None when below 1 N RMS or under 0.25 s)."""
    moving = np.flatnonzero(
        np.any(manoeuvre.road_m != 0, axis=1) | (manoeuvre.lateral_accel_m_per_s2 != 0)
    )
    n = min(int(moving[0]) if moving.size else manoeuvre.samples, run.steps)
    load = run.model["wheel_load"][:n]
    out: dict[str, Any] = {"seconds": n * run.dt_s, "wheel_load_rms_n": None,
                           "roll_rms_rad": None, "frequency_hz": None}  # fmt: skip
    if n < 2:
        return out
    rms = float(np.sqrt(np.mean(load**2)))
    out.update(wheel_load_rms_n=rms,
               roll_rms_rad=float(np.sqrt(np.mean(run.model["roll"][:n] ** 2))))  # fmt: skip
    if rms >= 1.0 and n * run.dt_s >= 0.25:
        x = load[:, 0] - load[:, 0].mean()
        spectrum = np.abs(np.fft.rfft(x * np.hanning(n)))
        out["frequency_hz"] = float(np.fft.rfftfreq(n, run.dt_s)[1 + np.argmax(spectrum[1:])])
    return out
