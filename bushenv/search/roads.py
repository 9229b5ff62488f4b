"""Road profiles through the batched quarter car (``bushenv.rigs.quartercar_batch``).

A road search evaluates B road profiles at once: two cars per road, both from
``QuarterCarBatch`` (the QuarterCar-v0 car as arrays), one with the model under test on the
attacked axis, its twin with the reference rubber bushing. The other axis carries the reference
rubber in both cars, so the two cars differ only by the bushing under test. The verdict is
``divergence.judge`` on the attacked axis: the model car's deflection and force against the
twin's force, the twin's own deflection for its work, and the road height defining holds (the
flat road after an obstacle: the car's free response must settle like the twin's).

A road so harsh that the twin (the real car) leaves its bounds (bump stop, wheel lift, the
bushing's rubber thickness) cannot judge the model: the profile is judged only up to that
sample.
"""

from __future__ import annotations

import numpy as np

from bushenv.divergence import judge
from bushenv.models import AXES, get_reference
from bushenv.models.base import BushingModel
from bushenv.scales import MACHINE


def quarter_car_responses(
    model: BushingModel,
    reference: BushingModel,
    road: np.ndarray,
    lengths: np.ndarray,
    dt: float,
    axis: str,
    scales=MACHINE,
):
    """(Verdict, x_model, f_model, f_ref, None) for (T, B) roads; see the module docstring."""
    from bushenv.rigs.quartercar import check_road

    T, B = road.shape
    car = make_cars(model, reference, B, dt, axis, max(T, 1))
    p = car.params
    h = check_road(road, p.max_road, p.max_road_step)
    car.reset()
    keys = (
        f"{axis}_deflection_m",
        f"reference_{axis}_deflection_m",
        f"force_{axis}_model_n",
        f"force_{axis}_reference_n",
    )
    rows = {k: np.empty((T, B)) for k in keys}
    limit_at = np.full(B, T, dtype=np.int64)
    for t in range(T):
        out = car.step(h[t])
        for k in keys:
            rows[k][t] = out[k]
        newly = out["physical_limit"] & (limit_at == T)
        limit_at[newly] = t
    judged = np.maximum(1, np.minimum(lengths, limit_at))
    x, x_ref = rows[keys[0]], rows[keys[1]]
    fm, fr = rows[keys[2]], rows[keys[3]]
    verdict = judge(x, fm, fr, dt, lengths=judged, x_ref=x_ref, hold_input=h, scales=scales)
    return verdict, x, fm, fr, None


def make_cars(model, reference, n: int, dt: float, axis: str, episode_steps: int):
    """``QuarterCarBatch`` of ``n`` cars: ``model`` on ``axis`` (the other axis the rubber),
    each with a twin on the rubber bushing alone."""
    from bushenv.rigs.quartercar_batch import QuarterCarBatch

    if axis not in AXES:
        raise ValueError(f"axis must be one of {AXES}, got {axis!r}")
    other = "axial" if axis == "radial" else "radial"
    other_ref = _reference_for(other, dt)
    return QuarterCarBatch(
        n,
        with_reference=True,
        model={axis: model.copy(), other: other_ref.copy()},
        reference={axis: reference.copy(), other: other_ref.copy()},
        dt_s=dt,
        episode_steps=episode_steps,
    )


def _reference_for(axis: str, dt: float) -> BushingModel:
    return get_reference("rubber", axis=axis, dt=dt)
